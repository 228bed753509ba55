//! One-dimensional minimum searches of the detectors' event-time fits: a grid scan, then a
//! golden-section refinement.

/// The best of f on the grid a, a + step, … ≤ b: (t, f(t)).
pub(super) fn grid_min(f: &impl Fn(f32) -> f32, (a, b): (f32, f32), step: f32) -> (f32, f32) {
    let (mut best, mut best_r) = (a, f32::INFINITY);
    let mut t = a;
    while t <= b {
        let r = f(t);
        if r < best_r {
            best_r = r;
            best = t;
        }
        t += step;
    }
    (best, best_r)
}

/// Golden-section search for the minimum of f on [lo, hi] (`iters` steps): the midpoint of the
/// final bracket.
pub(super) fn golden_min(f: &impl Fn(f32) -> f32, (mut lo, mut hi): (f32, f32), iters: u32) -> f32 {
    let gr = 0.618_034f32;
    for _ in 0..iters {
        let (m1, m2) = (hi - gr * (hi - lo), lo + gr * (hi - lo));
        if f(m1) < f(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    0.5 * (lo + hi)
}
