//! The friction identification against its per-sample reference and a sliding response.

use super::*;

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
