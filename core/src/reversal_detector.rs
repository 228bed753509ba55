//! Sensing friction reversals from the sampled base-to-table displacement (the slip).
//!
//! The slip x(t) has a local extremum at every reversal of sliding and is constant while the base
//! sticks. The detector tracks the running extremum in the current sliding direction and, with
//! hysteresis `h` against sensor noise, declares
//!
//! * a **reversal** once x has come back by more than `h` from the extremum,
//! * a **stick** once x has stayed within `h` of the extremum for `stick_samples`,
//! * a **slip start** once x leaves the stuck value by more than `h`.
//!
//! Event times are sub-sample: near a reversal the slip is a parabola on each side of the vertex
//! (constant friction, slowly varying spring force), so the vertex is located by least-squares
//! parabola fits on the samples before and after the extremum (up to `fit_half` samples each side),
//! averaged by point count. A slip start from rest is x − x_s ∝ (t − t_s)², so √|x − x_s| is fitted
//! by a line. The event is reported late (after the hysteresis is crossed) with its exact age in
//! samples, which the estimator back-dates. Fixed-size ring buffer of `N` samples; no heap, no
//! panics.

use crate::error::{check, Error, Param};

/// A detected change of sliding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SlipEvent {
    /// The base started to slide from rest in `direction` (+1 or −1).
    SlipStart {
        /// Slip direction.
        direction: i8,
        /// Samples between the event and the current sample (≥ 0).
        age_samples: f32,
    },
    /// The sliding direction reversed; the base now slides in `direction`.
    Reversal {
        /// New slip direction.
        direction: i8,
        /// Samples between the event and the current sample (≥ 0).
        age_samples: f32,
    },
    /// The base stopped and sticks.
    Stick {
        /// Samples between the event and the current sample (≥ 0).
        age_samples: f32,
    },
}

impl SlipEvent {
    /// The friction level after the event in units of F0 (friction opposes slip; 0 while stuck).
    pub fn friction_level(&self) -> f32 {
        match *self {
            SlipEvent::SlipStart { direction, .. } | SlipEvent::Reversal { direction, .. } => {
                -(direction as f32)
            }
            SlipEvent::Stick { .. } => 0.0,
        }
    }

    /// Age of the event in samples.
    pub fn age_samples(&self) -> f32 {
        match *self {
            SlipEvent::SlipStart { age_samples, .. }
            | SlipEvent::Reversal { age_samples, .. }
            | SlipEvent::Stick { age_samples } => age_samples,
        }
    }
}

/// Detector settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectorConfig {
    /// Hysteresis h (m): a few times the displacement noise RMS.
    pub hysteresis_m: f32,
    /// Samples on each side of an extremum used to locate it.
    pub fit_half: usize,
    /// Samples within `h` of the extremum after which the base is declared stuck.
    pub stick_samples: usize,
}

impl DetectorConfig {
    /// Defaults for a displacement noise RMS and sample rate: h = 8σ (at least 1 µm), fits over
    /// 2 ms, stick after 20 ms.
    pub fn for_noise(noise_rms_m: f64, sample_rate_hz: f64) -> Result<Self, Error> {
        check(
            Param::SampleRate,
            sample_rate_hz,
            sample_rate_hz > 0.0,
            "> 0 Hz",
        )?;
        check(Param::EventTime, noise_rms_m, noise_rms_m >= 0.0, ">= 0 m")?;
        let fit = libm::round(2e-3 * sample_rate_hz).clamp(2.0, 64.0) as usize;
        let stick = libm::round(20e-3 * sample_rate_hz).clamp(3.0, 1e6) as usize;
        Ok(Self {
            hysteresis_m: (8.0 * noise_rms_m).max(1e-6) as f32,
            fit_half: fit,
            stick_samples: stick,
        })
    }
}

/// The reversal/stick detector with a ring buffer of `N` samples (N ≥ 2·fit_half + 2).
#[derive(Debug, Clone)]
pub struct ReversalDetector<const N: usize> {
    cfg: DetectorConfig,
    ring: [f32; N],
    /// Index of the next sample (samples seen so far).
    k: u64,
    /// Current slip direction: +1, −1, or 0 while stuck.
    direction: i8,
    /// Extremum (sliding) or stuck value (stuck).
    ext: f32,
    /// Sample index of the extremum, or of the stick.
    ext_k: u64,
}

impl<const N: usize> ReversalDetector<N> {
    /// A detector that starts stuck at the first sample's value.
    pub fn new(cfg: DetectorConfig) -> Result<Self, Error> {
        check(
            Param::EventTime,
            cfg.hysteresis_m as f64,
            cfg.hysteresis_m > 0.0,
            "hysteresis > 0 m",
        )?;
        if cfg.fit_half < 2 || 2 * cfg.fit_half + 2 > N || cfg.stick_samples == 0 {
            return Err(Error::OutOfRange {
                param: Param::EventTime,
                value: cfg.fit_half as f64,
                expected: "2 <= fit_half, 2*fit_half + 2 <= buffer length, stick_samples >= 1",
            });
        }
        Ok(Self {
            cfg,
            ring: [0.0; N],
            k: 0,
            direction: 0,
            ext: 0.0,
            ext_k: 0,
        })
    }

    /// The current slip direction (+1, −1, 0 stuck).
    pub fn direction(&self) -> i8 {
        self.direction
    }

    /// Samples processed.
    pub fn samples(&self) -> u64 {
        self.k
    }

    fn at(&self, i: u64) -> f32 {
        self.ring[(i % N as u64) as usize]
    }

    /// Process one displacement sample (m). A non-finite sample is skipped (the detector keeps
    /// time; its slot repeats the previous value).
    pub fn process(&mut self, x: f32) -> Option<SlipEvent> {
        let k = self.k;
        let x = if x.is_finite() {
            x
        } else if k > 0 {
            self.at(k - 1)
        } else {
            0.0
        };
        self.ring[(k % N as u64) as usize] = x;
        self.k += 1;
        if k == 0 {
            self.ext = x;
            self.ext_k = 0;
            return None;
        }
        let h = self.cfg.hysteresis_m;
        let d = self.direction as f32;
        if self.direction == 0 {
            let dev = x - self.ext;
            if libm::fabsf(dev) > h {
                let direction = if dev > 0.0 { 1 } else { -1 };
                let t0 = self.slip_start_time(k);
                self.direction = direction;
                self.ext = x;
                self.ext_k = k;
                return Some(SlipEvent::SlipStart {
                    direction,
                    age_samples: (k as f32 - t0).max(0.0),
                });
            }
            return None;
        }
        if d * (x - self.ext) > 0.0 {
            self.ext = x;
            self.ext_k = k;
            return None;
        }
        if d * (self.ext - x) > h {
            let te = self.vertex_time(k);
            let direction = -self.direction;
            self.direction = direction;
            self.ext = x;
            self.ext_k = k;
            return Some(SlipEvent::Reversal {
                direction,
                age_samples: (k as f32 - te).max(0.0),
            });
        }
        if k - self.ext_k >= self.cfg.stick_samples as u64 {
            let te = self.vertex_time(k);
            self.direction = 0;
            // Stuck value: mean of the samples since the extremum (within the ring).
            let n = (k - self.ext_k).min(N as u64 - 1);
            let mut sum = 0.0f32;
            for i in (k - n + 1)..=k {
                sum += self.at(i);
            }
            self.ext = sum / n as f32;
            self.ext_k = k;
            return Some(SlipEvent::Stick {
                age_samples: (k as f32 - te).max(0.0),
            });
        }
        None
    }

    /// Vertex time (sample units, absolute) of the extremum at `ext_k`, from parabola fits on each
    /// side; the current sample is `k`.
    fn vertex_time(&self, k: u64) -> f32 {
        let e = self.ext_k;
        let l = self.cfg.fit_half as u64;
        let oldest = k.saturating_sub(N as u64 - 1);
        let lo = e.saturating_sub(l).max(oldest);
        let hi = (e + l).min(k);
        let left = fit_vertex(|i| self.at(i), lo, e + 1.min(k - e));
        let right = fit_vertex(|i| self.at(i), e.saturating_sub(1).max(oldest), hi);
        let guard =
            |v: Option<(f32, u64)>| v.filter(|(t, _)| libm::fabsf(*t - e as f32) <= 2.0 + l as f32);
        match (guard(left), guard(right)) {
            (Some((a, na)), Some((b, nb))) => (a * na as f32 + b * nb as f32) / (na + nb) as f32,
            (Some((a, _)), None) | (None, Some((a, _))) => a,
            (None, None) => e as f32,
        }
    }

    /// Slip start time (absolute sample units) from √|x − x_s| ∝ (t − t_s) over the recent samples.
    fn slip_start_time(&self, k: u64) -> f32 {
        let l = (2 * self.cfg.fit_half as u64).min(N as u64 - 1).min(k);
        let floor = 0.25 * self.cfg.hysteresis_m;
        let (mut n, mut st, mut sy, mut stt, mut sty) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for i in (k - l)..=k {
            let dev = libm::fabsf(self.at(i) - self.ext);
            if dev > floor {
                let t = (i as i64 - k as i64) as f32;
                let y = libm::sqrtf(dev);
                n += 1.0;
                st += t;
                sy += y;
                stt += t * t;
                sty += t * y;
            }
        }
        let den = n * stt - st * st;
        if n >= 3.0 && den > 0.0 {
            let slope = (n * sty - st * sy) / den;
            let icpt = (sy - slope * st) / n;
            if slope > 0.0 {
                let t0 = -icpt / slope;
                if t0 <= 0.0 && t0 >= -(l as f32) - 2.0 {
                    return k as f32 + t0;
                }
            }
        }
        k as f32
    }
}

/// Least-squares parabola through samples lo..=hi (at least 3); returns (vertex time, points).
fn fit_vertex(at: impl Fn(u64) -> f32, lo: u64, hi: u64) -> Option<(f32, u64)> {
    if hi < lo + 2 {
        return None;
    }
    let n = hi - lo + 1;
    let c = (lo + hi) as f32 / 2.0;
    let y0 = at(lo);
    let (mut s0, mut s1, mut s2, mut s3, mut s4) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    let (mut sy, mut suy, mut su2y) = (0.0f32, 0.0f32, 0.0f32);
    for i in lo..=hi {
        let u = i as f32 - c;
        let y = at(i) - y0;
        let u2 = u * u;
        s0 += 1.0;
        s1 += u;
        s2 += u2;
        s3 += u2 * u;
        s4 += u2 * u2;
        sy += y;
        suy += u * y;
        su2y += u2 * y;
    }
    // Normal equations [[s0 s1 s2][s1 s2 s3][s2 s3 s4]] (c0 c1 c2) = (sy suy su2y), Cramer's rule.
    let det3 = |a: [f32; 9]| {
        a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6])
            + a[2] * (a[3] * a[7] - a[4] * a[6])
    };
    let m = [s0, s1, s2, s1, s2, s3, s2, s3, s4];
    let d = det3(m);
    if d.is_nan() || d == 0.0 {
        return None;
    }
    let c1 = det3([s0, sy, s2, s1, suy, s3, s2, su2y, s4]) / d;
    let c2 = det3([s0, s1, sy, s1, s2, suy, s2, s3, su2y]) / d;
    if c2.is_nan() || c2 == 0.0 {
        return None;
    }
    let v = c - c1 / (2.0 * c2);
    v.is_finite().then_some((v, n))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A piecewise-parabolic slip with a reversal at a sub-sample time and different curvatures.
    #[test]
    fn locates_a_sub_sample_reversal_without_noise() {
        let cfg = DetectorConfig {
            hysteresis_m: 2e-6,
            fit_half: 20,
            stick_samples: 10_000,
        };
        let mut det = ReversalDetector::<64>::new(cfg).unwrap();
        let dt = 1e-4f64;
        let te = 0.0123456;
        let slip = |t: f64| {
            let u = t - te;
            if t < 0.002 {
                0.0
            } else if u < 0.0 {
                1e-3 - 0.5 * 3.0 * u * u
            } else {
                1e-3 - 0.5 * 5.0 * u * u
            }
        };
        let mut events = std::vec::Vec::new();
        for k in 0..400u64 {
            if let Some(e) = det.process(slip(k as f64 * dt) as f32) {
                events.push((k, e));
            }
        }
        let (k, e) = events
            .iter()
            .find(|(_, e)| matches!(e, SlipEvent::Reversal { .. }))
            .copied()
            .unwrap();
        let t_est = (k as f64 - e.age_samples() as f64) * dt;
        assert!((t_est - te).abs() < 0.05 * dt, "{t_est} vs {te}");
        assert_eq!(e.friction_level(), 1.0);
    }
}
