//! TEMPORARY randomized differential test: update_block vs per-sample update.
use ssvr_core::math::{F32Poly, Libm, Real, Transcendentals};
use ssvr_core::stick_slip_estimator::{storage_for, StickSlipConfig, StickSlipEstimator};
use ssvr_core::{Structure, StructureParams};

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    fn f(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
    fn chance(&mut self, p: f64) -> bool {
        self.f() < p
    }
}

trait Bits: Real {
    fn bits(self) -> u64;
}
impl Bits for f32 {
    fn bits(self) -> u64 {
        self.to_bits() as u64
    }
}
impl Bits for f64 {
    fn bits(self) -> u64 {
        self.to_bits()
    }
}

#[derive(Debug, Clone)]
struct Params {
    seed: u64,
    ty: &'static str,
    h: usize,
    history: usize,
    rate: f64,
    xi: f64,
    m1: f64,
    m2: f64,
    f_hz: f64,
    cfg: StickSlipConfig,
    n: u64,
    event_p: f64,
    bad_p: f64,
}

#[derive(Default, Debug)]
struct Stats {
    cases: u64,
    samples: u64,
    events: u64,
    events_ok: u64,
    blocks: u64,
    empty_blocks: u64,
    bad_len_checks: u64,
    bad_inputs: u64,
    predictions: u64,
}

fn fail(p: &Params, msg: String) -> ! {
    panic!("MISMATCH {msg}\nparams: {p:?}");
}

fn mu_bits(m: Option<ssvr_core::stick_slip_estimator::MuEstimate>) -> Option<(u64, u64, u32)> {
    m.map(|m| (m.mu.to_bits(), m.std.to_bits(), m.samples))
}

fn run_case<T: Bits, M: Transcendentals<T>, const H: usize>(
    rng: &mut Rng,
    p: &Params,
    st: &mut Stats,
) {
    let s = Structure::new(StructureParams {
        m1_kg: p.m1,
        m2_kg: p.m2,
        natural_frequency_hz: p.f_hz,
        damping_ratio: p.xi,
        friction_coefficient: 0.2,
        gravity_m_s2: 9.80665,
    })
    .unwrap();
    let mut a =
        StickSlipEstimator::<T, M, H>::with_history(&s, p.rate, p.cfg, p.history).unwrap();
    let mut b =
        StickSlipEstimator::<T, M, H>::with_history(&s, p.rate, p.cfg, p.history).unwrap();
    let hist = p.history as f64;
    let dt = 1.0 / p.rate;
    let (w1, w2) = (2.0 * core::f64::consts::PI * (1.0 + 20.0 * rng.f()), 2.0 * core::f64::consts::PI * (1.0 + 20.0 * rng.f()));
    let (amp_u, amp_y) = (0.1 + 5.0 * rng.f(), 0.1 + 5.0 * rng.f());
    let noise = rng.chance(0.5);
    let big = if T::from_f64(1e39).is_finite() { 1e300 } else { 3e38 };
    // Pre-generate inputs and events.
    let mut table = Vec::with_capacity(p.n as usize);
    let mut top = Vec::with_capacity(p.n as usize);
    let mut events: Vec<Vec<(i8, T)>> = Vec::with_capacity(p.n as usize);
    // stretch phases: sometimes event-free stretches
    for k in 0..p.n {
        let t = k as f64 * dt;
        let mut u = amp_u * (w1 * t).sin() + if noise { 0.1 * (rng.f() - 0.5) } else { 0.0 };
        let mut y = amp_y * (w2 * t).cos() + if noise { 0.1 * (rng.f() - 0.5) } else { 0.0 };
        if rng.chance(p.bad_p) {
            st.bad_inputs += 1;
            let v = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e30, -1e30, big, -big, 0.0][rng.below(8) as usize];
            match rng.below(3) {
                0 => u = v,
                1 => y = v,
                _ => {
                    u = v;
                    y = [f64::NAN, 1e30, f64::INFINITY][rng.below(3) as usize];
                }
            }
        }
        if rng.chance(0.02) {
            y = f64::NAN;
        }
        table.push(T::from_f64(u));
        top.push(T::from_f64(y));
        let mut ev = Vec::new();
        if rng.chance(p.event_p) {
            let count = 1 + if rng.chance(0.2) { rng.below(3) } else { 0 };
            for _ in 0..count {
                let phase = [1i8, -1, 0, 1, -1][rng.below(5) as usize];
                let maxa = (hist - 2.0).max(0.0);
                let age = match rng.below(20) {
                    0..=4 => 0.0,
                    5..=8 => (rng.f() * (maxa + 1.0)).floor().min(maxa),
                    9..=15 => rng.f() * maxa,
                    16 => maxa,
                    17 => hist - 1.0,
                    18 => hist - 1.0 + rng.f().max(1e-3),
                    _ => [hist, 1e9, -1.0, f64::NAN, f64::INFINITY, 0.5, 1.0, 1.5][rng.below(8) as usize],
                };
                // a few invalid phases
                let phase = if rng.chance(0.01) { 2 } else { phase };
                ev.push((phase, T::from_f64(age)));
            }
        }
        events.push(ev);
    }

    let check = |a: &StickSlipEstimator<T, M, H>,
                     b: &StickSlipEstimator<T, M, H>,
                     k: u64,
                     st: &mut Stats| {
        if a.sample_index() != b.sample_index() {
            fail(p, format!("sample_index {} vs {} at {k}", a.sample_index(), b.sample_index()));
        }
        if mu_bits(a.mu_estimate()) != mu_bits(b.mu_estimate()) {
            fail(p, format!("mu_estimate {:?} vs {:?} at {k}", a.mu_estimate(), b.mu_estimate()));
        }
        if a.mu_used().to_bits() != b.mu_used().to_bits() || a.phase() != b.phase() {
            fail(p, format!("mu_used/phase at {k}"));
        }
        let lo = k.saturating_sub(p.history as u64 + 2);
        for j in lo..=k + 1 {
            let (pa, pb) = (a.prediction_at(j), b.prediction_at(j));
            st.predictions += 1;
            if pa.map(T::bits) != pb.map(T::bits) {
                fail(p, format!("prediction_at({j}) {pa:?} vs {pb:?} after block ending at {k}"));
            }
        }
    };

    let mut k = 0u64;
    let mut out = vec![T::ZERO; 64];
    let mut pushed = u64::MAX;
    while k < p.n {
        // events for sample k, pushed into both (once)
        let evs: &[(i8, T)] = if pushed == k { &[] } else { &events[k as usize] };
        pushed = k;
        for &(ph, age) in evs {
            let ra = a.push_event(ph, age);
            let rb = b.push_event(ph, age);
            st.events += 1;
            if ra.is_ok() {
                st.events_ok += 1;
            }
            if ra != rb {
                fail(p, format!("push_event({ph}, {age:?}) at {k}: {ra:?} vs {rb:?}"));
            }
        }
        if rng.chance(0.03) {
            st.empty_blocks += 1;
            b.update_block(&[], &[], &mut []).unwrap();
        }
        if rng.chance(0.02) {
            // unequal lengths: nothing processed
            st.bad_len_checks += 1;
            let l = 1 + rng.below(10) as usize;
            let end = ((k as usize) + l).min(p.n as usize);
            let t = &table[k as usize..end];
            let y = &top[k as usize..end];
            let mut o = vec![T::from_f64(7.0); t.len() + 1];
            let r = match rng.below(3) {
                0 => b.update_block(t, &y[..y.len() - 1], &mut o[..t.len()]),
                1 => b.update_block(t, y, &mut o),
                _ => b.update_block(t, &top[k as usize..(end + 1).min(p.n as usize).max(end)], &mut o[..t.len() - 1]),
            };
            if r.is_ok() || o.iter().any(|x| x.bits() != T::from_f64(7.0).bits()) || b.sample_index() != k {
                fail(p, format!("unequal lengths at {k}: {r:?}, sample_index {}", b.sample_index()));
            }
        }
        let len = match rng.below(10) {
            0 => 1,
            1..=2 => rng.below(51),
            3..=5 => 16,
            _ => 1 + rng.below(50),
        } as u64;
        let mut end = (k + len).min(p.n);
        if let Some(j) = (k + 1..end).find(|&j| !events[j as usize].is_empty()) {
            end = j;
        }
        let (ks, ke) = (k as usize, end as usize);
        let want: Vec<T> = (ks..ke).map(|i| a.update(table[i], top[i])).collect();
        let o = &mut out[..ke - ks];
        b.update_block(&table[ks..ke], &top[ks..ke], o).unwrap();
        st.blocks += 1;
        st.samples += (ke - ks) as u64;
        for (i, (w, g)) in want.iter().zip(o.iter()).enumerate() {
            if w.bits() != g.bits() {
                fail(
                    p,
                    format!(
                        "output of sample {} (block {ks}..{ke}): update {w:?} vs update_block {g:?}; inputs table {:?} top {:?}",
                        ks + i,
                        table[ks + i],
                        top[ks + i]
                    ),
                );
            }
        }
        k = end;
        check(&a, &b, k, st);
    }
    st.cases += 1;
}

fn gen_params(rng: &mut Rng, seed: u64, long: bool) -> (Params, usize) {
    const HS: [usize; 10] = [8, 17, 40, 41, 64, 65, 97, 144, 145, 256];
    let hi = rng.below(HS.len() as u64) as usize;
    let h = HS[hi];
    let every = 1 + rng.below(32) as u32;
    // history: aligned with storage_for if possible, or random
    let history = match rng.below(6) {
        0 => h,
        1 => h - 1,
        2 => {
            // try aligned: storage_for(history, every) == h
            let cands: Vec<usize> = (2..=h).filter(|&x| storage_for(x, every) == h).collect();
            if cands.is_empty() {
                2 + rng.below(h as u64 - 1) as usize
            } else {
                cands[rng.below(cands.len() as u64) as usize]
            }
        }
        3 => 2 + rng.below(4.min(h as u64 - 1)) as usize,
        _ => 2 + rng.below(h as u64 - 1) as usize,
    };
    let rate = match rng.below(5) {
        0 => 1e4,
        1 => 1e3,
        _ => 200.0 * (500.0f64).powf(rng.f()),
    };
    // damping: (xi, m1, m2): ζ = √M ξ; M = 1 + m1/m2
    let (xi, m1, m2) = match rng.below(6) {
        0 => (0.0, 29.5, 1.75),
        1 => (0.05, 29.5, 1.75),
        2 => (0.7, 29.5, 1.75),  // ζ ≈ 2.96 overdamped sliding
        3 => (0.5, 3.0, 1.0),    // ζ = 1 exactly: critical sliding
        4 => (0.2, 99.0, 1.0),   // ζ = 2: overdamped
        _ => (0.99, 1.0, 3.0),   // fixed base nearly critical, ζ ≈ 1.14
    };
    let mut cfg = StickSlipConfig {
        identify_mu: rng.chance(0.75),
        use_identified_mu: rng.chance(0.5),
        min_samples: 1 + rng.below(60) as u32,
        identify_every: every,
        observer_bandwidth: [0.0, 2.0, 10.0][rng.below(3) as usize],
        forgetting: [0.9999, 1.0, 0.99][rng.below(3) as usize],
        ..StickSlipConfig::DEFAULT
    };
    if rng.chance(0.1) {
        cfg = StickSlipConfig { identify_mu: cfg.identify_mu, use_identified_mu: cfg.use_identified_mu, ..StickSlipConfig::DEFAULT.for_rate(rate) };
    }
    let n = if long {
        20_000 + rng.below(20_000)
    } else {
        200 + rng.below(4000)
    };
    let event_p = [0.0, 0.001, 0.005, 0.02, 0.1, 0.3][rng.below(6) as usize];
    let bad_p = [0.0, 0.0, 0.0005, 0.003, 0.02][rng.below(5) as usize];
    let tyi = rng.below(10);
    let ty = match tyi {
        0..=5 => "f32/F32Poly",
        6 => "f32/Libm",
        _ => "f64/Libm",
    };
    (
        Params {
            seed,
            ty,
            h,
            history,
            rate,
            xi,
            m1,
            m2,
            f_hz: [7.0, 7.0, 2.0, 25.0][rng.below(4) as usize],
            cfg,
            n,
            event_p,
            bad_p,
        },
        hi,
    )
}

macro_rules! dispatch {
    ($rng:expr, $p:expr, $st:expr, $($h:literal),*) => {
        match ($p.ty, $p.h) {
            $(
                ("f32/F32Poly", $h) => run_case::<f32, F32Poly, $h>($rng, $p, $st),
                ("f32/Libm", $h) => run_case::<f32, Libm, $h>($rng, $p, $st),
                ("f64/Libm", $h) => run_case::<f64, Libm, $h>($rng, $p, $st),
            )*
            _ => unreachable!(),
        }
    };
}

fn one(seed: u64, long: bool, st: &mut Stats) {
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    for _ in 0..3 {
        rng.next();
    }
    let (p, _) = gen_params(&mut rng, seed, long);
    if std::env::var("FUZZ_VERBOSE").is_ok() {
        eprintln!("{p:?}");
    }
    dispatch!(&mut rng, &p, st, 8, 17, 40, 41, 64, 65, 97, 144, 145, 256);
}

#[test]
fn fuzz_blocks_vs_samples() {
    let cases: u64 = std::env::var("FUZZ_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(2400);
    let base: u64 = std::env::var("FUZZ_BASE").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    let mut st = Stats::default();
    for c in 0..cases {
        let seed = base + c;
        let long = seed % 12 == 0;
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut s2 = Stats::default();
            one(seed, long, &mut s2);
            s2
        }));
        match r {
            Ok(s2) => {
                st.cases += s2.cases;
                st.samples += s2.samples;
                st.events += s2.events;
                st.events_ok += s2.events_ok;
                st.blocks += s2.blocks;
                st.empty_blocks += s2.empty_blocks;
                st.bad_len_checks += s2.bad_len_checks;
                st.bad_inputs += s2.bad_inputs;
                st.predictions += s2.predictions;
            }
            Err(_) => {
                panic!("case seed {seed} failed (see message above); stats so far {st:?}");
            }
        }
    }
    eprintln!("STATS {st:?}");
}

#[test]
fn fuzz_one_seed() {
    if let Ok(s) = std::env::var("FUZZ_SEED") {
        let seed: u64 = s.parse().unwrap();
        let mut st = Stats::default();
        one(seed, seed % 12 == 0, &mut st);
        eprintln!("STATS {st:?}");
    }
}
