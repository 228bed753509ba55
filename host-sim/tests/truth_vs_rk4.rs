//! The exact stick-slip truth against an independent second method: a fine fixed-step RK4 integration
//! (dt = 1e-6 s, steps aligned with the record samples) of eq (1)-(2) written in the table frame with
//! the displacements x1, x2 (not the drift δ), with every event located by bisection of the step.
//!
//! RK4's truncation error at dt = 1e-6 s is about (ω dt)⁴ ≈ 1e-15 relative and bisection locates
//! events to ~1e-16 s, so the reference is good to rounding. Measured (printed with `--nocapture`):
//! ü1 agrees to ≤ 9.3e-13 gμ (the undamped case; 1.4e-13 to 2.7e-13 otherwise) and event times to
//! ≤ 1.4e-14 s (8.9e-13 s at the ill-conditioned grazing breakaway); the tolerances below (3e-12 gμ,
//! 5e-14 s, grazing 3e-12 s) keep a margin of 3-4, far tighter than the 1e-4 gμ / 1e-5 s of the
//! specification.

mod common;
use common::max_finite;
use host_sim::table_motion::TableMotion;
use host_sim::truth::{simulate, Direction, EventKind, TruthInput};
use ssvr_core::{Structure, StructureParams};

fn structure(m1: f64, m2: f64, f_hz: f64, xi: f64, mu: f64, g: f64) -> Structure {
    Structure::new(StructureParams {
        m1_kg: m1,
        m2_kg: m2,
        natural_frequency_hz: f_hz,
        damping_ratio: xi,
        friction_coefficient: mu,
        gravity_m_s2: g,
    })
    .unwrap()
}

/// Table 1 specimen of the paper.
fn table1() -> Structure {
    structure(29.5, 1.75, 7.0, 0.05, 0.2, 9.80665)
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    Stuck,
    Slide(f64),
}

/// Reference: RK4 of y = (x1, ẋ1, x2, ẋ2) with Coulomb friction and bisection event location.
struct Rk4Reference<'a> {
    m1: f64,
    m2: f64,
    c: f64,
    k: f64,
    f0: f64,
    fs: f64,
    table: &'a TableMotion,
}

struct RefRun {
    events: Vec<(f64, EventKind)>,
    /// (t, ü1) samples.
    samples: Vec<(f64, f64)>,
}

impl<'a> Rk4Reference<'a> {
    fn new(s: &Structure, mu_static: f64, table: &'a TableMotion) -> Self {
        let (m1, m2, p, xi) = (s.m1(), s.m2(), s.p(), s.xi());
        Self {
            m1,
            m2,
            c: 2.0 * m1 * p * xi,
            k: m1 * p * p,
            f0: s.mu() * (m1 + m2) * s.g(),
            fs: mu_static * (m1 + m2) * s.g(),
            table,
        }
    }

    /// ü_g on a step [ta, tb] that contains no record sample in its interior: a record is linear
    /// there, so it is rebuilt from two interior values (this avoids the one-sided values at samples).
    fn step_input(&self, ta: f64, tb: f64) -> impl Fn(f64) -> f64 + '_ {
        let is_record = matches!(self.table, TableMotion::Record { .. });
        let (t1, t2) = (ta + (tb - ta) / 3.0, ta + 2.0 * (tb - ta) / 3.0);
        let (a1, a2) = if is_record {
            (self.table.accel(t1), self.table.accel(t2))
        } else {
            (0.0, 0.0)
        };
        let slope = (a2 - a1) / (t2 - t1);
        move |t: f64| {
            if is_record {
                a1 + slope * (t - t1)
            } else {
                self.table.accel(t)
            }
        }
    }

    fn spring(&self, y: &[f64; 4]) -> f64 {
        self.c * (y[1] - y[3]) + self.k * (y[0] - y[2])
    }

    fn deriv(&self, y: &[f64; 4], ug: f64, mode: Mode) -> [f64; 4] {
        let sp = self.spring(y);
        let a1 = -ug - sp / self.m1;
        match mode {
            Mode::Stuck => [y[1], a1, 0.0, 0.0],
            Mode::Slide(s) => [y[1], a1, y[3], -ug + (-s * self.f0 + sp) / self.m2],
        }
    }

    fn rk4(&self, y: &[f64; 4], t: f64, dt: f64, mode: Mode, u: &impl Fn(f64) -> f64) -> [f64; 4] {
        let add = |a: &[f64; 4], k: &[f64; 4], h: f64| {
            [
                a[0] + h * k[0],
                a[1] + h * k[1],
                a[2] + h * k[2],
                a[3] + h * k[3],
            ]
        };
        let k1 = self.deriv(y, u(t), mode);
        let k2 = self.deriv(&add(y, &k1, 0.5 * dt), u(t + 0.5 * dt), mode);
        let k3 = self.deriv(&add(y, &k2, 0.5 * dt), u(t + 0.5 * dt), mode);
        let k4 = self.deriv(&add(y, &k3, dt), u(t + dt), mode);
        let mut out = *y;
        for i in 0..4 {
            out[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        out
    }

    /// Friction needed to hold the base: m1 ü1 + m2 ü_g = −spring + m2 ü_g.
    fn f_req(&self, y: &[f64; 4], ug: f64) -> f64 {
        -self.spring(y) + self.m2 * ug
    }

    fn triggered(&self, y: &[f64; 4], ug: f64, mode: Mode) -> bool {
        match mode {
            Mode::Stuck => self.f_req(y, ug).abs() > self.fs,
            Mode::Slide(s) => s * y[3] <= 0.0,
        }
    }

    fn run(&self, duration: f64, dt: f64, sample_every: usize) -> RefRun {
        let mut breakpoints: Vec<f64> = match self.table {
            TableMotion::Record { times_s, .. } => {
                times_s.iter().copied().filter(|&t| t < duration).collect()
            }
            _ => vec![],
        };
        breakpoints.push(duration);
        let mut bp = 0usize;
        let (mut t, mut y, mut mode) = (0.0f64, [0.0f64; 4], Mode::Stuck);
        let mut run = RefRun {
            events: vec![],
            samples: vec![(0.0, 0.0)],
        };
        let mut steps = 0usize;
        while t < duration {
            while breakpoints[bp] <= t {
                bp += 1;
            }
            let tb = (t + dt).min(breakpoints[bp]);
            let u = self.step_input(t, tb);
            let h = tb - t;
            let y1 = self.rk4(&y, t, h, mode, &u);
            if !self.triggered(&y1, u(tb), mode) {
                (t, y) = (tb, y1);
                steps += 1;
                if steps == sample_every {
                    steps = 0;
                    run.samples.push((t, -self.spring(&y) / self.m1));
                }
                continue;
            }
            // Bisection on the fraction of the step.
            let (mut lo, mut hi) = (0.0f64, 1.0f64);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                let ym = self.rk4(&y, t, mid * h, mode, &u);
                if self.triggered(&ym, u(t + mid * h), mode) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let te = t + hi * h;
            let mut ye = self.rk4(&y, t, hi * h, mode, &u);
            ye[3] = 0.0;
            let fr = self.f_req(&ye, u(te));
            let pushed = if fr > 0.0 { -1.0 } else { 1.0 };
            let kind = match mode {
                Mode::Stuck => {
                    mode = Mode::Slide(pushed);
                    EventKind::SlipStart {
                        direction: dir(pushed),
                    }
                }
                Mode::Slide(_) => {
                    if fr.abs() <= self.fs {
                        mode = Mode::Stuck;
                        EventKind::Stick
                    } else {
                        mode = Mode::Slide(pushed);
                        EventKind::Reversal {
                            new_direction: dir(pushed),
                        }
                    }
                }
            };
            run.events.push((te, kind));
            (t, y) = (te, ye);
        }
        run
    }
}

fn dir(s: f64) -> Direction {
    if s > 0.0 {
        Direction::Positive
    } else {
        Direction::Negative
    }
}

/// A short synthetic record: zero until 0.05 s, then linear between samples every 0.02 s until
/// 1.25 s (both ends jump), then zero.
fn synthetic_record() -> TableMotion {
    let mut times_s = vec![];
    let mut accel_m_s2 = vec![];
    let mut lcg = 12345u64;
    for k in 0..61 {
        let t = 0.05 + 0.02 * k as f64;
        lcg = lcg
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let jitter = ((lcg >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1.0;
        let a = 3.0 * (2.0 * std::f64::consts::PI * t / 0.15).sin()
            + 1.5 * (2.0 * std::f64::consts::PI * t / 0.37 + 1.0).sin()
            + jitter;
        times_s.push(t);
        accel_m_s2.push(a);
    }
    TableMotion::Record {
        times_s,
        accel_m_s2,
    }
}

/// Compare the truth with the reference; returns (max |Δü1|/gμ, max |Δt_event|, events).
fn compare(s: &Structure, mu_static: f64, table: &TableMotion, duration: f64) -> (f64, f64, usize) {
    let truth = simulate(&TruthInput::new(s, table, duration).with_static_friction(mu_static))
        .expect("valid input");
    let reference = Rk4Reference::new(s, mu_static, table).run(duration, 1e-6, 1000);
    assert!(
        !truth.events().is_empty(),
        "the scene should slide at least once"
    );
    assert_eq!(
        truth.events().len(),
        reference.events.len(),
        "event counts differ:\ntruth {:?}\nref {:?}",
        truth.events(),
        reference.events
    );
    let mut dt_max = 0.0f64;
    for (e, (t, kind)) in truth.events().iter().zip(&reference.events) {
        assert_eq!(e.kind, *kind, "event kinds differ at {t}");
        dt_max = max_finite(dt_max, (e.time_s - t).abs(), "event time error", t);
    }
    let mut cursor = truth.sampler();
    let mut da_max = 0.0f64;
    for &(t, a) in &reference.samples {
        let got = cursor.sample(t).expect("in range").top_accel_m_s2;
        da_max = max_finite(da_max, (got - a).abs() / s.gmu(), "ü1 error", t);
    }
    (da_max, dt_max, truth.events().len())
}

/// Measured ≤ 9.3e-13 gμ.
const ACCEL_TOL: f64 = 3e-12;
/// Measured ≤ 1.4e-14 s.
const TIME_TOL: f64 = 5e-14;

fn check(label: &str, (da, dt, n): (f64, f64, usize)) {
    eprintln!("{label}: {n} events, max |Δü1| = {da:.3e} gμ, max |Δt_event| = {dt:.3e} s");
    assert!(da < ACCEL_TOL, "{label}: {da}");
    assert!(dt < TIME_TOL, "{label}: {dt}");
}

#[test]
fn table1_harmonic_matches_rk4() {
    let s = table1();
    let table = TableMotion::Harmonic {
        amplitude_m_s2: 2.0,
        period_s: 0.143,
    };
    for mu_static in [0.2, 0.25] {
        check(
            &format!("table 1, harmonic 2 m/s² T=0.143 s, μs={mu_static}"),
            compare(&s, mu_static, &table, 2.0),
        );
    }
}

#[test]
fn table1_record_matches_rk4() {
    let s = table1();
    let table = synthetic_record();
    for mu_static in [0.2, 0.25] {
        check(
            &format!("table 1, synthetic record, μs={mu_static}"),
            compare(&s, mu_static, &table, 2.0),
        );
    }
}

#[test]
fn other_damping_regimes_match_rk4() {
    use ssvr_core::Regime;
    let cases = [
        // M = 21, ξ = 0.3: Mξ² = 1.89, overdamped sliding drift.
        (
            structure(20.0, 1.0, 5.0, 0.3, 0.15, 9.80665),
            Regime::Overdamped,
        ),
        // M = 1001, ξ = 0.05: Mξ² = 2.5, a light base (fast mode a + ν ≈ 3000 /s).
        (
            structure(1.0, 1e-3, 5.0, 0.05, 0.2, 9.81),
            Regime::Overdamped,
        ),
        // M = 4, ξ = 0.5: critically damped sliding drift.
        (structure(3.0, 1.0, 5.0, 0.5, 0.2, 9.81), Regime::Critical),
        // ξ = 0: undamped structure.
        (
            structure(29.5, 1.75, 7.0, 0.0, 0.2, 9.80665),
            Regime::Underdamped,
        ),
    ];
    let table = TableMotion::Harmonic {
        amplitude_m_s2: 4.0,
        period_s: 0.3,
    };
    for (s, regime) in cases {
        assert_eq!(s.regime(), regime);
        check(
            &format!("{regime:?}, M = {}, ξ = {}", s.mass_ratio(), s.xi()),
            compare(&s, s.mu(), &table, 1.5),
        );
    }
}

#[test]
fn grazing_breakaway() {
    // Table 1 under 0.2 s harmonic input: A* = 0.7129172293862671 m/s² (found by bisection) is the
    // amplitude at which the holding force first just touches F0, at t ≈ 0.2519 s.
    let s = table1();
    let harmonic = |a: f64| TableMotion::Harmonic {
        amplitude_m_s2: a,
        period_s: 0.2,
    };
    let a_star = 0.7129172293862671;
    let below = simulate(&TruthInput::new(&s, &harmonic(a_star * (1.0 - 1e-8)), 1.0)).unwrap();
    assert!(below.events().is_empty());
    // 1e-8 above: a slide of about 0.01 ms, which the reference (dt = 1e-6 s) still resolves. Event
    // times are ill-conditioned here (the holding force crosses F0 with a slope of a few N/s).
    let (da, dt, n) = compare(&s, 0.2, &harmonic(a_star * (1.0 + 1e-8)), 1.0);
    eprintln!("grazing: {n} events, max |Δü1| = {da:.3e} gμ, max |Δt_event| = {dt:.3e} s");
    assert_eq!(n, 2);
    assert!(da < ACCEL_TOL, "{da}");
    // Measured 8.9e-13 s.
    assert!(dt < 3e-12, "{dt}");
    // Regression: at this amplitude (1e-6 above A*) the holding force reaches F0 exactly (e = 0 at
    // the located crossing, slope ~3 N/s), so the slide starts with zero slip acceleration and must
    // still be followed to its stop 0.12 ms later (it once stalled at the breakaway instant).
    let a_touch = f64::from_bits(4604596613810812354);
    let truth = simulate(&TruthInput::new(&s, &harmonic(a_touch), 1.0)).unwrap();
    let kinds: Vec<EventKind> = truth.events().iter().map(|e| e.kind).collect();
    assert_eq!(
        kinds,
        [
            EventKind::SlipStart {
                direction: Direction::Negative
            },
            EventKind::Stick
        ]
    );
    let slide = truth.events()[1].time_s - truth.events()[0].time_s;
    assert!(slide > 1e-4 && slide < 2e-4, "{slide}");
}
