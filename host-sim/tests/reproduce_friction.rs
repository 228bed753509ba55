use host_sim::table_motion::TableMotion;
use host_sim::truth::{simulate, Truth, TruthInput};
use ssvr_core::{FrictionLaw, Structure, StructureParams};
use std::time::Instant;

fn s() -> Structure {
    Structure::new(StructureParams {
        m1_kg: 29.5,
        m2_kg: 1.75,
        natural_frequency_hz: 7.0,
        damping_ratio: 0.05,
        friction_coefficient: 0.2,
        gravity_m_s2: 9.8,
    })
    .unwrap()
}
fn peak(t: &Truth, t0: f64, t1: f64) -> f64 {
    let n = 20000;
    let mut c = t.sampler();
    (0..=n)
        .map(|i| {
            c.sample(t0 + (t1 - t0) * i as f64 / n as f64)
                .map_or(0.0, |x| x.top_accel_m_s2.abs())
        })
        .fold(0.0, f64::max)
}
#[test]
fn explore() {
    let s = s();
    println!(
        "xi p {} slow {} gmu {}",
        s.xi() * s.p(),
        s.slow_rate(),
        s.gmu()
    );
    for period in [0.143, 0.2, 0.3] {
        let table = TableMotion::Harmonic {
            amplitude_m_s2: 2.0,
            period_s: period,
        };
        for a in [10.0, 30.0, 100.0] {
            for r in [1.0, 0.8, 0.6, 0.4] {
                let dur = 40.0;
                let law = if r == 1.0 {
                    FrictionLaw::Coulomb
                } else {
                    FrictionLaw::velocity_dependent(r * 0.2, a, 0.2).unwrap()
                };
                let c = Instant::now();
                let tr = simulate(
                    &TruthInput::new(&s, &table, dur)
                        .with_static_friction(r * 0.2)
                        .with_friction(law),
                )
                .unwrap();
                let el = c.elapsed().as_secs_f64();
                let w = 5.0 * period;
                let ps: Vec<String> = [3.0, 5.0, 10.0, 20.0, 40.0]
                    .iter()
                    .map(|&d: &f64| {
                        let d = (d / period).round() * period;
                        format!("{:.4}", peak(&tr, d - w, d) / s.gmu())
                    })
                    .collect();
                println!(
                    "T {period} a {a} r {r}: {el:.3}s events {} slip {:.4} peaks(3,5,10,20,40) {}",
                    tr.events().len(),
                    tr.max_abs_slip_m(),
                    ps.join(" ")
                );
            }
        }
    }
}
