//! The contact phase of the sliding base: stuck, or sliding with the friction level ±1.

/// Contact phase: 0 stuck, +1 or −1 the friction level F/F0 while sliding (friction opposes slip).
pub type Phase = i8;
