//! Host benchmarks: ns/sample of the recursion (f32, f64, libm and micromath at reversals) and of
//! the closed form with 10, 10^3 and 10^4 past reversals (undamped: every term is kept).
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use ssvr_core::closed_form::duhamel::{DuhamelClosedForm, ReversalTrain};
use ssvr_core::recursion::{Estimator32, Estimator32Libm, Estimator32Micromath, Estimator64};
use ssvr_core::{Structure, StructureParams};

fn table1(xi: f64) -> Structure {
    Structure::new(StructureParams {
        m1_kg: 29.5,
        m2_kg: 1.75,
        natural_frequency_hz: 7.0,
        damping_ratio: xi,
        friction_coefficient: 0.2,
        gravity_m_s2: 9.80665,
    })
    .unwrap()
}

fn recursion(c: &mut Criterion) {
    let s = table1(0.05);
    const N: usize = 4096;
    let mut g = c.benchmark_group("recursion_steady_state");
    g.throughput(Throughput::Elements(N as u64));
    let mut e32 = Estimator32::new(&s, 1e4).unwrap();
    e32.push_reversal(1.0, 0.3).unwrap();
    let mut e64 = Estimator64::new(&s, 1e4).unwrap();
    e64.push_reversal(1.0, 0.3).unwrap();
    g.bench_function("f32_update", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for _ in 0..N {
                acc += e32.update();
            }
            black_box(acc)
        })
    });
    g.bench_function("f64_update", |b| {
        b.iter(|| {
            let mut acc = 0.0f64;
            for _ in 0..N {
                acc += e64.update();
            }
            black_box(acc)
        })
    });
    let mut buf32 = vec![0.0f32; N];
    g.bench_function("f32_update_block", |b| {
        b.iter(|| {
            e32.update_block(&mut buf32);
            black_box(buf32[N - 1])
        })
    });
    let mut buf64 = vec![0.0f64; N];
    g.bench_function("f64_update_block", |b| {
        b.iter(|| {
            e64.update_block(&mut buf64);
            black_box(buf64[N - 1])
        })
    });
    g.finish();

    let mut g = c.benchmark_group("recursion_reversal");
    g.throughput(Throughput::Elements(1));
    let mut level = 1.0f32;
    g.bench_function("f32_poly_reversal_plus_update", |b| {
        b.iter(|| {
            level = -level;
            e32.push_reversal(level, black_box(0.37)).unwrap();
            black_box(e32.update())
        })
    });
    let mut el = Estimator32Libm::new(&s, 1e4).unwrap();
    g.bench_function("f32_libm_reversal_plus_update", |b| {
        b.iter(|| {
            level = -level;
            el.push_reversal(level, black_box(0.37)).unwrap();
            black_box(el.update())
        })
    });
    let mut em = Estimator32Micromath::new(&s, 1e4).unwrap();
    g.bench_function("f32_micromath_reversal_plus_update", |b| {
        b.iter(|| {
            level = -level;
            em.push_reversal(level, black_box(0.37)).unwrap();
            black_box(em.update())
        })
    });
    let mut l64 = 1.0f64;
    g.bench_function("f64_libm_reversal_plus_update", |b| {
        b.iter(|| {
            l64 = -l64;
            e64.push_reversal(l64, black_box(0.37)).unwrap();
            black_box(e64.update())
        })
    });
    g.finish();
}

fn closed_form(c: &mut Criterion) {
    let s = table1(0.0);
    let cf = DuhamelClosedForm::new(&s);
    let mut g = c.benchmark_group("closed_form_per_sample");
    g.throughput(Throughput::Elements(1));
    for past in [10usize, 1_000, 10_000] {
        let half = 0.0715;
        let train = ReversalTrain::Periodic {
            first_s: 0.0,
            half_period_s: half,
            initial_sign: 1.0,
        };
        let t = (past as f64 - 0.5) * half;
        g.bench_with_input(BenchmarkId::from_parameter(past), &t, |b, &t| {
            b.iter(|| black_box(cf.accel(&train, black_box(t))))
        });
    }
    g.finish();
}

criterion_group!(benches, recursion, closed_form);
criterion_main!(benches);
