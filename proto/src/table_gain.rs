//! The table accelerometer's gain, against the base-to-table displacement sensor.
//!
//! Every other accelerometer's gain is identified relative to the table's (the detector tracks
//! the base's, the fuse mode's model the top's), so the table accelerometer's own gain error e
//! scales every prediction by 1 + e. The displacement sensor is the absolute reference: the base
//! starts each sliding episode stuck (slip velocity 0), so from a sample r while stuck before it
//! to a sample n while stuck after it
//!
//! ```text
//! Q = ΣΣ a·dt²  =  (1 + e)·D  +  b·W,    D = s_n − s_r,   W = m(m+1)/2·dt²,
//! ΣΣ x = Σ_{j=r+1..n} Σ_{i=r+1..j} x_i
//! ```
//!
//! where a is the slip acceleration in the table accelerometer's units (the base corrected by the
//! gain mismatch and offset its detector tracks, less the table), s the measured slip, b what is
//! left of a's offset and m = n − r. Least squares over the episodes gives 1 + e and b, with the
//! standard deviation of 1 + e from the residuals. The displacement sensor's own offset cancels
//! in D; its noise (1 µm) is far below a slip (0.5-5 mm).
//!
//! What limits one episode is not the accelerometers' noise (~1e-6 m) but the jumps of the slip
//! acceleration at reversals and sticks (2μ(m1+m2)g/m2, tens of m/s²) between samples: a point
//! sample misplaces each by up to half a sample, ~1e-5 m by the episode's end on El Centro.
//! These errors are independent from episode to episode, so the fit's formal standard
//! deviation (1e-4 after 140 episodes of the default scene, 1e-3 after El Centro's 31) shrinks
//! as 1/√episodes; a bias of a few 1e-4 remains beyond it (El Centro with μ = 0.15:
//! −3.6e-4 ± 6.7e-5), which [`MIN_CHANGE`] keeps from being adopted.
//! Fitting the base's residual gain mismatch as a third coefficient (its term is the table's own
//! double sum) was tried: on a periodic input the episodes repeat, so that term and D are 99.7 %
//! correlated and the gain's standard deviation grows tenfold.
//!
//! The detector's events arrive late (a slip start up to its longest back-dating after the
//! fact), so two integrators are restarted in turn while the base sticks, every `H` > longest
//! back-dating samples (at the ends of blocks of 8 samples, which the samples are summed over
//! first): when a slip start arrives, the one restarted latest before the slip began carries
//! the episode (one restarted after it, the slip already under way, is spoilt for good; with
//! none left the episode is not used), no restart until the next stick, which closes it.
//!
//! An estimate is adopted ([`TableGain::scale`]) once eight episodes give a standard deviation
//! below [`ADOPT_SIGMA`], and again whenever it moves by more than 3σ and [`MIN_CHANGE`]; an
//! estimate more than [`MAX_ERROR`] from 1 is never adopted (a displacement sensor off scale is
//! not an accelerometer fault).

use ssvr_core::detect::displacement::SlipEvent;
use ssvr_core::least_squares::PagedNormal;

/// Adopt an estimate of 1 + e once its standard deviation is below this.
pub const ADOPT_SIGMA: f64 = 2e-3;
/// The largest gain error adopted.
pub const MAX_ERROR: f64 = 0.1;
/// The smallest change of the gain in use worth adopting (a tenth of a percent is far below
/// what the prediction's goals notice; smaller changes would follow the estimate's noise).
pub const MIN_CHANGE: f64 = 1e-3;
/// Episodes before a first adoption.
const MIN_EPISODES: u32 = 8;
/// Samples between a slip start and the restart of the integrator that carries it, at least.
const MARGIN: u32 = 16;
/// Samples summed before they are added to the integrators (a sample costs two additions; the
/// integrators, their restarts and the episodes' ends go by blocks).
const BLOCK: u32 = 8;

/// One integrator: the double sum of the slip acceleration since its restart.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Integrator {
    /// Sample index of the restart.
    start: u32,
    /// Slip displacement at the restart (NaN: unusable).
    s0: f32,
    /// Σ a.
    v: f32,
    /// Σ Σ a.
    q: f32,
}

impl Integrator {
    const IDLE: Self = Self {
        start: 0,
        s0: f32::NAN,
        v: 0.0,
        q: 0.0,
    };
}

/// The table accelerometer's gain identified against the slip displacement.
#[derive(Debug, Clone)]
pub struct TableGain {
    dt2: f64,
    /// Blocks between restarts, and to the next one.
    period: u32,
    countdown: u32,
    next: usize,
    slots: [Integrator; 2],
    /// The block's Σ a and Σ Σ a, and its samples.
    lv: f32,
    lq: f32,
    count: u32,
    /// Whether the base slides (from a slip start's arrival to its episode's end), and the slot
    /// carrying the episode (`None`: no slot was restarted before the slip began; the episode is
    /// not used).
    sliding: bool,
    carrying: Option<usize>,
    /// The episode's stick arrived; it ends at the first block with a valid displacement.
    closing: bool,
    last: f32,
    /// Q = g·D + b·W over the episodes.
    fit: PagedNormal<f64, 2, 6>,
    episodes: u32,
    adopted: f32,
    inverse: f32,
    estimate: Option<GainEstimate>,
    /// The last adoption not yet taken ([`Self::take_change`]): its sample and the factor
    /// the samples' units changed by; and 1 + the batch (of [`crate::pipeline::BATCH`] samples
    /// from the run's start) of the last adoption (0: none).
    change: Option<(u32, f32)>,
    change_batch: u32,
}

/// An estimate of the table accelerometer's gain, 1 + e.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GainEstimate {
    /// 1 + e.
    pub gain: f64,
    /// Its standard deviation.
    pub sigma: f64,
    /// Episodes it rests on.
    pub episodes: u32,
    /// The 1 + e in use (adopted; 1 until an adoption).
    pub in_use: f32,
}

impl TableGain {
    /// At `rate_hz`, for a detector whose events are back-dated by at most `max_age` samples.
    pub fn new(rate_hz: f32, max_age: usize) -> Self {
        let period = (max_age as u32)
            .saturating_add(2 * MARGIN)
            .max(16)
            .div_ceil(BLOCK);
        let dt = 1.0 / f64::from(rate_hz);
        Self {
            dt2: dt * dt,
            period,
            countdown: 0,
            next: 0,
            slots: [Integrator::IDLE; 2],
            lv: 0.0,
            lq: 0.0,
            count: 0,
            sliding: false,
            carrying: None,
            closing: false,
            last: 0.0,
            fit: PagedNormal::new(1.0),
            episodes: 0,
            adopted: 1.0,
            inverse: 1.0,
            estimate: None,
            change: None,
            change_batch: 0,
        }
    }

    /// The identification of `plan`, if it has one ([`crate::Plan::identifies_table_gain`]), for
    /// a detector whose events are back-dated by at most `max_age` samples.
    pub fn of_plan(plan: &crate::Plan, max_age: usize) -> Option<Self> {
        plan.identifies_table_gain()
            .then(|| Self::new(plan.specimen.sample_rate_hz as f32, max_age))
    }

    /// The adopted 1 + e (1 until an estimate is adopted): the accelerometers' samples in the
    /// table's units are divided by it.
    #[inline(always)]
    pub fn scale(&self) -> f32 {
        self.adopted
    }

    /// 1 / [`Self::scale`].
    #[inline(always)]
    pub fn inverse(&self) -> f32 {
        self.inverse
    }

    /// The last adoption, once: the sample from which the accelerometers' samples are divided
    /// by the new gain, and the factor their units changed by (the new [`Self::inverse`] over
    /// the old one), for the model's rescaling
    /// ([`Model::rescale_units`](crate::Model::rescale_units)).
    pub fn take_change(&mut self) -> Option<(u32, f32)> {
        self.change.take()
    }

    /// The latest estimate, adopted or not, with the gain in use.
    pub fn estimate(&self) -> Option<GainEstimate> {
        self.estimate.map(|e| GainEstimate {
            in_use: self.adopted,
            ..e
        })
    }

    /// Sample `index`: the slip acceleration `a` in the table's units (NaN when unusable: the last
    /// usable one is held), the slip displacement `s`
    /// (NaN when unusable) and the detector's event.
    #[inline(always)]
    pub fn push(&mut self, index: u32, a: f32, s: f32, event: Option<&SlipEvent>) {
        if a.is_finite() {
            self.last = a;
        }
        self.lv += self.last;
        self.lq += self.lv;
        self.count += 1;
        if let Some(e) = event {
            self.event(index, e);
        }
        if self.count >= BLOCK {
            self.flush(index, s);
        }
    }

    /// The block into the integrators, at its last sample `index` (slip `s`): then a restart
    /// while the base sticks, or the episode's end.
    #[inline(never)]
    fn flush(&mut self, index: u32, s: f32) {
        let n = self.count as f32;
        for slot in self.slots.iter_mut() {
            slot.q += n * slot.v + self.lq;
            slot.v += self.lv;
        }
        (self.lv, self.lq, self.count) = (0.0, 0.0, 0);
        if self.sliding {
            if self.closing && s.is_finite() {
                self.close(index, s);
            }
            return;
        }
        if self.countdown == 0 {
            self.countdown = self.period;
            if let Some(slot) = self.slots.get_mut(self.next) {
                *slot = Integrator {
                    start: index,
                    s0: s,
                    ..Integrator::IDLE
                };
            }
            self.next ^= 1;
        }
        self.countdown -= 1;
    }

    #[inline(never)]
    fn event(&mut self, index: u32, e: &SlipEvent) {
        match e {
            SlipEvent::SlipStart { .. } if !self.sliding => {
                // The slot restarted latest before the slip began; one restarted after it (the
                // slip already under way) is of no use for any episode.
                let age = e.age_samples() as u32;
                let began = index.saturating_sub(age.saturating_add(MARGIN));
                for slot in self.slots.iter_mut() {
                    if slot.start > began {
                        slot.s0 = f32::NAN;
                    }
                }
                self.carrying = self
                    .slots
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| s.s0.is_finite())
                    .max_by_key(|(_, s)| s.start)
                    .map(|(i, _)| i);
                (self.sliding, self.closing) = (true, false);
            }
            SlipEvent::Stick { .. } if self.sliding => self.closing = true,
            _ => {}
        }
    }

    #[inline(never)]
    fn close(&mut self, index: u32, s: f32) {
        let carrying = self.carrying.take();
        (self.sliding, self.closing, self.countdown) = (false, false, 0);
        let Some(slot) = carrying.and_then(|c| self.slots.get(c)) else {
            return;
        };
        let d = f64::from(s - slot.s0);
        let m = f64::from(index.wrapping_sub(slot.start));
        let w = m * (m + 1.0) / 2.0 * self.dt2;
        let q = f64::from(slot.q) * self.dt2;
        if d == 0.0 || !(d.is_finite() && q.is_finite()) {
            return;
        }
        self.fit.add(&[d, w], q);
        self.episodes += 1;
        self.solve(index);
    }

    fn solve(&mut self, index: u32) {
        if self.episodes < MIN_EPISODES {
            return;
        }
        let Some(fit) = self.fit.solve::<2>() else {
            return;
        };
        let gain = fit.theta[0];
        let sigma = libm::sqrt(fit.cov[0][0].max(0.0));
        if !(gain.is_finite() && sigma.is_finite()) {
            return;
        }
        self.estimate = Some(GainEstimate {
            gain,
            sigma,
            episodes: self.episodes,
            in_use: self.adopted,
        });
        // (At most one adoption per batch: the pipeline takes a batch's change once, at its
        // end, and the host's reference one sample at a time; a second one would have them
        // rescale differently. Two episodes' ends within 16 samples are all but impossible.)
        let batch = index / crate::pipeline::BATCH as u32 + 1;
        if sigma < ADOPT_SIGMA
            && libm::fabs(gain - 1.0) <= MAX_ERROR
            && libm::fabs(gain - f64::from(self.adopted)) > libm::fmax(3.0 * sigma, MIN_CHANGE)
            && batch != self.change_batch
        {
            let old = self.inverse;
            self.adopted = gain as f32;
            self.inverse = 1.0 / self.adopted;
            self.change = Some((index, self.inverse / old));
            self.change_batch = batch;
        }
    }
}

/// Where a pipeline keeps its [`TableGain`]: `Option<TableGain>`, or `()` (no code, no storage:
/// the fixed-base model's image, whose base never slides).
pub trait GainSlot: Clone + core::fmt::Debug {
    /// No gain identification.
    fn none() -> Self;
    /// The slot holding `gain` (`()`: still none).
    fn of(gain: TableGain) -> Self;
    /// The identification, if any.
    fn get(&self) -> Option<&TableGain>;
    /// The identification, if any.
    fn get_mut(&mut self) -> Option<&mut TableGain>;
}

impl GainSlot for () {
    fn none() -> Self {}
    fn of(_: TableGain) -> Self {}
    #[inline(always)]
    fn get(&self) -> Option<&TableGain> {
        None
    }
    #[inline(always)]
    fn get_mut(&mut self) -> Option<&mut TableGain> {
        None
    }
}

impl GainSlot for Option<TableGain> {
    fn none() -> Self {
        None
    }
    fn of(gain: TableGain) -> Self {
        Some(gain)
    }
    #[inline(always)]
    fn get(&self) -> Option<&TableGain> {
        self.as_ref()
    }
    #[inline(always)]
    fn get_mut(&mut self) -> Option<&mut TableGain> {
        self.as_mut()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Episodes of a known slip (one sine period of slip acceleration) measured with a table
    /// gain error of 1.2 % and a residual offset of 2e-4 m/s²: the gain is found within 1e-4.
    #[test]
    fn the_gain_of_slip_episodes_against_the_displacement() {
        let g = episodes(0.012, 12, false);
        let est = g.estimate().expect("an estimate");
        assert_eq!(est.episodes, 12);
        assert!((est.gain - 1.012).abs() < 1e-4, "{est:?}");
        assert!(est.sigma < 1e-4, "{est:?}");
        assert!(est.sigma.is_finite());
        assert!((f64::from(g.scale()) - 1.012).abs() < 1e-4);
    }

    /// `n` episodes (one sine period of slip acceleration each, alternating amplitude, stuck
    /// 2000–3400 samples between) measured with a table gain error `e` and a residual offset of
    /// 2e-4 m/s²; with `nan_at_stick` the displacement is missing for 30 samples from each stick
    /// event on (the episode closes at the first valid one).
    fn episodes(e: f64, n: u32, nan_at_stick: bool) -> TableGain {
        let rate = 10_000.0f32;
        let dt = 1.0 / f64::from(rate);
        let mut g = TableGain::new(rate, 300);
        let b = 2e-4;
        let mut s_true = 0.003f64; // the displacement sensor's offset is arbitrary
        let mut v_true = 0.0f64;
        let mut k = 0u32;
        for ep in 0..n {
            let stuck = 2000 + 700 * (ep % 3);
            let slide = 1500 + 400 * (ep % 2);
            let amp = if ep % 2 == 0 { 3.0 } else { -2.0 };
            for j in 0..stuck + slide + 400 {
                let acc = if j >= stuck && j < stuck + slide {
                    let x = f64::from(j - stuck) / f64::from(slide);
                    amp * libm::sin(2.0 * core::f64::consts::PI * x)
                } else {
                    0.0
                };
                v_true += acc * dt;
                s_true += v_true * dt;
                let a = ((1.0 + e) * acc + b) as f32;
                let event = if j == stuck + 120 {
                    Some(SlipEvent::SlipStart {
                        age_samples: 120.0,
                        direction: 1,
                    })
                } else if j == stuck + slide + 150 {
                    Some(SlipEvent::Stick { age_samples: 150.0 })
                } else {
                    None
                };
                let missing =
                    nan_at_stick && (stuck + slide + 150..stuck + slide + 180).contains(&j);
                let s = if missing { f32::NAN } else { s_true as f32 };
                g.push(k, a, s, event.as_ref());
                k += 1;
            }
            v_true = 0.0;
        }
        g
    }

    /// What is not adopted: a gain error beyond [`MAX_ERROR`] (found, not used), and one below
    /// [`MIN_CHANGE`]; a displacement missing at the stick only delays the episode's close.
    #[test]
    fn what_is_not_adopted_and_a_missing_displacement() {
        let far = episodes(0.2, 12, false);
        let est = far.estimate().expect("an estimate");
        assert!((est.gain - 1.2).abs() < 1e-3, "{est:?}");
        assert_eq!(far.scale(), 1.0);
        let small = episodes(5e-4, 12, false);
        let est = small.estimate().expect("an estimate");
        assert!(
            (est.gain - 1.0005).abs() < 1e-4 && est.sigma < 1e-4,
            "{est:?}"
        );
        assert_eq!(small.scale(), 1.0);
        let gaps = episodes(0.012, 12, true);
        let est = gaps.estimate().expect("an estimate");
        assert_eq!(est.episodes, 12);
        assert!((est.gain - 1.012).abs() < 1e-4, "{est:?}");
        assert!((f64::from(gaps.scale()) - 1.012).abs() < 1e-4);
    }

    /// Short sticks: stuck for 100 samples between slides while the detector reports a stick 150
    /// samples late and a slip start 120 samples late, so the integrator restarted when an
    /// episode closes is restarted after the next slip began; it must never carry an episode
    /// (without that rule the gain came out 0.9981 for 1.012). Gain within 1e-4.
    #[test]
    fn short_sticks_never_use_an_integrator_restarted_while_sliding() {
        let rate = 10_000.0f32;
        let dt = 1.0 / f64::from(rate);
        let mut g = TableGain::new(rate, 300);
        let e = 0.012;
        let (mut s_true, mut v_true, mut k) = (0.003f64, 0.0f64, 0u32);
        for ep in 0..40 {
            let stuck = if ep % 2 == 0 { 100 } else { 2000 };
            let slide = 1500 + 300 * (ep % 3);
            let amp = if ep % 2 == 0 { 3.0 } else { -2.0 };
            for j in 0..stuck + slide {
                let acc = if j >= stuck {
                    let x = f64::from(j - stuck) / f64::from(slide);
                    amp * libm::sin(2.0 * core::f64::consts::PI * x)
                } else {
                    0.0
                };
                v_true += acc * dt;
                s_true += v_true * dt;
                let event = if j == stuck + 120 {
                    Some(SlipEvent::SlipStart {
                        age_samples: 120.0,
                        direction: 1,
                    })
                } else if j == 150 && ep > 0 {
                    Some(SlipEvent::Stick { age_samples: 150.0 })
                } else {
                    None
                };
                g.push(k, ((1.0 + e) * acc) as f32, s_true as f32, event.as_ref());
                k += 1;
            }
            v_true = 0.0;
        }
        let est = g.estimate().expect("an estimate");
        assert!(est.episodes >= 15, "{est:?}");
        assert!((est.gain - (1.0 + e)).abs() < 1e-4, "{est:?}");
        assert!(est.sigma.is_finite() && est.sigma < 1e-4, "{est:?}");
    }

    /// Without slip episodes nothing is adopted; NaN samples are held.
    #[test]
    fn nothing_without_episodes() {
        let mut g = TableGain::new(1000.0, 50);
        for k in 0..10_000u32 {
            let a = if k % 7 == 0 { f32::NAN } else { 0.01 };
            g.push(k, a, f32::NAN, None);
        }
        assert_eq!(g.scale(), 1.0);
        assert!(g.estimate().is_none());
    }
}
