//! The closed forms of the paper and their exact building block, evaluated at any time from the
//! whole friction history (the references the recursion and the estimators are checked against).
//!
//! * [`free_vibration`]: the exact free vibration of the relative motion (the building block of
//!   every method), evaluated robustly in all three damping regimes.
//! * [`fourier`]: the trapezoid (TFM, eq 14-18) and rectangular (RFM, eq 20-22) Fourier methods.
//! * [`duhamel`]: the rectangular Duhamel method (RDM, eq 36) generalised to any train of friction
//!   reversals.
//! * [`truncated`]: eq (36) truncated to the K newest reversals (O(K) per sample; a baseline).

pub mod duhamel;
pub mod fourier;
pub mod free_vibration;
pub mod truncated;
