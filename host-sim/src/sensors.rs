//! Sensor models: what the logger measures of the truth.
//!
//! Every channel is sampled at the scene's rate, at t_k = k / rate_hz: accelerometers on the table,
//! the base and the top (white Gaussian noise, then a `accel_adc_bits` ADC over ±`accel_range_m_s2`,
//! saturating), and a base-to-table displacement sensor (white noise, ±`disp_range_m`, saturating).
//! The noise is seeded (`[sensors] seed`), so a scene always produces the same log.
//!
//! Imperfections (`[sensors]`): each accelerometer measures (1 + e)·true + bias + noise
//! (`accel_gain_error`, `accel_bias_m_s2`: table, base, top), the displacement sensor true +
//! `disp_bias_m` + noise; with `dropout_probability` a sample's whole frame is missing (flagged
//! [`FLAG_MISSING`], channels NaN), drawn from a second seeded stream so that the other samples'
//! noise is the same as without dropouts.

use crate::scene::Sensors;
use crate::truth::{Truth, TruthSample};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Flag: an accelerometer channel saturated.
pub const FLAG_ACCEL_SATURATED: u8 = 1 << 0;
/// Flag: the displacement channel saturated.
pub const FLAG_DISP_SATURATED: u8 = 1 << 1;
/// Flag: the sample's frame is missing (dropped); its channels are NaN.
pub const FLAG_MISSING: u8 = 1 << 2;

/// One sample of the measured channels (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorFrame {
    /// Sample index k.
    pub k: u64,
    /// Table acceleration (m/s²).
    pub table_accel_m_s2: f32,
    /// Base absolute acceleration (m/s²).
    pub base_accel_m_s2: f32,
    /// Top absolute acceleration (m/s²).
    pub top_accel_m_s2: f32,
    /// Base-to-table displacement (slip, m).
    pub disp_m: f32,
    /// `FLAG_*` bits.
    pub flags: u8,
}

/// The seeded sensor model of a scene.
#[derive(Debug, Clone)]
pub struct SensorModel {
    cfg: Sensors,
    rng: ChaCha8Rng,
    /// The dropouts' own stream.
    dropout_rng: ChaCha8Rng,
    accel_noise: Option<Normal<f64>>,
    disp_noise: Option<Normal<f64>>,
    lsb: f64,
    max_code: f64,
}

impl SensorModel {
    /// The model for a scene's `[sensors]` table.
    pub fn new(cfg: &Sensors) -> Self {
        let max_code = (2f64).powi(cfg.accel_adc_bits as i32 - 1);
        Self {
            cfg: cfg.clone(),
            rng: ChaCha8Rng::seed_from_u64(cfg.seed),
            dropout_rng: {
                let mut r = ChaCha8Rng::seed_from_u64(cfg.seed);
                r.set_stream(1);
                r
            },
            accel_noise: Normal::new(0.0, cfg.accel_noise_rms_m_s2)
                .ok()
                .filter(|_| cfg.accel_noise_rms_m_s2 > 0.0),
            disp_noise: Normal::new(0.0, cfg.disp_noise_rms_m)
                .ok()
                .filter(|_| cfg.disp_noise_rms_m > 0.0),
            lsb: cfg.accel_range_m_s2 / max_code,
            max_code,
        }
    }

    /// Accelerometer `i` (table, base, top) measuring `x`.
    fn accel(&mut self, i: usize, x: f64, flags: &mut u8) -> f32 {
        let (e, b) = (self.cfg.accel_gain_error[i], self.cfg.accel_bias_m_s2[i]);
        // (Applied only when set, so that a perfect sensor gives today's numbers bit for bit.)
        let x = if e != 0.0 { (1.0 + e) * x } else { x };
        let x = if b != 0.0 { x + b } else { x };
        let noisy = x + self.accel_noise.map_or(0.0, |n| n.sample(&mut self.rng));
        let code = (noisy / self.lsb).round();
        let clamped = code.clamp(-self.max_code, self.max_code - 1.0);
        if clamped != code {
            *flags |= FLAG_ACCEL_SATURATED;
        }
        (clamped * self.lsb) as f32
    }

    /// Measure one truth sample (sample index `k`).
    pub fn measure(&mut self, k: u64, s: &TruthSample) -> SensorFrame {
        let mut flags = 0;
        let table = self.accel(0, s.table_accel_m_s2, &mut flags);
        let base = self.accel(1, s.base_accel_m_s2, &mut flags);
        let top = self.accel(2, s.top_accel_m_s2, &mut flags);
        let slip = if self.cfg.disp_bias_m != 0.0 {
            s.slip_m + self.cfg.disp_bias_m
        } else {
            s.slip_m
        };
        let d = slip + self.disp_noise.map_or(0.0, |n| n.sample(&mut self.rng));
        let r = self.cfg.disp_range_m;
        let disp = if d.abs() > r {
            flags |= FLAG_DISP_SATURATED;
            d.clamp(-r, r)
        } else {
            d
        };
        let p = self.cfg.dropout_probability;
        if p > 0.0 && self.dropout_rng.random::<f64>() < p {
            return SensorFrame {
                k,
                table_accel_m_s2: f32::NAN,
                base_accel_m_s2: f32::NAN,
                top_accel_m_s2: f32::NAN,
                disp_m: f32::NAN,
                flags: FLAG_MISSING,
            };
        }
        SensorFrame {
            k,
            table_accel_m_s2: table,
            base_accel_m_s2: base,
            top_accel_m_s2: top,
            disp_m: disp as f32,
            flags,
        }
    }
}

/// Measure a truth at every sample k = 0..samples (t_k = k / rate_hz); also returns the truth samples.
pub fn measure_all(
    cfg: &Sensors,
    truth: &Truth,
    rate_hz: f64,
    samples: u64,
) -> Vec<(TruthSample, SensorFrame)> {
    let mut model = SensorModel::new(cfg);
    let mut cursor = truth.sampler();
    let mut out = Vec::with_capacity(samples as usize);
    for k in 0..samples {
        let t = k as f64 / rate_hz;
        if let Some(s) = cursor.sample(t) {
            let f = model.measure(k, &s);
            out.push((s, f));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table_motion::TableMotion;
    use crate::truth::{simulate, TruthInput};
    use ssvr_core::{Structure, StructureParams};

    fn table1() -> Structure {
        Structure::new(StructureParams {
            m1_kg: 29.5,
            m2_kg: 1.75,
            natural_frequency_hz: 7.0,
            damping_ratio: 0.05,
            friction_coefficient: 0.2,
            gravity_m_s2: 9.80665,
        })
        .unwrap()
    }

    /// The default scene's truth (2 m/s² at 0.143 s: sticking and sliding), `duration_s` long.
    fn sliding_truth(duration_s: f64) -> Truth {
        let table = TableMotion::Harmonic {
            amplitude_m_s2: 2.0,
            period_s: 0.143,
        };
        simulate(&TruthInput::new(&table1(), &table, duration_s)).unwrap()
    }

    #[test]
    fn noise_has_the_configured_rms_and_is_seeded() {
        let s = table1();
        let table = TableMotion::None;
        let truth = simulate(&TruthInput::new(&s, &table, 1.0)).unwrap();
        let cfg = Sensors::default();
        let a = measure_all(&cfg, &truth, 1e4, 10_000);
        let b = measure_all(&cfg, &truth, 1e4, 10_000);
        assert_eq!(a.len(), 10_000);
        assert!(a.iter().zip(&b).all(|(x, y)| x.1 == y.1));
        let rms = |f: &dyn Fn(&SensorFrame) -> f64| {
            (a.iter().map(|(_, s)| f(s).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
        };
        let acc = rms(&|s| s.top_accel_m_s2 as f64);
        let disp = rms(&|s| s.disp_m as f64);
        assert!((acc / 5e-3 - 1.0).abs() < 0.05, "accel rms {acc}");
        assert!((disp / 1e-6 - 1.0).abs() < 0.05, "disp rms {disp}");
        assert!(a.iter().all(|(_, s)| s.flags == 0));
    }

    #[test]
    fn offsets_and_gain_errors_are_applied_exactly() {
        let truth = sliding_truth(1.0);
        let cfg = Sensors {
            accel_noise_rms_m_s2: 0.0,
            disp_noise_rms_m: 0.0,
            accel_bias_m_s2: [0.3, -0.2, 0.1],
            accel_gain_error: [0.02, 0.01, -0.01],
            disp_bias_m: 1e-3,
            ..Sensors::default()
        };
        let frames = measure_all(&cfg, &truth, 1e4, 10_000);
        assert_eq!(frames.len(), 10_000);
        // The 24-bit ADC's step over ±39.2266 m/s² (4.7e-6 m/s²): at most half of it, then f32.
        let lsb = cfg.accel_range_m_s2 / 2f64.powi(cfg.accel_adc_bits as i32 - 1);
        let mut worst = 0f64;
        for (t, f) in &frames {
            let truths = [t.table_accel_m_s2, t.base_accel_m_s2, t.top_accel_m_s2];
            let measured = [f.table_accel_m_s2, f.base_accel_m_s2, f.top_accel_m_s2];
            for i in 0..3 {
                let want = (1.0 + cfg.accel_gain_error[i]) * truths[i] + cfg.accel_bias_m_s2[i];
                let err = (measured[i] as f64 - want).abs();
                let tol = 0.5 * lsb + want.abs() * f32::EPSILON as f64;
                assert!(err <= tol, "k = {} channel {i}: {err} > {tol}", f.k);
                worst = worst.max(err);
            }
            let want = t.slip_m + cfg.disp_bias_m;
            assert!(
                (f.disp_m as f64 - want).abs() <= want.abs() * f32::EPSILON as f64,
                "k = {}: displacement {} != {want}",
                f.k,
                f.disp_m
            );
            assert_eq!(f.flags, 0);
        }
        assert!(worst > 0.0 && worst <= 0.5 * lsb + 1e-6, "worst {worst}");
        // The defaults are a perfect sensor: with them the same truth measures the truth.
        let perfect = Sensors {
            accel_noise_rms_m_s2: 0.0,
            disp_noise_rms_m: 0.0,
            ..Sensors::default()
        };
        for ((t, f), (_, g)) in measure_all(&perfect, &truth, 1e4, 10_000)
            .iter()
            .zip(&frames)
        {
            assert!((f.top_accel_m_s2 as f64 - t.top_accel_m_s2).abs() <= 0.5 * lsb + 1e-6);
            assert_eq!(f.disp_m, t.slip_m as f32);
            assert_ne!(f.top_accel_m_s2, g.top_accel_m_s2);
        }
    }

    #[test]
    fn dropouts_have_the_configured_rate_and_leave_the_other_samples_unchanged() {
        let truth = sliding_truth(10.0);
        let n = 100_000;
        let p = 0.01;
        let clean = measure_all(&Sensors::default(), &truth, 1e4, n);
        let cfg = Sensors {
            dropout_probability: p,
            ..Sensors::default()
        };
        let dropped = measure_all(&cfg, &truth, 1e4, n);
        assert_eq!((clean.len(), dropped.len()), (n as usize, n as usize));
        let mut missing = 0u64;
        for ((_, c), (_, d)) in clean.iter().zip(&dropped) {
            assert_eq!(c.k, d.k);
            if d.flags & FLAG_MISSING != 0 {
                missing += 1;
                assert_eq!(d.flags, FLAG_MISSING);
                assert!(d.table_accel_m_s2.is_nan() && d.base_accel_m_s2.is_nan());
                assert!(d.top_accel_m_s2.is_nan() && d.disp_m.is_nan());
            } else {
                // Bit for bit (NaN-free frames: `==` is bitwise here).
                assert_eq!(c, d, "k = {}", c.k);
            }
        }
        // Binomial: mean n·p = 1000, σ = sqrt(n·p·(1 − p)) ≈ 31.5; within 5 σ.
        let (mean, sigma) = (n as f64 * p, (n as f64 * p * (1.0 - p)).sqrt());
        assert!(
            (missing as f64 - mean).abs() <= 5.0 * sigma,
            "{missing} missing of {n}, expected {mean} ± {sigma}"
        );
        // Seeded: the same dropouts again; another seed drops other samples.
        assert_eq!(
            measure_all(&cfg, &truth, 1e4, n)
                .iter()
                .map(|(_, f)| f.flags)
                .collect::<Vec<_>>(),
            dropped.iter().map(|(_, f)| f.flags).collect::<Vec<_>>()
        );
        let other = Sensors { seed: 2, ..cfg };
        let other = measure_all(&other, &truth, 1e4, n);
        assert!(other
            .iter()
            .zip(&dropped)
            .any(|((_, a), (_, b))| a.flags != b.flags));
    }
}
