//! Bits of a frame's `flags` (one byte in every streamed frame). A bit set, not a state: several
//! can be set at once.

/// A channel is NaN or infinite.
pub const NOT_FINITE: u8 = 1 << 0;
/// A channel is at the ADC full scale (clipped).
pub const SATURATED: u8 = 1 << 1;
/// The sample is missing (not acquired, or dropped upstream); its channels are meaningless.
pub const MISSING: u8 = 1 << 2;
/// Frames were lost before this one because the streaming queue was full.
pub const OVERRUN: u8 = 1 << 3;
/// A friction event was pushed to the estimator at this sample (a slip start or reversal; for
/// the stick-slip model also a stick).
pub const EVENT_PUSHED: u8 = 1 << 4;
/// The estimator rejected the event of this sample (invalid level or age).
pub const EVENT_REJECTED: u8 = 1 << 5;
/// The ADC reported an error (SPI, CRC) for this sample (board image; implies [`MISSING`]).
pub const ADC_ERROR: u8 = 1 << 6;
/// The displacement was unusable (missing, not finite, saturated): a displacement detector
/// repeated its last value.
pub const DISP_INVALID: u8 = 1 << 7;
/// The flags that make a sample's accelerations unusable to the models (their inputs held, the
/// identification's samples left out): saturated or missing.
pub const ACCEL_UNUSABLE: u8 = SATURATED | MISSING;
/// Any of the flags that make a measured channel unusable.
pub const INVALID: u8 = NOT_FINITE | SATURATED | MISSING | ADC_ERROR | DISP_INVALID;
/// The flags an acquisition may set on a [`crate::Sample`] (the pipeline adds the others):
/// `OVERRUN` too, when the acquiring side had to drop samples before this one (the board's
/// sample interrupt).
pub const ACQUISITION: u8 = SATURATED | MISSING | ADC_ERROR | DISP_INVALID | OVERRUN;
