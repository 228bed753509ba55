//! The table accelerometer's offset from the input's start against the plan, allowing for the
//! table's lag ([`start_offset`]): either mode without a rest
//! ([`BaseTuning::note_table_start`](crate::model::BaseTuning::note_table_start)).
//!
//! Over the input's first samples (the open-loop start,
//! [`open_start_samples`](crate::model::open_start_samples), its first [`LAGS`] − 1 at most)
//! the measured table acceleration is its offset b plus the table's motion. The controller
//! knows the plan, not the table: a servo table follows its plan some time τ late
//! (milliseconds), at rest until then. With the planned start's least-squares line a0 + r·k
//! over the same samples, the table's motion is taken as the plan's line τ samples late,
//! nothing before:
//!
//! h_τ(k) = [k ≥ τ]·(a0 + r·(k − τ)).
//!
//! Three statistics of the measured start are kept as sums: its least-squares line's intercept
//! α and slope β, and its first half's mean less the line's value at that half's mean index
//! (f: 0 for any line, whichever samples are missing). For a lag τ they are (b + α_h, β_h, f_h)
//! plus noise, (α_h, β_h, f_h) the same of h_τ. b enters α alone, so each whole lag over the
//! start, and τ beyond it (the table not yet moving: a rest, reading its offset), has a χ² from
//! β and f (their covariance from the noise and the accelerometer's gain error,
//! [`START_GAIN_SD`]) and its own best b, α's miss less its regression on theirs. The offset's
//! uncertainty is that of its profile likelihood: the offsets within 3σ of the best fit over
//! every lag (and the neighbouring lags' b), whose reach from the best lag's b is 3σ. It is far
//! from a normal's: a lag of a sample barely changes the slope but moves the intercept by the
//! rise.
//!
//! * A sine from rest (a0 = 0): the offset is found for any lag, σ up to ~2.4 × the noise for
//!   lags of a sample or less (the old intercept-only start, which took the table to follow
//!   within a sample: 0.41 ×, but a lag of 0.5 ms read as −0.044 m/s²), down to the mean's
//!   beyond the start.
//! * A record that starts with an acceleration (El Centro's 0.0063 g): a table that follows it
//!   at once and one still at rest read the same flat start, a0 apart, and nothing in the start
//!   tells them apart. The consistent lags are then apart: the offset is the midpoint of their
//!   range, half a0 off either way, with 3σ ≥ a0/2: 0.05 g is still found, and no offset is
//!   taken for a lagging table that reads its own rest (the old start took −a0: El Centro, a
//!   1 ms lag, 0.73 % RMS over 32 s without any offset; 0.065 % now).
//!
//! All in f64, once, at the start's end (33 lags; ~3.7 KB of flash on the M4F).

/// Lags tried (samples): every whole lag over a start of at most `LAGS − 1` samples (a step in
/// the plan shows by the whole sample it falls on), and beyond it (a table not yet moving). A
/// longer start keeps the statistics of its first `LAGS − 1` samples
/// ([`BaseTuning`](crate::model::BaseTuning)): a table later than those reads its offset there.
pub const LAGS: usize = 33;

/// The standard deviation of the table accelerometer's gain error in the offset's σ (the
/// goals' ±1 %, taken as 1σ): a gain error is read as a lag of ~0.8 sample per % on the default
/// scene's start.
pub const START_GAIN_SD: f64 = 0.01;

/// Largest χ² (2 degrees of freedom: the slope and the first half's mean against a lagged
/// plan's) of the best lag for a start like the plan's: beyond it the table's start is like
/// no lag of the plan (the noise is itself estimated from the start's ~20 differences).
pub const MAX_START_CHI2: f64 = 25.0;

/// The least-squares line y = a + s·k through samples given by their sums.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineFit {
    /// Intercept a (at k = 0).
    pub intercept: f64,
    /// Slope s (per sample).
    pub slope: f64,
}

impl LineFit {
    /// The line through samples given by their sums `[n, Σk, Σk², Σy, Σk·y]`; `None` when the
    /// sums are degenerate (fewer than two distinct k).
    pub fn new(sums: [f64; 5]) -> Option<Self> {
        let [n, sk, skk, sy, sky] = sums;
        let det = n * skk - sk * sk;
        if det.is_nan() || det <= 0.0 {
            return None;
        }
        Some(Self {
            intercept: (skk * sy - sk * sky) / det,
            slope: (n * sky - sk * sy) / det,
        })
    }
}

/// Σ_{k=0}^{x} k² (0 for x < 0).
fn sum_sq(x: f64) -> f64 {
    if x < 0.0 {
        0.0
    } else {
        x * (x + 1.0) * (2.0 * x + 1.0) / 6.0
    }
}

/// What a table that follows the plan's line `a0 + r·k` `tau` samples late (0 before) shows
/// over the start's k = 0..n: its least-squares line's intercept and slope, and its mean over
/// the first `n1` samples less that line's at their mean index.
fn lagged(n: f64, n1: f64, a0: f64, r: f64, tau: f64) -> Option<Lagged> {
    // Σ over k = m..=last of 1, k, k² (m the first k ≥ τ).
    let sums = |last: f64| {
        let m = libm::ceil(tau).max(0.0);
        let count = (last + 1.0 - m).max(0.0);
        if count > 0.0 {
            (
                count,
                (m + last) * count / 2.0,
                sum_sq(last) - sum_sq(m - 1.0),
            )
        } else {
            (0.0, 0.0, 0.0)
        }
    };
    let (c, s1, s2) = sums(n - 1.0);
    let sh = a0 * c + r * (s1 - tau * c);
    let skh = a0 * s1 + r * (s2 - tau * s1);
    let fit = LineFit::new([n, n * (n - 1.0) / 2.0, sum_sq(n - 1.0), sh, skh])?;
    let (c1, s11, _) = sums(n1 - 1.0);
    let first = (a0 * c1 + r * (s11 - tau * c1)) / n1;
    Some(Lagged {
        intercept: fit.intercept,
        slope: fit.slope,
        first: first - fit.intercept - fit.slope * (n1 - 1.0) / 2.0,
    })
}

/// [`lagged`]'s answer.
#[derive(Debug, Clone, Copy)]
struct Lagged {
    intercept: f64,
    slope: f64,
    first: f64,
}

/// The measured start for [`start_offset`]: the least-squares line through its samples and the
/// mean of its first samples.
#[derive(Debug, Clone, Copy)]
pub struct MeasuredStart {
    /// The line through the start's samples.
    pub line: LineFit,
    /// The mean of its first half's samples (the finite ones).
    pub first_mean: f64,
    /// Their mean index: the line's value there is what the first half's mean is compared with,
    /// so that a missing sample does not move the statistic.
    pub first_mean_k: f64,
    /// The first half's length (samples, missing ones included).
    pub first_n: f64,
    /// The start's length n (samples; the line's k runs 0..n).
    pub n: f64,
    /// The noise of one sample.
    pub noise: f64,
}

/// The table accelerometer's offset and its standard deviation from the `measured` start (of
/// at most `LAGS − 1` samples) against the planned start's line `a0 + r·k`, for a table up to
/// any lag late (module documentation); `None` when no lag makes the plan's start the measured
/// one (the table's start is not the plan's), or for a longer start.
pub fn start_offset(measured: &MeasuredStart, a0: f64, r: f64) -> Option<(f64, f64)> {
    let MeasuredStart {
        line,
        first_mean,
        first_mean_k,
        first_n,
        n,
        noise,
    } = *measured;
    if first_n.is_nan()
        || first_n < 1.0
        || n.is_nan()
        || n <= first_n
        || n > (LAGS - 1) as f64
        || noise.is_nan()
        || noise <= 0.0
    {
        return None;
    }
    // The statistics (intercept, slope, the first half's mean less the line's at its mean
    // index k1) and their covariance per unit noise² (for the whole start: a missing sample
    // changes them little): the intercept's and the slope's weights w_k = (Σk² − k·Σk)/det and
    // v_k = (n·k − Σk)/det summed over the first half give m1's covariances with them.
    let stats = [
        line.intercept,
        line.slope,
        first_mean - line.intercept - line.slope * first_mean_k,
    ];
    let (sk, skk) = (n * (n - 1.0) / 2.0, sum_sq(n - 1.0));
    let det = n * skk - sk * sk;
    let s1 = first_n * (first_n - 1.0) / 2.0;
    let k1 = (first_n - 1.0) / 2.0;
    let (m1_a, m1_s) = (
        (first_n * skk - sk * s1) / det / first_n,
        (n * s1 - sk * first_n) / det / first_n,
    );
    let (var_a, var_s, cov_as) = (skk / det, n / det, -sk / det);
    let cov_fa = m1_a - var_a - k1 * cov_as;
    let cov_fs = m1_s - cov_as - k1 * var_s;
    let var_f =
        1.0 / first_n + var_a + k1 * k1 * var_s - 2.0 * m1_a - 2.0 * k1 * m1_s + 2.0 * k1 * cov_as;
    // For each lag tried, the last beyond the start (nothing moved): the
    // offset that fits the statistics best, its χ² and its σ at that lag. b enters the
    // intercept alone, so χ² is that of the slope and the first half's (d, their misses; M,
    // their covariance, with the gain error's share of the lagged plan's statistics), and b
    // the intercept's miss less its regression on theirs (v: its covariances with them).
    let ge = START_GAIN_SD / noise;
    let mut fits = [(0.0f64, 0.0f64, 0.0f64); LAGS];
    let mut best = f64::INFINITY;
    for (j, fit) in fits.iter_mut().enumerate() {
        let h = lagged(n, first_n, a0, r, (j as f64).min(n))?;
        let g = [ge * h.intercept, ge * h.slope, ge * h.first];
        let (m11, m12, m22) = (
            var_s + g[1] * g[1],
            cov_fs + g[1] * g[2],
            var_f + g[2] * g[2],
        );
        let (v1, v2) = (cov_as + g[0] * g[1], cov_fa + g[0] * g[2]);
        let det_m = m11 * m22 - m12 * m12;
        if det_m.is_nan() || det_m <= 0.0 {
            return None;
        }
        let d = [stats[1] - h.slope, stats[2] - h.first];
        let t = [
            (m22 * d[0] - m12 * d[1]) / det_m,
            (m11 * d[1] - m12 * d[0]) / det_m,
        ];
        let chi2 = (d[0] * t[0] + d[1] * t[1]) / (noise * noise);
        let b = stats[0] - h.intercept - (v1 * t[0] + v2 * t[1]);
        let var_b =
            var_a + g[0] * g[0] - (v1 * (m22 * v1 - m12 * v2) + v2 * (m11 * v2 - m12 * v1)) / det_m;
        *fit = (b, chi2, noise * libm::sqrt(libm::fmax(var_b, 0.0)));
        best = best.min(chi2);
    }
    if best.is_nan() || best > MAX_START_CHI2 {
        return None;
    }
    // The offsets within 3σ of the best fit (its profile likelihood, far from a normal's: a
    // lag of a sample barely changes χ² and moves b by the rise): the union over the lags of
    // b(τ) ± σ_b(τ)·√(χ²_min + 9 − χ²(τ)), and the neighbouring lags' b (the true lag may lie
    // between two tried). The offset is the best lag's, or with lags apart within it (a
    // record's first acceleration: followed at once, or not yet) the union's midpoint; σ a
    // third of the union's reach from it, so that an offset is taken (3σ) only when no lag
    // within 3σ explains it.
    let (mut lo, mut hi, mut at_best) = (f64::INFINITY, f64::NEG_INFINITY, f64::NAN);
    let (mut first, mut last, mut count) = (usize::MAX, 0usize, 0usize);
    for (j, &(b, chi2, sd)) in fits.iter().enumerate() {
        let room = best + 9.0 - chi2;
        if room >= 0.0 {
            let half = sd * libm::sqrt(room);
            (lo, hi) = (lo.min(b - half), hi.max(b + half));
            for k in [j.wrapping_sub(1), j + 1] {
                if let Some(&(bk, _, _)) = fits.get(k) {
                    (lo, hi) = (lo.min(bk), hi.max(bk));
                }
            }
            (first, last, count) = (first.min(j), j, count + 1);
        }
        if chi2 == best {
            at_best = b;
        }
    }
    let b = if last + 1 - first == count {
        at_best
    } else {
        (lo + hi) / 2.0
    };
    let sd = libm::fmax(hi - b, b - lo) / 3.0;
    (b.is_finite() && sd.is_finite() && sd > 0.0).then_some((b, sd))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planned_start::planned_start;
    use ssvr_core::StructureParams;

    /// A deterministic normal sample per call (Box–Muller on SplitMix64).
    struct Noise(u64);
    impl Noise {
        fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^= z >> 31;
            ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn normal(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            libm::sqrt(-2.0 * libm::log(u)) * libm::cos(2.0 * core::f64::consts::PI * v)
        }
    }

    /// The measured start of a table `lag` samples late on the plan `accel(t)` (at rest
    /// before), read with offset `b` and gain `1 + e`, noise `sd`, at 10 kHz, for a prior of
    /// `f_hz` (the start is 0.1 rad of it: 22 samples at 7 Hz, 102 at 1.55 Hz, of which the
    /// table's start keeps 32); and the planned start's line.
    fn start_at(
        f_hz: f64,
        accel: impl Fn(f64) -> f64,
        lag: f64,
        b: f64,
        e: f64,
        sd: f64,
        noise: &mut Noise,
    ) -> (MeasuredStart, f64, f64) {
        let params = StructureParams {
            natural_frequency_hz: f_hz,
            ..crate::test_params()
        };
        let rate = 10_000.0;
        // (The table's start keeps its first LAGS − 1 samples, as `BaseTuning` does.)
        let n = crate::model::open_start_samples(&params, rate).min(LAGS as u32 - 1);
        let p = planned_start(&params, rate, &accel).unwrap();
        let half = n / 2;
        let (mut s, mut sk, mut skk, mut sy, mut sky) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut first, mut first_k, mut sd1, mut sd2, mut nd, mut last) =
            (0.0, 0.0, 0.0, 0.0, 0.0, f64::NAN);
        for k in 0..n {
            let kf = k as f64;
            let table = if kf >= lag {
                accel((kf - lag) / rate)
            } else {
                0.0
            };
            let y = b + (1.0 + e) * table + sd * noise.normal();
            (s, sk, skk, sy, sky) = (s + 1.0, sk + kf, skk + kf * kf, sy + y, sky + kf * y);
            if k < n - half {
                (first, first_k) = (first + y, first_k + kf);
            }
            if last.is_finite() {
                let d = y - last;
                (sd1, sd2, nd) = (sd1 + d, sd2 + d * d, nd + 1.0);
            }
            last = y;
        }
        let measured = MeasuredStart {
            line: LineFit::new([s, sk, skk, sy, sky]).unwrap(),
            first_mean: first / (n - half) as f64,
            first_mean_k: first_k / (n - half) as f64,
            first_n: (n - half) as f64,
            n: n as f64,
            // (The differences' noise, their mean left out, as `OpenStart` measures it.)
            noise: libm::sqrt((sd2 - sd1 * sd1 / nd) / (nd - 1.0) / 2.0),
        };
        (
            measured,
            f64::from(p.accel_m_s2),
            f64::from(p.rise_per_sample_m_s2),
        )
    }

    /// A sine from rest (the default scene's 2 m/s² at 7 Hz), lags from none to beyond the
    /// start, offsets 0 and ±0.5 m/s², gains ±1 %, noise 5e-3 m/s², 198 starts per lag (2 376):
    /// the offset is within 3σ of the truth in all but 1.5 % of them (measured: 0.4 %) and
    /// within 6σ in every one (the noise itself is estimated from the start's 21 differences,
    /// ±16 %); its σ is at most twice the noise (measured: 1.8; a lag of a sample or two,
    /// barely seen in the slope, moves the intercept by the rise), down to the mean's 1/√22
    /// beyond the start (the table at rest, reading its offset).
    #[test]
    fn a_sine_start_gives_the_offset_for_any_lag() {
        let sine = |t: f64| 2.0 * libm::sin(2.0 * core::f64::consts::PI * 7.0 * t);
        let mut noise = Noise(7);
        let (mut trials, mut beyond_3) = (0, 0);
        for lag in [
            0.0, 0.4, 1.0, 2.0, 3.3, 5.0, 8.0, 12.0, 17.0, 21.0, 30.0, 400.0,
        ] {
            let (mut max_z, mut max_sd, mut min_sd) = (0.0f64, 0.0f64, f64::INFINITY);
            for b in [0.0, 0.5, -0.5] {
                for e in [-0.01, 0.0, 0.01] {
                    for _ in 0..22 {
                        let (m, a0, r) = start_at(7.0, sine, lag, b, e, 5e-3, &mut noise);
                        let (est, sd) = start_offset(&m, a0, r).unwrap();
                        let z = (est - b).abs() / sd;
                        (max_z, max_sd, min_sd) = (
                            max_z.max(z),
                            max_sd.max(sd / m.noise),
                            min_sd.min(sd / m.noise),
                        );
                        assert!(z < 6.0, "lag {lag} b {b} e {e}: {est} ± {sd} {m:?}");
                        assert!(sd < 2.5 * m.noise, "lag {lag}: σ {sd}, noise {}", m.noise);
                        if lag >= 30.0 {
                            assert!(sd < 0.35 * m.noise, "σ {sd}, noise {}", m.noise);
                        }
                        trials += 1;
                        beyond_3 += usize::from(z > 3.0);
                    }
                }
            }
            std::eprintln!("lag {lag}: max |z| {max_z:.2}, σ/noise {min_sd:.2}..{max_sd:.2}");
        }
        std::eprintln!("{beyond_3} of {trials} beyond 3σ");
        assert!(
            beyond_3 * 1000 <= 15 * trials,
            "{beyond_3} of {trials} beyond 3σ"
        );
    }

    /// A record that starts with an acceleration (El Centro's 0.0063 g, flat over the start):
    /// a table that follows it at once and one still at rest read the same flat line, a0
    /// apart. The offset is their midpoint, within a0/2 + 3σ of the noise of the truth, with a
    /// 3σ of at least a0/2: no offset is taken (3σ) for a table at rest, and 0.5 m/s² is. A lag
    /// within the start shows the step: the offset within 3.5σ.
    #[test]
    fn a_record_that_starts_with_a_jump_gives_the_midpoint() {
        let a0 = 0.0063 * 9.80665;
        let record = |_: f64| a0;
        let mut noise = Noise(11);
        for lag in [0.0, 100.0] {
            for b in [0.0, 0.5] {
                for _ in 0..20 {
                    let (m, p0, r) = start_at(7.0, record, lag, b, 0.0, 5e-3, &mut noise);
                    let (est, sd) = start_offset(&m, p0, r).unwrap();
                    assert!(sd >= a0 / 6.0, "{sd}");
                    assert!(
                        (est - b).abs() <= a0 / 2.0 + 3.0 * 0.41 * m.noise,
                        "lag {lag} b {b}: {est} ± {sd}"
                    );
                    assert_eq!(
                        est.abs() > 3.0 * sd,
                        b != 0.0,
                        "lag {lag} b {b}: {est} ± {sd}"
                    );
                }
            }
        }
        for lag in [3.0, 7.0, 11.0, 15.0] {
            for _ in 0..20 {
                let (m, p0, r) = start_at(7.0, record, lag, 0.5, 0.0, 5e-3, &mut noise);
                let (est, sd) = start_offset(&m, p0, r).unwrap();
                assert!((est - 0.5).abs() < 3.5 * sd, "lag {lag}: {est} ± {sd}");
                assert!(sd <= 0.035, "lag {lag}: {sd}");
            }
        }
    }

    /// A long start (102 samples: a 1.55 Hz prior at 10 kHz, of which the table's start keeps
    /// the first 32), a record that starts with an acceleration and a sine, lags within those
    /// and beyond them: the offset within 3σ in all but 1.5 % of 608 starts, within 6σ in all.
    /// (Over all 102 samples with lags in steps of n/32, a step 2 samples late was taken for
    /// one in the last 3 samples: 95σ off; with whole lags near the ends and 16 between, a
    /// step 9.3 samples late: 26σ.)
    #[test]
    fn a_long_start_gives_the_offset_for_any_lag() {
        let a0 = 0.0063 * 9.80665;
        let record = |_: f64| a0;
        let sine = |t: f64| 2.0 * libm::sin(2.0 * core::f64::consts::PI * 1.55 * t);
        let mut noise = Noise(5);
        let (mut trials, mut beyond_3, mut max_z) = (0, 0, 0.0f64);
        for lag in [0.0, 2.0, 2.5, 9.3, 50.0, 97.0, 101.4, 200.0] {
            for plan in [&record as &dyn Fn(f64) -> f64, &sine] {
                for _ in 0..38 {
                    let (m, p0, r) = start_at(1.55, plan, lag, 0.49, 0.0, 5e-3, &mut noise);
                    assert_eq!(m.n, 32.0);
                    let (est, sd) = start_offset(&m, p0, r).unwrap();
                    let z = (est - 0.49).abs() / sd;
                    assert!(z < 6.0, "lag {lag}: {est} ± {sd}");
                    max_z = max_z.max(z);
                    trials += 1;
                    beyond_3 += usize::from(z > 3.0);
                }
            }
        }
        std::eprintln!("{beyond_3} of {trials} beyond 3σ, max |z| {max_z:.2}");
        assert!(
            beyond_3 * 1000 <= 15 * trials,
            "{beyond_3} of {trials} beyond 3σ"
        );
    }

    /// A table whose start is not the plan's at any lag (twice its rise, or falling where the
    /// plan rises) gives no offset.
    #[test]
    fn a_start_unlike_the_plan_gives_none() {
        let sine = |t: f64| 2.0 * libm::sin(2.0 * core::f64::consts::PI * 7.0 * t);
        let mut noise = Noise(3);
        for e in [1.0, -2.0] {
            let (m, a0, r) = start_at(7.0, sine, 0.0, 0.1, e, 5e-3, &mut noise);
            assert_eq!(start_offset(&m, a0, r), None, "gain 1 + {e}");
        }
    }
}
