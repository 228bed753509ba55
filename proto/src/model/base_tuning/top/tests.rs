//! Tests of the `top` module.

use super::super::*;

use super::super::test_params as params;

/// A deterministic stand-in for the sensor's noise: uniform in ±√3·`rms` (that RMS).
fn noise(k: u32, rms: f32) -> f32 {
    let h = k.wrapping_mul(2_654_435_761).rotate_left(13) ^ 0x9e37_79b9;
    let u = (h.wrapping_mul(2_246_822_519) >> 8) as f32 / (1u32 << 24) as f32;
    (2.0 * u - 1.0) * 1.732_050_8 * rms
}

/// The start's length is the first 0.1 rad of p (22 samples at 7 Hz and 10 kHz), at least 10
/// samples while they span at most 0.5 rad (from ~880 Hz on at 7 Hz), none below; only fuse
/// mode without a rest has one, and predict mode's with a planned start.
#[test]
fn the_open_starts_lengths() {
    let b = |zeroed, fuse, rate| {
        BaseTuning::new(params(), rate, zeroed, fuse, 37)
            .unwrap()
            .open_start()
    };
    // 0.1 × 10 000 / (2π·7) = 22.7; at 4 kHz 9.1, fewer than MIN_OPEN_START: 10 (0.11 rad),
    // at 1 kHz 10 (0.44 rad), at 850 Hz none (10 samples would span 0.52 rad).
    assert_eq!(b(false, true, 10_000.0), 22);
    assert_eq!(b(false, true, 4_000.0), 10);
    assert_eq!(b(false, true, 1_000.0), 10);
    assert_eq!(b(false, true, 850.0), 0);
    assert_eq!(b(false, true, 200.0), 0);
    assert_eq!(b(true, true, 10_000.0), 0);
    assert_eq!(b(false, false, 10_000.0), 0);
    let planned = |zeroed, rate| {
        BaseTuning::new(params(), rate, zeroed, false, 37)
            .unwrap()
            .with_planned_start(Some(crate::PlannedStart {
                accel_m_s2: 0.0,
                rise_per_sample_m_s2: 0.0,
            }))
            .open_start()
    };
    assert_eq!(planned(false, 10_000.0), 22);
    assert_eq!(planned(false, 1_000.0), 10);
    assert_eq!(planned(false, 850.0), 0);
    assert_eq!(planned(true, 10_000.0), 0);
}

/// Measured − predicted over the start, in runs of any length (a missing sample skipped):
/// an offset of ±0.05 m/s² under 5e-3 m/s² of noise comes out within its standard error
/// (5e-3/√21 = 1.1e-3), taken with that standard deviation; without an offset nothing is
/// taken (3σ), and the momentum balance's later estimates decide. Samples after the start
/// are not read.
#[test]
fn the_start_gives_the_top_offset() {
    for offset in [0.05f32, -0.05, 0.0] {
        let mut b = BaseTuning::new(params(), 10_000.0, false, true, 37).unwrap();
        let n = b.open_start();
        let pred: [f32; 40] = core::array::from_fn(|k| 0.3 * libm::sinf(k as f32 * 0.05));
        let mut measured: [f32; 40] =
            core::array::from_fn(|k| pred[k] + offset + noise(k as u32, 5e-3));
        measured[3] = f32::NAN;
        // Samples after the start: far off, never read.
        measured[n..].iter_mut().for_each(|m| *m = 1e3);
        let mut at = 0;
        for len in [5usize, 16, 19] {
            let to = (at + len).min(40);
            b.note_open_start(&measured[at..to], &pred[at..to]);
            at = to;
        }
        assert_eq!(b.open_start(), 0);
        let (found, sd) = (b.top_offset(), b.top_offset_std_use);
        if offset == 0.0 {
            assert_eq!((found, sd), (0.0, 0.0));
        } else {
            // Measured: 7.4e-4 off, σ 1.02e-3 (from consecutive differences).
            assert!((found - offset).abs() < 1e-3, "{found} for {offset}");
            assert!(sd > 0.9e-3 && sd < 1.2e-3, "σ {sd}");
        }
    }
}

/// Below ~4.4 kHz (here 1 kHz) the start is 10 samples over 0.44 rad of p, and the model's
/// response to a table offset b_t from rest, b_t·u(t) with
/// u = 1 − e^{−ξpt}(cos p_d t − ξ/√(1 − ξ²)·sin p_d t) = 2ξ·pt + (½ − 2ξ²)(pt)² + …, reaches
/// ~0.1·b_t: measured − predicted is b_top − b_t·u. The curved start's least squares on 1
/// and k² + l·k gives b_top within 3σ for b_t up to ±0.1 g (216 starts), σ 0.35–0.6 × the
/// noise (its own estimate, from the fit's residual: a mean's would be 0.32×); without a
/// top offset nothing is taken (measured: 0 of 72 starts; the momentum balance's later estimates
/// decide, as at 10 kHz). On k² alone (undamped) b_top came out −7e-3·b_t off, and the
/// mean alone, as at 10 kHz, is b_t·0.06 off and fails the halves' test.
#[test]
fn a_curved_start_gives_the_top_offset_beside_the_tables() {
    let rate = 1_000.0;
    let (p, xi) = (2.0 * core::f64::consts::PI * 7.0, 0.05);
    let pd = p * libm::sqrt(1.0 - xi * xi);
    let u = |k: usize| {
        let t = k as f64 / rate;
        let e = libm::exp(-xi * p * t);
        (1.0 - e * (libm::cos(pd * t) - xi / libm::sqrt(1.0 - xi * xi) * libm::sin(pd * t))) as f32
    };
    let (mut taken_at_zero, mut starts_at_zero) = (0, 0);
    for seed in 0..12u32 {
        for top in [0.49f32, -0.49, 0.1, 0.0] {
            for table in [0.98f32, -0.98, 0.49, -0.2, 0.0, 0.05] {
                let mut b = BaseTuning::new(params(), rate, false, true, 37).unwrap();
                assert_eq!(b.open_start(), 10);
                let measured: [f32; 10] = core::array::from_fn(|k| {
                    top - table * u(k) + noise(k as u32 + 100 * seed, 5e-3)
                });
                b.note_open_start(&measured, &[0.0; 10]);
                assert_eq!(b.open_start(), 0);
                let (found, sd) = (b.top_offset(), b.top_offset_std_use);
                assert!(found.is_finite() && sd.is_finite());
                if top == 0.0 {
                    starts_at_zero += 1;
                    taken_at_zero += usize::from(found != 0.0);
                    assert!(found.abs() < 0.015, "{found} for none, table {table}");
                } else {
                    assert!(
                        (found - top).abs() < 3.0 * sd as f32,
                        "{found} ± {sd} for {top}, table {table}, seed {seed}"
                    );
                    // Measured: σ 1.8e-3 to 3.1e-3 (the fit's residual, 8 degrees of
                    // freedom), within −2.4σ and 1.4σ.
                    assert!(sd > 1.5e-3 && sd < 3.5e-3, "σ {sd}");
                }
            }
        }
    }
    assert_eq!(starts_at_zero, 72);
    assert!(
        taken_at_zero <= 2,
        "{taken_at_zero} of 72 taken without an offset"
    );
}

/// A start that is not at rest (a steady oscillation of 1 m/s² at 5.6 Hz that the model,
/// starting at rest, does not know: the firmware benchmark's inputs) shows its motion's
/// trend in the residual: no offset is taken from it, whatever its level.
#[test]
fn a_moving_start_gives_no_offset() {
    let mut b = BaseTuning::new(params(), 10_000.0, false, true, 37).unwrap();
    let w = 2.0 * core::f32::consts::PI * 5.6 / 10_000.0;
    let measured: [f32; 22] =
        core::array::from_fn(|k| 0.05 + libm::sinf(w * k as f32 + 0.3) + noise(k as u32, 5e-3));
    b.note_open_start(&measured, &[0.0; 22]);
    assert_eq!(b.open_start(), 0);
    assert_eq!((b.top_offset(), b.top_offset_std_use), (0.0, 0.0));
    // At 1 kHz (the curved start: 10 samples) too.
    let mut b = BaseTuning::new(params(), 1_000.0, false, true, 37).unwrap();
    let w = 2.0 * core::f32::consts::PI * 5.6 / 1_000.0;
    let measured: [f32; 10] =
        core::array::from_fn(|k| 0.05 + libm::sinf(w * k as f32 + 0.3) + noise(k as u32, 5e-3));
    b.note_open_start(&measured, &[0.0; 10]);
    assert_eq!(b.open_start(), 0);
    assert_eq!((b.top_offset(), b.top_offset_std_use), (0.0, 0.0));
}

/// Predict mode's table start (no rest, a planned start): the measured table's line against
/// the plan's, for a table any lag late ([`start_offset`]), in runs of any length (a missing
/// sample skipped). On a ramp from 0 (the default scene's sine: 8.8e-3 m/s² per sample) an
/// offset of ±0.1 m/s² under 5e-3 m/s² of noise comes out within 2σ, σ 0.4–1.6 times the
/// noise (a lag of a sample or two is barely seen in the slope and moves the intercept by
/// the rise), and is taken with that σ, the fits from one direction of sliding then told it
/// is known; none without one (3σ), beyond 0.1 g, or without a plan (no start). On a
/// gentle ramp from 0.06 m/s² (a record's first acceleration) a table that follows at once
/// and one still at rest are 0.06 apart: the midpoint, 3σ ≥ 0.03; 0.5 m/s² is taken, −0.03
/// is not (a table at rest reads +0.03, one that follows at once −0.03).
#[test]
fn the_table_start_gives_the_table_offset() {
    let start_without = |a0: f32, rise: f32, offset: f32, missing: usize| {
        let mut b = BaseTuning::new(params(), 10_000.0, false, false, 37)
            .unwrap()
            .with_planned_start(Some(crate::PlannedStart {
                accel_m_s2: a0,
                rise_per_sample_m_s2: rise,
            }));
        let n = b.open_start();
        assert_eq!(n, 22);
        let mut table: [f32; 40] =
            core::array::from_fn(|k| a0 + rise * k as f32 + offset + noise(k as u32, 5e-3));
        table[missing] = f32::NAN;
        // Samples after the start: never read.
        table[n..].iter_mut().for_each(|m| *m = 1e3);
        let (mut at, mut taken) = (0, None);
        for len in [3usize, 16, 21] {
            let to = (at + len).min(40);
            let t = b.note_table_start(&table[at..to]);
            assert!(t.is_none() || to >= n, "taken before the start's end");
            taken = taken.or(t);
            at = to;
        }
        assert_eq!(b.open_start(), 0);
        (b, taken)
    };
    let start = |a0: f32, rise: f32, offset: f32| start_without(a0, rise, offset, 5);
    for offset in [0.1f32, -0.1, 0.0, 1.2] {
        let (b, taken) = start(0.0, 8.8e-3, offset);
        let (found, sd) = (b.offset(), b.offset_std_use);
        if offset == 0.0 || offset > 1.0 {
            assert_eq!((found, sd, b.offset_known), (0.0, 0.0, false), "{offset}");
            assert_eq!(taken, None);
        } else {
            assert!(sd > 2e-3 && sd < 8e-3, "σ {sd}");
            assert!(
                (found - offset).abs() < 2.0 * sd as f32,
                "{found} for {offset}"
            );
            assert!(b.offset_known && b.id_shift == found);
            // (The model integrated it over the start's 21 intervals.)
            assert_eq!(taken, Some((found, 21)));
        }
    }
    // A missing sample anywhere in the start (the first half's mean is compared with the
    // line at its own mean index: when it was compared at the half's middle, a sample
    // missing at 0, 1 or 10 lost the offset).
    for missing in [0, 1, 10, 11, 21] {
        let (b, _) = start_without(0.0, 8.8e-3, 0.1, missing);
        let (found, sd) = (b.offset(), b.offset_std_use);
        assert!(b.offset_known, "missing {missing}");
        assert!(
            (found - 0.1).abs() < 3.0 * sd as f32,
            "missing {missing}: {found} ± {sd}"
        );
    }
    let (jump, _) = start(0.06, 1e-4, -0.03);
    assert!(
        !jump.offset_known,
        "an offset within the plan's first acceleration taken"
    );
    let (jump, _) = start(0.06, 1e-4, 0.5);
    assert!(jump.offset_known && jump.offset_std_use >= 0.01);
    assert!(
        (jump.offset() - 0.5).abs() < 0.03 + 5e-3,
        "{}",
        jump.offset()
    );
    // No plan, or a rest: no start; fuse mode's start is the top's.
    let none = BaseTuning::new(params(), 10_000.0, false, false, 37).unwrap();
    assert_eq!(none.with_planned_start(None).open_start(), 0);
    let rest = BaseTuning::new(params(), 10_000.0, true, false, 37).unwrap();
    let flat = crate::PlannedStart {
        accel_m_s2: 0.0,
        rise_per_sample_m_s2: 0.0,
    };
    assert_eq!(rest.with_planned_start(Some(flat)).open_start(), 0);
}
