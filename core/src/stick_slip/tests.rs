//! Unit tests of the stick-slip estimator.

use super::maps::mat;
use super::packed;
use super::phase::Level;
use super::*;
use crate::error::Param;
use crate::math::{F32Poly, Libm};
use crate::structure::{Structure, StructureParams};

fn structure(mu: f64, xi: f64) -> Structure {
    Structure::new(StructureParams {
        m1_kg: 29.5,
        m2_kg: 1.75,
        natural_frequency_hz: 7.0,
        damping_ratio: xi,
        friction_coefficient: mu,
        gravity_m_s2: 9.80665,
    })
    .unwrap()
}

/// Table acceleration and measured top acceleration of sample k.
fn inputs(k: u64) -> (f32, f32) {
    let t = k as f32 * 1e-4;
    (2.0 * (43.9 * t).sin(), 1.5 * (40.0 * t).cos())
}

/// (sample, phase, age) events: slip, stick, slip back, old stick, slip.
const EVENTS: [(u64, i8, f32); 6] = [
    (40, 1, 0.25),
    (300, 0, 100.5),
    (330, -1, 3.75),
    (700, 0, 60.0),
    (705, 1, 0.0),
    (720, 1, 2.5),
];

fn drive<const H: usize>(
    est: &mut StickSlipEstimator<f32, F32Poly, H>,
    n: u64,
) -> std::vec::Vec<u32> {
    (0..n)
        .map(|k| {
            for &(_, p, a) in EVENTS.iter().filter(|e| e.0 == k) {
                est.push_event(p, a).unwrap();
            }
            let (u, y) = inputs(k);
            est.update(u, y).to_bits()
        })
        .collect()
}

/// [`drive`] skipping the events older than the history.
fn drive_lenient<const H: usize>(
    est: &mut StickSlipEstimator<f32, F32Poly, H>,
    n: u64,
) -> std::vec::Vec<u32> {
    (0..n)
        .map(|k| {
            for &(_, p, a) in EVENTS.iter().filter(|e| e.0 == k) {
                let _ = est.push_event(p, a);
            }
            let (u, y) = inputs(k);
            est.update(u, y).to_bits()
        })
        .collect()
}

#[test]
fn coefficients_round_trip_through_their_bits() {
    for xi in [0.05, 0.0, 0.99, 0.5] {
        let s = structure(0.2, xi);
        let c = StickSlipCoefficients::<f32>::new(&s, 1e4).unwrap();
        let back = StickSlipCoefficients::<f32>::from_bits(&c.to_bits()).unwrap();
        assert_eq!(back.to_bits(), c.to_bits());
        let mut bad = c.to_bits();
        bad[31] = 3;
        assert!(StickSlipCoefficients::<f32>::from_bits(&bad).is_none());
    }
    let s = structure(0.2, 0.05);
    let cfg = StickSlipConfig::DEFAULT;
    let mut a = StickSlipEstimator::<f32, F32Poly, 200>::new(&s, 1e4, cfg).unwrap();
    let c = StickSlipCoefficients::<f32>::from_bits(&a.coefficients().to_bits()).unwrap();
    let mut b = StickSlipEstimator::<f32, F32Poly, 200>::from_coefficients(c, cfg, 200).unwrap();
    assert_eq!(drive(&mut a, 3000), drive(&mut b, 3000));
}

#[test]
fn the_history_length_not_the_storage_decides() {
    let s = structure(0.2, 0.05);
    let cfg = StickSlipConfig {
        use_identified_mu: true,
        min_blocks: 100,
        ..StickSlipConfig::DEFAULT
    };
    let mut a = StickSlipEstimator::<f32, F32Poly, 144>::new(&s, 1e4, cfg).unwrap();
    let mut b = StickSlipEstimator::<f32, F32Poly, 512>::with_history(&s, 1e4, cfg, 144).unwrap();
    assert_eq!(b.history(), 144);
    assert_eq!(drive(&mut a, 5000), drive(&mut b, 5000));
    let (ma, mb) = (a.mu_estimate().unwrap(), b.mu_estimate().unwrap());
    assert_eq!((ma.mu, ma.std, ma.blocks), (mb.mu, mb.std, mb.blocks));
    for d in 0..150 {
        assert_eq!(
            a.prediction_at(4999 - d).map(f32::to_bits),
            b.prediction_at(4999 - d).map(f32::to_bits)
        );
    }
    assert!(a.prediction_at(5000 - 145).is_none() && a.prediction_at(5000).is_none());
    // Storages with a copy slot, and a multiple of the block plus one (the wrap aligned with
    // the blocks): the same results.
    assert_eq!(storage_for(144, 16), 145);
    let mut c = StickSlipEstimator::<f32, F32Poly, 145>::new(&s, 1e4, cfg).unwrap();
    let mut d = StickSlipEstimator::<f32, F32Poly, 145>::with_history(&s, 1e4, cfg, 144).unwrap();
    let mut e = StickSlipEstimator::<f32, F32Poly, 146>::with_history(&s, 1e4, cfg, 144).unwrap();
    let mut b = StickSlipEstimator::<f32, F32Poly, 512>::with_history(&s, 1e4, cfg, 144).unwrap();
    let want = drive(&mut b, 5000);
    assert_eq!(drive(&mut c, 5000), want);
    assert_eq!(drive(&mut d, 5000), want);
    assert_eq!(drive(&mut e, 5000), want);
    for short in [2, 3, 17, 39, 40, 48] {
        let mut a =
            StickSlipEstimator::<f32, F32Poly, 512>::with_history(&s, 1e4, cfg, short).unwrap();
        let mut b =
            StickSlipEstimator::<f32, F32Poly, 49>::with_history(&s, 1e4, cfg, short).unwrap();
        let mut c =
            StickSlipEstimator::<f32, F32Poly, 48>::with_history(&s, 1e4, cfg, short).unwrap();
        let want = drive_lenient(&mut a, 3000);
        assert_eq!(drive_lenient(&mut b, 3000), want, "{short}");
        assert_eq!(drive_lenient(&mut c, 3000), want, "{short}");
        assert_eq!(a.mu_estimate(), b.mu_estimate(), "{short}");
        assert_eq!(a.mu_estimate(), c.mu_estimate(), "{short}");
        for d in 0..60 {
            let (pa, pb) = (a.prediction_at(2999 - d), b.prediction_at(2999 - d));
            assert_eq!(pa.map(f32::to_bits), pb.map(f32::to_bits), "{short}");
        }
    }
    assert!(StickSlipEstimator::<f32, F32Poly, 64>::with_history(&s, 1e4, cfg, 65).is_err());
    assert!(StickSlipEstimator::<f32, F32Poly, 64>::with_history(&s, 1e4, cfg, 1).is_err());
}

#[test]
fn events_within_the_history_are_accepted() {
    let s = structure(0.2, 0.05);
    let mut e =
        StickSlipEstimator::<f64, Libm, 64>::new(&s, 1e4, StickSlipConfig::DEFAULT).unwrap();
    for k in 0..10 {
        e.update(0.1, f64::NAN);
        // Back to sample 0, not before it (the next sample is k + 1).
        assert!(e.push_event(1, k as f64 + 1.5).is_err());
        assert!(e.push_event(1, k as f64 + 1.0).is_ok());
        assert!(e.push_event(1, k as f64 + 0.5).is_ok());
    }
    for _ in 0..100 {
        e.update(0.1, f64::NAN);
    }
    // history 64: an age < 63 samples, or exactly 63 (on a sample), is accepted.
    for age in [0.0, 0.5, 1.0, 61.5, 62.0, 62.75, 63.0] {
        assert!(e.push_event(0, age).is_ok(), "{age}");
    }
    for age in [63.5, 64.0, 1e9, f64::INFINITY, f64::NAN, -1.0] {
        assert!(e.push_event(0, age).is_err(), "{age}");
    }
    assert!(e.push_event(2, 1.0).is_err());
}

#[test]
fn identifies_mu_from_a_sliding_response() {
    // The measured top acceleration: the model itself with μ = 0.2, sliding back and forth;
    // the estimator starts from μ = 0.25.
    let (truth_s, model_s) = (structure(0.2, 0.05), structure(0.25, 0.05));
    let cfg = StickSlipConfig {
        identify_mu: false,
        ..StickSlipConfig::DEFAULT
    };
    let mut truth = StickSlipEstimator::<f64, Libm, 64>::new(&truth_s, 1e4, cfg).unwrap();
    let mut est =
        StickSlipEstimator::<f64, Libm, 64>::new(&model_s, 1e4, StickSlipConfig::DEFAULT).unwrap();
    for k in 0..40_000u64 {
        if k % 700 == 0 {
            let p = if (k / 700) % 2 == 0 { 1 } else { -1 };
            truth.push_event(p, 0.0).unwrap();
            est.push_event(p, 0.0).unwrap();
        }
        let t = k as f64 * 1e-4;
        let u = 2.0 * (43.9 * t).sin();
        let y = truth.update(u, f64::NAN);
        est.update(u, y);
    }
    let m = est.mu_estimate().unwrap();
    assert!((m.mu - 0.2).abs() < 1e-6, "{m:?}");
    assert!(m.std >= 0.0 && m.std < 1e-3, "{m:?}");
    assert_eq!(est.mu_used(), 0.25);
    assert!(!est.mu_adopted(), "identified, not used");
}

/// A plain per-sample reference of the identification (phases kept for every interval, z_h
/// and z_u advanced sample by sample), fed the same events and reading the estimator's
/// stored states at the episode starts.
struct Reference {
    /// Interval j's phases and switch fractions (j < k).
    iv: std::vec::Vec<(u8, [f64; MAX_SWITCHES])>,
    phase: Level,
    zh: [f64; 2],
    zu: [f64; 2],
    /// The state at the end of the block before.
    z_start: [f64; 2],
    episode: bool,
    rls: (f64, f64, f64, f64, u32),
}

impl Reference {
    fn push(&mut self, phase: Level, age: f64) {
        let k = self.iv.len();
        if k == 0 || age == 0.0 {
            self.phase = phase;
            return;
        }
        let whole = age.floor();
        let frac = age - whole;
        let (back, f) = if frac == 0.0 {
            (whole as usize, 0.0)
        } else {
            (whole as usize + 1, 1.0 - frac)
        };
        let i = k - back;
        if f == 0.0 {
            self.iv[i].0 = packed::new(phase);
        } else {
            let (b, fr) = &mut self.iv[i];
            packed::add(b, fr, f, phase);
        }
        for j in i + 1..k {
            self.iv[j].0 = packed::new(phase);
        }
        self.phase = phase;
    }

    /// After sample k was stored (y its measured top acceleration, the estimator `e`).
    fn stored<const H: usize>(&mut self, e: &StickSlipEstimator<f64, Libm, H>, ys: &[f64]) {
        self.iv.push((packed::new(self.phase), [0.0; MAX_SWITCHES]));
        let k = self.iv.len() as u64 - 1;
        let (n, len) = (e.cfg.identify_every as u64, e.len as u64);
        if k + 2 < len + n || !(k + 2 - len).is_multiple_of(n) {
            return;
        }
        let d = k + 2 - len;
        let c = &e.c;
        let block = &self.iv[(d - n) as usize..d as usize];
        let sliding = block
            .iter()
            .all(|(b, _)| packed::switches(*b) == 0 && packed::start(*b) != 0);
        let end = packed::end(block[block.len() - 1].0);
        if sliding && !self.episode {
            // An episode starts at the block's start.
            self.zh = self.z_start;
            self.zu = [0.0; 2];
            self.episode = true;
        }
        let z_end = e.slots[e.slot_of(d)].z;
        if self.episode && sliding {
            for (b, _) in block {
                let g = if packed::start(*b) > 0 { c.g } else { -c.g };
                let (wh, wu) = (mat(&c.phi_s, self.zh), mat(&c.phi_s, self.zu));
                self.zh = [self.zh[0] + wh[0], self.zh[1] + wh[1]];
                self.zu = [
                    self.zu[0] + (wu[0] + g * c.force_s[0]),
                    self.zu[1] + (wu[1] + g * c.force_s[1]),
                ];
            }
            let y = ys[d as usize];
            if y.is_finite() {
                let (zh, zu) = (self.zh, self.zu);
                let phi = zu[0];
                let target = y - zh[0];
                let lambda = e.cfg.forgetting.powi(n as i32);
                let alpha = 1.0 - (1.0 - 1e-3f64).powi(n as i32);
                let (mu, a, b, e2, cnt) = &mut self.rls;
                let err = target - *mu * phi;
                *a = lambda * *a + phi * phi;
                *b = lambda * *b + phi * target;
                *mu = *b / *a;
                *e2 += (err * err - *e2) * alpha;
                *cnt += 1;
            }
        } else if end != 0 {
            self.zh = z_end;
            self.zu = [0.0; 2];
            self.episode = true;
        } else {
            self.episode = false;
        }
        self.z_start = z_end;
    }
}

/// The estimator's identification against [`Reference`] over random events (storage `H`).
fn check_identification<const H: usize>(
    history: usize,
    every: u32,
    rate: f64,
    rnd: &mut impl FnMut() -> f64,
) {
    let (truth_s, model_s) = (structure(0.2, 0.05), structure(0.25, 0.05));
    let off = StickSlipConfig {
        identify_mu: false,
        ..StickSlipConfig::DEFAULT
    };
    let cfg = StickSlipConfig {
        identify_every: every,
        use_identified_mu: true,
        min_blocks: 20,
        ..StickSlipConfig::DEFAULT
    };
    let mut truth =
        StickSlipEstimator::<f64, Libm, H>::with_history(&truth_s, 1e4, off, history).unwrap();
    let mut est =
        StickSlipEstimator::<f64, Libm, H>::with_history(&model_s, 1e4, cfg, history).unwrap();
    let mut r = Reference {
        iv: std::vec::Vec::new(),
        phase: 0,
        zh: [0.0; 2],
        zu: [0.0; 2],
        z_start: [0.0; 2],
        episode: false,
        rls: (0.25, 1.0, 0.25, 1e-4, 0),
    };
    let mut ys = std::vec::Vec::new();
    for k in 0..30_000u64 {
        while rnd() < rate {
            // Mostly sliding, reversals in and between samples, some sticks.
            let phase = [1, -1, 1, -1, 0][(rnd() * 5.0) as usize];
            let age = match (rnd() * 4.0) as u32 {
                0 => 0.0,
                1 => (rnd() * (history as f64 - 1.0)).floor(),
                _ => rnd() * (history as f64 - 2.0),
            };
            // (Older than the samples so far: rejected by both.)
            if est.push_event(phase, age).is_ok() {
                truth.push_event(phase, age).unwrap();
                r.push(phase, age);
            }
        }
        let u = 2.0 * (43.9 * k as f64 * 1e-4).sin();
        let y = truth.update(u, f64::NAN);
        ys.push(if k % 101 == 0 { f64::NAN } else { y });
        est.update(u, ys[k as usize]);
        r.stored(&est, &ys);
    }
    let m = est.mu_estimate().unwrap();
    let (mu, a, _, e2, n) = r.rls;
    let at = (H, history, every);
    assert_eq!(m.blocks, n, "{at:?}");
    assert!(n > 100, "{at:?}: {n}");
    assert!((m.mu - mu).abs() < 1e-9 * mu.abs(), "{at:?}: {m:?} {mu}");
    let std = (e2 / a).sqrt();
    assert!((m.std - std).abs() < 1e-6 * std, "{at:?}: {m:?} {std}");
}

#[test]
fn identification_matches_a_per_sample_reference() {
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for (history, every, rate) in [
        (64, 16, 0.01),
        (144, 16, 0.003),
        (2, 4, 0.05),
        (17, 32, 0.01),
        (40, 1, 0.02),
        (30, 7, 0.2),
    ] {
        check_identification::<200>(history, every, rate, &mut rnd);
        if history <= 64 {
            // A copy slot, the wrap aligned with the blocks where n divides 64.
            check_identification::<65>(history, every, rate, &mut rnd);
        }
        if history == 64 {
            // No copy slot.
            check_identification::<64>(history, every, rate, &mut rnd);
        }
    }
}

/// The stuck-phase observer: an error injected into the state (10 ms of a wrong table
/// acceleration) decays like critically damped dynamics at b·p, (1 + b·p·t)·e^(−b·p·t),
/// whatever the damping, at fine and at coarse sampling; the measured top acceleration is an
/// open-loop estimator's prediction (exact for the same model).
#[test]
fn the_observer_error_decays_at_its_bandwidth() {
    for (xi, rate, b) in [
        (0.0, 1e4, 2.0),
        (0.05, 1e4, 2.0),
        (0.9, 1e4, 2.0),
        (0.3, 1e3, 10.0),
        (0.0, 200.0, 10.0),
    ] {
        let s = structure(0.2, xi);
        let open = StickSlipConfig {
            identify_mu: false,
            observer_bandwidth: 0.0,
            sliding_observer: false,
            ..StickSlipConfig::DEFAULT
        };
        let obs = StickSlipConfig {
            observer_bandwidth: b,
            sliding_observer: true,
            ..open
        };
        let mut reference = StickSlipEstimator::<f64, Libm, 8>::new(&s, rate, open).unwrap();
        let mut est = StickSlipEstimator::<f64, Libm, 8>::new(&s, rate, obs).unwrap();
        let w = b * s.p();
        let dt = 1.0 / rate;
        let inject = (0.01 * rate).ceil() as u64;
        let (mut e0, mut worst) = (0.0f64, 0.0f64);
        for k in 0..(inject + (12.0 / (w * dt)) as u64) {
            let u = (2.0 * core::f64::consts::PI * 3.0 * k as f64 * dt).sin();
            let wrong = if k < inject { u + 1.0 } else { u };
            let y = reference.update(u, f64::NAN);
            let pred = est.update(wrong, y);
            let err = (pred - y).abs();
            assert!(err.is_finite(), "error at sample {k} is not finite: {err}");
            if k == inject {
                e0 = err.max(1e-12);
            }
            if k > inject {
                let t = (k - inject) as f64 * dt;
                let bound = 20.0 * (1.0 + w * t) * libm::exp(-w * t);
                worst = worst.max(err / e0 / bound);
            }
        }
        std::println!("xi {xi} rate {rate} b {b}: worst {:.3} of the bound", worst);
        // Measured: ≤ 0.13 of the bound at 10 kHz, 0.50 at b·p·Δt = 0.44 (1 kHz, b = 10),
        // where the discrete double eigenvalue's transient is larger than the continuous
        // one; with the gain of the continuous design this case diverged.
        assert!(worst < 1.0, "xi {xi} rate {rate} b {b}: {worst}");
    }
}

/// The sliding-phase observer: a state error made before a slip start (10 ms of a wrong table
/// acceleration while stuck) decays while sliding like critically damped dynamics at the
/// sliding observer's bandwidth w = 2·b·p·√M (wide: μ̂ not adopted), (1 + w·t)·e^(−w·t) (the
/// reference is the open-loop estimator, exact for the same model); a fast or overdamped
/// sliding oscillator gets no sliding observer. Capped (`cap_sliding_observer`), the wide
/// bandwidth beyond 0.1 rad per sample is allowed up to 0.5: 0.37 at 2 kHz, and at 1 kHz 0.74
/// is held to 0.5; the error decays at that.
#[test]
fn the_sliding_observer_error_decays_at_its_bandwidth() {
    for (xi, rate, b, cap) in [
        (0.0, 1e4, 2.0, false),
        (0.05, 1e4, 2.0, false),
        (0.1, 2e4, 1.0, false),
        (0.05, 2e3, 2.0, true),
        (0.05, 1e3, 2.0, true),
    ] {
        let s = structure(0.2, xi);
        let open = StickSlipConfig {
            identify_mu: false,
            observer_bandwidth: 0.0,
            sliding_observer: false,
            ..StickSlipConfig::DEFAULT
        };
        let obs = StickSlipConfig {
            observer_bandwidth: b,
            sliding_observer: true,
            cap_sliding_observer: cap,
            ..open
        };
        let dt = 1.0 / rate;
        let w = 2.0 * b * s.p() * libm::sqrt(s.mass_ratio());
        assert_eq!(w * dt > 0.1, cap, "{rate}");
        let w = w.min(super::observer::SLIDE_CAPPED_BANDWIDTH / dt);
        let run = |cfg: StickSlipConfig, reference: Option<&[f64]>| {
            let mut est = StickSlipEstimator::<f64, Libm, 8>::new(&s, rate, cfg).unwrap();
            let inject = (0.01 * rate).ceil() as u64;
            let mut out = std::vec::Vec::new();
            for k in 0..(inject + (12.0 / (w * dt)) as u64) {
                let u = (2.0 * core::f64::consts::PI * 3.0 * k as f64 * dt).sin();
                let wrong = if k < inject { u + 1.0 } else { u };
                if k == inject {
                    est.push_event(1, 0.0).unwrap();
                }
                let y = reference.map_or(f64::NAN, |r| r[k as usize]);
                out.push(est.update(if reference.is_some() { wrong } else { u }, y));
            }
            (out, inject as usize)
        };
        let (truth, inject) = run(open, None);
        let (pred, _) = run(obs, Some(&truth));
        let e0 = (pred[inject] - truth[inject]).abs().max(1e-12);
        let mut worst = 0.0f64;
        for k in inject + 1..pred.len() {
            let err = (pred[k] - truth[k]).abs();
            assert!(err.is_finite(), "error at sample {k} is not finite: {err}");
            let t = (k - inject) as f64 * dt;
            worst = worst.max(err / e0 / ((1.0 + w * t) * libm::exp(-w * t)));
        }
        std::println!("xi {xi} rate {rate} b {b}: worst {worst:.3} of the bound, e0 {e0:.3e}");
        // Measured: 0.89, 0.88, 0.93 and, capped, 0.64 (2 kHz) and 0.47 (1 kHz) of the
        // critically damped curve.
        assert!(worst < 1.1, "xi {xi} rate {rate} b {b}: {worst}");
        assert!(e0 > 1e-3, "an error was injected: {e0}");
    }
    // A nearly massless base (√M ≈ 130): the sliding oscillator is too fast for the sample rate.
    let light = Structure::new(StructureParams {
        m2_kg: 0.001,
        ..*structure(0.2, 0.05).params()
    })
    .unwrap();
    let est =
        StickSlipEstimator::<f32, F32Poly, 8>::new(&light, 1e4, StickSlipConfig::DEFAULT).unwrap();
    assert_eq!(est.slides[0].0, [0.0; 2]);
    let est = StickSlipEstimator::<f32, F32Poly, 8>::new(
        &structure(0.2, 0.05),
        1e4,
        StickSlipConfig::DEFAULT,
    )
    .unwrap();
    assert!(est.slides[0].0[0] != 0.0 && est.slides[1].0[0] != 0.0);
    assert!(est.slides[1].0[0].abs() < est.slides[0].0[0].abs());
    // At 2 kHz: no sliding observer uncapped; capped, the wide one only (the narrow one, the
    // model known, would let the noise in).
    for cap in [false, true] {
        let cfg = StickSlipConfig {
            cap_sliding_observer: cap,
            ..StickSlipConfig::DEFAULT
        };
        let est =
            StickSlipEstimator::<f32, F32Poly, 8>::new(&structure(0.2, 0.05), 2e3, cfg).unwrap();
        assert_eq!(est.slides[0].0[0] != 0.0, cap);
        assert_eq!(est.slides[1].0, [0.0; 2]);
    }
}

#[test]
fn for_rate_takes_any_rate() {
    for r in [f64::NAN, -1.0, 0.0, 1.0, 1e3, 1e4, 1e9, f64::INFINITY] {
        let c = StickSlipConfig::DEFAULT.for_rate(r);
        assert!((1..=MAX_IDENTIFY_EVERY).contains(&c.identify_every), "{r}");
    }
    assert_eq!(StickSlipConfig::DEFAULT.for_rate(1e4).identify_every, 32);
    assert_eq!(StickSlipConfig::DEFAULT.for_rate(1e3).identify_every, 3);
}

/// Events of sample k in a repeating pattern: slip, stick (late), slip back, stick, slip.
fn pattern(k: u64) -> Option<(i8, f32)> {
    match k % 1000 {
        40 => Some((1, 0.25)),
        300 => Some((0, 10.5)),
        330 => Some((-1, 3.75)),
        700 => Some((0, 20.0)),
        705 => Some((1, 0.0)),
        _ => None,
    }
}

/// Inputs of sample k with a non-finite table acceleration now and then, a missing top
/// acceleration now and then, and stretches of a third of the samples without a top (as in
/// predict mode), broken by one finite top and holding an infinite one in stuck phases.
fn gappy_inputs(k: u64) -> (f32, f32) {
    let (u, y) = inputs(k);
    let u = if k % 997 == 500 { f32::NAN } else { u };
    let y = match k % 3000 {
        1690 => f32::INFINITY,
        1310 => y,
        1000..2000 => f32::NAN,
        _ if k % 389 == 7 => f32::NAN,
        _ => y,
    };
    (u, y)
}

fn block_vs_samples<const H: usize>(cfg: StickSlipConfig, history: usize, n: u64) {
    let s = structure(0.2, 0.05);
    let mut a = StickSlipEstimator::<f32, F32Poly, H>::with_history(&s, 1e4, cfg, history).unwrap();
    let mut b = a.clone();
    let want: std::vec::Vec<u32> = (0..n)
        .map(|k| {
            if let Some((p, age)) = pattern(k) {
                a.push_event(p, age).unwrap();
            }
            let (u, y) = gappy_inputs(k);
            a.update(u, y).to_bits()
        })
        .collect();
    // Blocks of 1 to 40 samples, split where an event is pushed.
    let mut got = std::vec::Vec::new();
    let (mut k, mut len) = (0u64, 1u64);
    while k < n {
        if let Some((p, age)) = pattern(k) {
            b.push_event(p, age).unwrap();
        }
        let end = (k + len).min(n);
        let end = (k + 1..end).find(|&j| pattern(j).is_some()).unwrap_or(end);
        let (table, top): (std::vec::Vec<f32>, std::vec::Vec<f32>) =
            (k..end).map(gappy_inputs).unzip();
        let mut out = std::vec![0.0f32; table.len()];
        b.update_block(&table, &top, &mut out).unwrap();
        got.extend(out.iter().map(|x| x.to_bits()));
        k = end;
        len = len * 7 % 41 + 1;
    }
    assert_eq!(got.len(), want.len());
    let first = got.iter().zip(&want).position(|(g, w)| g != w);
    assert_eq!(first, None, "first difference at sample {first:?}");
    assert_eq!(a.mu_estimate(), b.mu_estimate());
    assert!(a.mu_estimate().is_some());
}

#[test]
fn blocks_give_the_per_sample_predictions_bit_for_bit() {
    let cfg = StickSlipConfig {
        use_identified_mu: true,
        min_blocks: 50,
        ..StickSlipConfig::DEFAULT
    };
    // The firmware's layout (storage = a multiple of the block plus one) and a plain one.
    block_vs_samples::<{ storage_for(39, 32) }>(cfg, 39, 30_000);
    block_vs_samples::<144>(cfg, 144, 30_000);
    block_vs_samples::<64>(StickSlipConfig::DEFAULT.for_rate(1e3), 40, 30_000);
}

/// A non-finite table acceleration in the first slot after the ring's wrap, inside a block
/// whose run reached the ring's last slot (found by fuzzing `update_block` against `update`):
/// the redone sample reads its predecessor from the copy slot, not from the last slot the
/// aborted run overwrote.
#[test]
fn a_redone_run_after_the_wrap_reads_the_copy_slot() {
    let s = structure(0.2, 0.05);
    let cfg = StickSlipConfig {
        identify_mu: false,
        ..StickSlipConfig::DEFAULT
    };
    for phase in [0, 1] {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let mut a =
                StickSlipEstimator::<f32, F32Poly, 8>::with_history(&s, 1e4, cfg, 7).unwrap();
            a.push_event(phase, 0.0).unwrap();
            let mut b = a.clone();
            let (mut want, mut got) = (std::vec::Vec::new(), std::vec::Vec::new());
            for k in 0..7 {
                let (u, y) = inputs(k);
                want.push(a.update(u, y).to_bits());
                got.push(b.update(u, y).to_bits());
            }
            let (mut table, top): (std::vec::Vec<f32>, std::vec::Vec<f32>) =
                (7..30).map(inputs).unzip();
            table[0] = bad;
            want.extend(
                table
                    .iter()
                    .zip(&top)
                    .map(|(&u, &y)| a.update(u, y).to_bits()),
            );
            let mut out = std::vec![0.0f32; table.len()];
            b.update_block(&table, &top, &mut out).unwrap();
            got.extend(out.iter().map(|x| x.to_bits()));
            assert_eq!(got, want, "phase {phase}, table {bad}");
            assert!(out.iter().all(|x| x.is_finite()));
        }
    }
}

#[test]
fn blocks_of_unequal_lengths_are_an_error() {
    let s = structure(0.2, 0.05);
    let mut e =
        StickSlipEstimator::<f32, F32Poly, 64>::new(&s, 1e4, StickSlipConfig::DEFAULT).unwrap();
    let mut out = [0.0f32; 3];
    let err = e.update_block(&[1.0; 3], &[1.0; 2], &mut out).unwrap_err();
    assert_eq!(err.param(), Param::BlockLength);
    assert!(e.update_block(&[1.0; 2], &[1.0; 2], &mut out).is_err());
    assert_eq!(e.sample_index(), 0, "nothing processed");
    assert!(e.update_block(&[], &[], &mut []).is_ok());
}

#[test]
fn sliding_phases_are_their_friction_levels() {
    for p in [
        SlidingPhase::Negative,
        SlidingPhase::Stuck,
        SlidingPhase::Positive,
    ] {
        assert_eq!(SlidingPhase::from_level(p.level()), Ok(p));
    }
    assert_eq!(SlidingPhase::Negative.level(), -1);
    assert_eq!(SlidingPhase::Positive.level(), 1);
    assert_eq!(
        SlidingPhase::from_level(2).unwrap_err().param(),
        Param::Phase
    );
    let s = structure(0.2, 0.05);
    let mut e =
        StickSlipEstimator::<f32, F32Poly, 64>::new(&s, 1e4, StickSlipConfig::DEFAULT).unwrap();
    assert_eq!(e.phase(), SlidingPhase::Stuck);
    e.push_event(SlidingPhase::Negative.level(), 0.0).unwrap();
    assert_eq!(e.phase(), SlidingPhase::Negative);
}

/// The breakaway coefficient at an age: |(M − 1)·ü1 + üg| / (M·g) of the top and table
/// accelerations interpolated at that time, computed here by hand from the inputs fed; the
/// slide's coefficient the same with üg + s̈. (Against the exact stick-slip truth:
/// `host-sim/tests/prior_errors.rs`, a static coefficient told wrong.)
#[test]
fn breakaway_coefficient_interpolates_the_held_force() {
    let s = structure(0.2, 0.05);
    let cfg = StickSlipConfig {
        identify_mu: false,
        ..StickSlipConfig::DEFAULT
    };
    let mut est = StickSlipEstimator::<f64, Libm, 40>::with_history(&s, 1e4, cfg, 39).unwrap();
    let u = |k: u64| 0.5 + 0.01 * k as f64;
    let y = |k: u64| 1.0 - 0.02 * k as f64;
    for k in 0..100u64 {
        est.update(u(k), y(k));
    }
    // The next sample is 100; age 2.25 is time 97.75.
    let m = s.mass_ratio();
    let want = |t: f64| {
        let (uu, yy) = (0.5 + 0.01 * t, 1.0 - 0.02 * t);
        ((m - 1.0) * yy + uu).abs() / (m * s.g())
    };
    for age in [1.0, 2.25, 10.5, 30.0] {
        let got = est.breakaway_coefficient(age, true).unwrap();
        assert!((got - want(100.0 - age)).abs() < 1e-12, "{age}: {got}");
    }
    // Younger than the last kept sample: that sample's value.
    let got = est.breakaway_coefficient(0.3, true).unwrap();
    assert!((got - want(99.0)).abs() < 1e-12, "{got}");
    assert!(est.breakaway_coefficient(38.5, true).is_none());
    assert!(est.breakaway_coefficient(-1.0, true).is_none());
    assert!(est.breakaway_coefficient(f64::NAN, true).is_none());
    // The model's own prediction instead of the measurement: finite.
    assert!(est.breakaway_coefficient(2.0, false).unwrap().is_finite());
    // The slide's coefficient: the base's acceleration üg + s̈ for the table's.
    for (age, slip) in [(2.25, 0.0), (2.25, -3.0), (10.5, 0.7)] {
        let got = est.slide_coefficient(age, true, slip).unwrap();
        let t = 100.0 - age;
        let (uu, yy) = (0.5 + 0.01 * t + slip, 1.0 - 0.02 * t);
        let want = ((m - 1.0) * yy + uu).abs() / (m * s.g());
        assert!((got - want).abs() < 1e-12, "{age} {slip}: {got}");
    }
    assert!(est.slide_coefficient(2.0, true, f64::NAN).is_none());
}

/// `shift_top`: the state's top acceleration shifted by d at a sliding sample, its relative
/// velocity kept, evolves as the sliding oscillator's free response from Δx = −d/p², Δẋ = 0
/// (closed form, ω = p·√M, ζ = ξ·√M): the shifted run less the unshifted one, open loop, at
/// every position of rings of 8 and 9 slots (with and without the copy slot, and right after a
/// wrap). A non-finite shift changes nothing; the last sample's stored measurement moves with
/// the state.
#[test]
fn shift_top_is_a_free_response_of_the_sliding_oscillator() {
    fn worst<const H: usize>() -> (f64, usize) {
        let s = structure(0.2, 0.05);
        let cfg = StickSlipConfig {
            identify_mu: false,
            observer_bandwidth: 0.0,
            sliding_observer: false,
            ..StickSlipConfig::DEFAULT
        };
        let rate = 1e4;
        let dt = 1.0 / rate;
        let (p, xi) = (s.p(), 0.05);
        let root_m = libm::sqrt(s.mass_ratio());
        let (w, z) = (p * root_m, xi * root_m);
        let wd = w * libm::sqrt(1.0 - z * z);
        let d = 0.5;
        let x0 = -d / (p * p);
        let free = |t: f64| {
            let e = libm::exp(-z * w * t);
            let x = x0 * e * (libm::cos(wd * t) + z * w / wd * libm::sin(wd * t));
            let v = -x0 * w * w / wd * e * libm::sin(wd * t);
            -(p * p * x + 2.0 * xi * p * v)
        };
        let u = |k: u64| (2.0 * core::f64::consts::PI * 3.0 * k as f64 * dt).sin();
        let mut worst = 0.0f64;
        let mut first = 0;
        for k0 in 60..60 + H as u64 {
            // A history of 8: the ring of 9 slots has the copy slot.
            let mut b = StickSlipEstimator::<f64, Libm, H>::with_history(&s, rate, cfg, 8).unwrap();
            for k in 0..k0 {
                if k == 20 {
                    b.push_event(1, 0.0).unwrap();
                }
                b.update(u(k), f64::NAN);
            }
            first = b.first;
            let mut a = b.clone();
            a.shift_top(f64::NAN);
            assert_eq!(
                a.update(u(k0), f64::NAN).to_bits(),
                b.clone().update(u(k0), f64::NAN).to_bits()
            );
            let mut a = b.clone();
            a.shift_top(d);
            for j in 1..400u64 {
                let k = k0 - 1 + j;
                let diff = a.update(u(k), f64::NAN) - b.update(u(k), f64::NAN);
                let err = (diff - free(j as f64 * dt)).abs();
                assert!(err.is_finite(), "H {H}, k0 {k0}, j {j}");
                worst = worst.max(err);
            }
        }
        (worst, first)
    }
    // The stored measurement of the last sample, which the next interval's correction reads,
    // moves with the state.
    let mut e = StickSlipEstimator::<f64, Libm, 8>::new(&structure(0.2, 0.05), 1e4, {
        StickSlipConfig::DEFAULT
    })
    .unwrap();
    e.push_event(1, 0.0).unwrap();
    for k in 0..13 {
        e.update(0.1 * k as f64, 0.5);
    }
    let at = if e.at < 8 { e.at } else { 7 };
    let before = e.slots[at];
    e.shift_top(0.25);
    assert_eq!(e.slots[at].y, before.y + 0.25);
    assert_eq!(e.slots[at].z[0], before.z[0] + 0.25);
    assert_eq!(e.slots[at].z[1], before.z[1]);
    let (w8, f8) = worst::<8>();
    let (w9, f9) = worst::<9>();
    std::println!("shift_top: worst {w8:.3e} (first slot {f8}), {w9:.3e} (first slot {f9}) m/s²");
    assert_ne!(f8, f9, "one ring with the copy slot, one without");
    // Measured: ~5e-15 m/s² of a 0.5 m/s² shift.
    assert!(w8 < 1e-12 && w9 < 1e-12, "{w8}, {w9}");
}

/// `retune` mid-slide: the friction identification's episode goes on with the new maps (its
/// free and unit-μ parts' pδ' scaled as the state's), and the μ̂ adopted after it stays near
/// the truth. The measured top acceleration is the model with f = 7 Hz and μ = 0.2, sliding
/// back and forth; the estimator starts from f 0.5 % high and μ = 0.25, adopts μ̂, and is
/// retuned to 7 Hz in the middle of slides (a large change: its least squares restart).
#[test]
fn a_retune_mid_slide_keeps_the_friction_episode() {
    let truth_s = structure(0.2, 0.05);
    let p = |f: f64, mu: f64| {
        Structure::new(StructureParams {
            natural_frequency_hz: f,
            ..*structure(mu, 0.05).params()
        })
        .unwrap()
    };
    let cfg = StickSlipConfig {
        use_identified_mu: true,
        ..StickSlipConfig::DEFAULT
    }
    .for_rate(1e4);
    let mut truth = StickSlipEstimator::<f64, Libm, 64>::new(
        &truth_s,
        1e4,
        StickSlipConfig {
            identify_mu: false,
            ..StickSlipConfig::DEFAULT
        },
    )
    .unwrap();
    let mut est = StickSlipEstimator::<f64, Libm, 64>::new(&p(7.035, 0.25), 1e4, cfg).unwrap();
    let target = StickSlipCoefficients::<f64>::new(&p(7.0, 0.25), 1e4).unwrap();
    let mut worst_after = 0.0f64;
    for k in 0..20_000u64 {
        if k % 700 == 0 {
            let s = if (k / 700) % 2 == 0 { 1 } else { -1 };
            truth.push_event(s, 0.0).unwrap();
            est.push_event(s, 0.0).unwrap();
        }
        if k == 1_050 || k == 3_500 + 350 {
            est.retune(target);
        }
        let t = k as f64 * 1e-4;
        let u = 2.0 * (43.9 * t).sin();
        let y = truth.update(u, f64::NAN);
        est.update(u, y);
        // Adopted from the first episode's blocks on, and it stays so through the retunes.
        assert_eq!(est.mu_adopted(), est.mu_used() != 0.25, "k {k}");
        if k > 1_050 {
            let err = (est.mu_used() / 0.2 - 1.0).abs();
            assert!(err.is_finite(), "k {k}");
            worst_after = worst_after.max(err);
        }
    }
    std::println!("μ in use after the retune: worst {worst_after:.2e}");
    // Measured: 8.1e-3 (the first adoptions after a restart of the least squares); ending the
    // episode, as before, 0.35: the next block started one mid-slide.
    assert!(worst_after < 1e-2, "{worst_after}");
    let m = est.mu_estimate().unwrap();
    assert!((m.mu - 0.2).abs() < 1e-5, "{m:?}");
    assert!(est.mu_adopted());
}

/// `hold_wide`: μ̂ adopted, the held estimator keeps the wide sliding observer while the other
/// narrows at the adoption; released, it narrows at the next adoption of μ̂ (the next
/// identification block: measured at sample 5 022, released at 5 000), and stays so. The measured top is the truth model's
/// (μ = 0.2), sliding back and forth; both estimators start from μ = 0.25.
#[test]
fn a_held_sliding_observer_stays_wide_until_released() {
    let cfg = StickSlipConfig {
        use_identified_mu: true,
        ..StickSlipConfig::DEFAULT
    }
    .for_rate(1e4);
    let mut truth = StickSlipEstimator::<f64, Libm, 64>::new(
        &structure(0.2, 0.05),
        1e4,
        StickSlipConfig {
            identify_mu: false,
            ..StickSlipConfig::DEFAULT
        },
    )
    .unwrap();
    let mut free =
        StickSlipEstimator::<f64, Libm, 64>::new(&structure(0.25, 0.05), 1e4, cfg).unwrap();
    let mut held = free.clone();
    held.hold_wide(true);
    let wide = free.slides[0].0;
    assert_ne!(wide, free.slides[1].0, "the two observers differ");
    let (mut released_at, mut narrowed_at) = (None, None);
    for k in 0..12_000u64 {
        if k % 700 == 0 {
            let s = if (k / 700) % 2 == 0 { 1 } else { -1 };
            for e in [&mut truth, &mut free, &mut held] {
                e.push_event(s, 0.0).unwrap();
            }
        }
        let u = 2.0 * (43.9 * k as f64 * 1e-4).sin();
        let y = truth.update(u, f64::NAN);
        free.update(u, y);
        held.update(u, y);
        assert_eq!(held.mu_adopted(), free.mu_adopted(), "k {k}");
        // Narrow once μ̂ is adopted; the held one wide until released.
        let narrow = free.slides[1].0;
        assert_eq!(
            free.slide_gain,
            if free.mu_adopted() { narrow } else { wide }
        );
        if released_at.is_none() {
            assert_eq!(held.slide_gain, wide, "k {k}");
            if free.mu_adopted() && k >= 5_000 {
                held.hold_wide(false);
                released_at = Some(k);
            }
        } else if held.slide_gain == narrow {
            narrowed_at = narrowed_at.or(Some(k));
        } else {
            assert!(narrowed_at.is_none(), "k {k}: wide again");
        }
    }
    assert!(free.mu_adopted());
    assert_eq!(released_at, Some(5_000));
    // Narrow at the first identification block after the release that adopts μ̂ (mid-slide:
    // the slide from 4 900 on), and for good.
    let at = narrowed_at.unwrap();
    std::println!("narrowed at {at}");
    assert!(at > 5_000 && at <= 5_600, "{at}");
}

/// `remove_input_offset`: a stuck model fed its table input with an offset b for its first n
/// samples, then told of it (the offset removed from the state and the last stored input at
/// once, from the input from then on), follows the model that never saw it: its later
/// predictions within 1e-12 m/s² (f64; measured 1.7e-18, and 1.0e-3 with the stored input
/// left); without the correction the free oscillation left is ~0.1·b (measured 0.043 m/s² for
/// b = 0.49 m/s² over 22 samples at 7 Hz). Nothing is done while sliding.
#[test]
fn an_input_offset_is_removed_from_the_state() {
    let (b, n) = (0.49, 22u64);
    let cfg = StickSlipConfig {
        identify_mu: false,
        observer_bandwidth: 0.0,
        ..StickSlipConfig::DEFAULT
    };
    let s = structure(0.2, 0.05);
    let mk = || StickSlipEstimator::<f64, Libm, 64>::new(&s, 1e4, cfg).unwrap();
    let (mut clean, mut fixed, mut left) = (mk(), mk(), mk());
    let u = |k: u64| 2.0 * (43.9 * k as f64 * 1e-4).sin();
    let (mut worst_fixed, mut worst_left) = (0.0f64, 0.0f64);
    for k in 0..20_000u64 {
        let off = if k < n { b } else { 0.0 };
        let y = clean.update(u(k), f64::NAN);
        let yf = fixed.update(u(k) + off, f64::NAN);
        let yl = left.update(u(k) + off, f64::NAN);
        if k + 1 == n {
            fixed.remove_input_offset(b, (n - 1) as u32);
        }
        if k >= n {
            assert!(y.is_finite() && yf.is_finite() && yl.is_finite());
            worst_fixed = worst_fixed.max((yf - y).abs());
            worst_left = worst_left.max((yl - y).abs());
        }
    }
    std::println!("after the start: {worst_fixed:.2e} corrected, {worst_left:.3} not");
    assert!(worst_fixed < 1e-12, "{worst_fixed}");
    assert!(worst_left > 0.040 && worst_left < 0.047, "{worst_left}");
    // Sliding: nothing done.
    let mut sliding = mk();
    sliding.push_event(1, 0.0).unwrap();
    sliding.update(0.0, f64::NAN);
    let before = sliding.update(0.0, f64::NAN);
    sliding.remove_input_offset(b, 21);
    assert_eq!(sliding.update(0.0, f64::NAN), {
        let mut again = mk();
        again.push_event(1, 0.0).unwrap();
        again.update(0.0, f64::NAN);
        again.update(0.0, f64::NAN);
        again.update(0.0, f64::NAN)
    });
    assert!(before.is_finite());
}
