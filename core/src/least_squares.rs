//! Linear least squares on a stream of rows, for the firmware's f32 ([`PagedNormal`]): the
//! normal equations' products summed in `T` over pages of [`PAGE`] rows and the pages in f64
//! (with a forgetting factor per page), so that long runs lose no precision in f32; solved in
//! f64 by Cholesky, with the formal covariance σ²·S⁻¹.

use crate::math::Real;

/// Rows summed in `T` before they are added to the f64 sums. (128: each page's fold costs
/// the M4F ~150 soft-float instructions per product; at 32 rows the folds took ~20 of the fuse
/// mode's instructions per sample, at 128 ~5. An f32 page of 128 rows rounds to ~1e-5 of its
/// sums at worst; the test `f32_pages_match_f64_on_a_hard_case` measures what that does to a
/// fit.)
pub const PAGE: u32 = 128;

/// A least-squares fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit<const N: usize> {
    /// The parameters.
    pub theta: [f64; N],
    /// Their formal covariance σ²·S⁻¹.
    pub cov: [[f64; N]; N],
    /// Rows (with forgetting).
    pub rows: f64,
}

/// The normal equations of `N` regressors; `K` = N(N+1)/2 + N + 1 products per row (the upper
/// triangle of S, the right-hand side c, the target's square).
#[derive(Debug, Clone)]
pub struct PagedNormal<T, const N: usize, const K: usize> {
    page: [T; K],
    page_rows: u32,
    sums: [f64; K],
    rows: f64,
    added: u32,
    rho_page: f64,
}

impl<T: Real, const N: usize, const K: usize> PagedNormal<T, N, K> {
    const SIZES: () = assert!(K == N * (N + 1) / 2 + N + 1 && N <= MAX_N);
    /// The products' indices in `[φ, t]`, in the sums' order: the upper triangle of S (i ≤ j
    /// < N), then c (φi·t), then t·t.
    const PAIRS: [(usize, usize); K] = pairs::<N, K>();
    /// [`Self::PAIRS`] in bytes (the rescaling's table in the firmware's flash: a quarter).
    const BYTE_PAIRS: [[u8; 2]; K] = {
        let mut out = [[0u8; 2]; K];
        let mut k = 0;
        while k < K {
            out[k] = [Self::PAIRS[k].0 as u8, Self::PAIRS[k].1 as u8];
            k += 1;
        }
        out
    };

    /// Empty normal equations, forgetting `forgetting` per row in (0, 1] (not checked here: the
    /// identifiers that own them check it).
    pub fn new(forgetting: f64) -> Self {
        let () = Self::SIZES;
        Self {
            page: [T::ZERO; K],
            page_rows: 0,
            sums: [0.0; K],
            rows: 0.0,
            added: 0,
            rho_page: (0..PAGE).fold(1.0, |a, _| a * forgetting),
        }
    }

    /// One row: regressors `phi`, target `t`. A row whose squares are not finite (an absurd
    /// sample) is skipped: in the sums it would end the fit for good.
    #[inline(always)]
    pub fn add(&mut self, phi: &[T; N], t: T) {
        // The row's values and target side by side, [φ, t] (built element by element: a zeroed
        // array to fill took a `memclr` call per row); the products in the sums' order
        // ([`Self::PAIRS`]). The firmware is built for size, which unrolls no loop: the sizes in
        // use are written out (~4 instructions a product on the M4F instead of ~13; ~25 of the
        // fuse mode's instructions per sample while sliding), the squares' test too.
        let at = |i: usize| phi.get(i).copied().unwrap_or(t);
        let x: [T; MAX_N + 1] = [at(0), at(1), at(2), at(3), at(4)];
        let squares = match N {
            4 => t * t + x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3],
            3 => t * t + x[0] * x[0] + x[1] * x[1] + x[2] * x[2],
            _ => phi.iter().fold(t * t, |q, &p| q + p * p),
        };
        if !squares.is_finite() {
            return;
        }
        let p = &mut self.page;
        match N {
            4 => products!(p, x; (0, 0), (0, 1), (0, 2), (0, 3), (1, 1), (1, 2), (1, 3), (2, 2),
                (2, 3), (3, 3), (0, 4), (1, 4), (2, 4), (3, 4), (4, 4)),
            3 => products!(p, x; (0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2), (0, 3), (1, 3),
                (2, 3), (3, 3)),
            _ => {
                for (p, &(i, j)) in p.iter_mut().zip(Self::PAIRS.iter()) {
                    *p += x[i] * x[j];
                }
            }
        }
        self.page_rows += 1;
        self.added = self.added.wrapping_add(1);
        if self.page_rows >= PAGE {
            self.fold();
        }
    }

    /// Adds the page to the f64 sums (forgetting the older ones).
    #[inline(never)]
    fn fold(&mut self) {
        for (s, p) in self.sums.iter_mut().zip(self.page.iter_mut()) {
            *s = *s * self.rho_page + p.to_f64();
            *p = T::ZERO;
        }
        self.rows = self.rows * self.rho_page + self.page_rows as f64;
        self.page_rows = 0;
    }

    /// The rows already in, as if their first `scaled` regressors and their targets had been
    /// `c` times what they were (a change of the measurements' units, the other regressors
    /// without units: each product scaled by the factors of its pair). Exact up to the
    /// products' rounding.
    pub fn rescale(&mut self, scaled: usize, c: f32) {
        scale_products(
            &mut self.sums,
            &mut self.page,
            &Self::BYTE_PAIRS,
            (scaled, N),
            c,
        );
    }

    /// Rows ever added (wrapping): a fit changes only when it does.
    pub fn added(&self) -> u32 {
        self.added
    }

    /// Rows, with forgetting.
    pub fn rows(&self) -> f64 {
        self.rows + self.page_rows as f64
    }

    /// The fit of the first `M` regressors (the others taken as 0; `M` = `N`: all of them),
    /// `None` if their normal equations are not positive definite or there are no more rows
    /// than parameters.
    pub fn solve<const M: usize>(&self) -> Option<Fit<M>> {
        self.solve_with::<M>(None)
    }

    /// [`Self::solve`] with the covariance σ²·S⁻¹ of a given residual variance `sigma2` (one
    /// tracked apart: the residual from the sums cancels in f32 when the fit is close).
    pub fn solve_given<const M: usize>(&self, sigma2: f64) -> Option<Fit<M>> {
        self.solve_with::<M>(Some(sigma2))
    }

    fn solve_with<const M: usize>(&self, sigma2: Option<f64>) -> Option<Fit<M>> {
        let mut v = [0.0f64; MAX_K];
        for ((d, &s), p) in v.iter_mut().zip(&self.sums).zip(&self.page) {
            *d = s + p.to_f64();
        }
        let (theta, cov) = solve_packed(&v, N, M, self.rows(), sigma2)?;
        Some(Fit {
            theta: core::array::from_fn(|i| theta[i]),
            cov: core::array::from_fn(|i| core::array::from_fn(|j| cov[i][j])),
            rows: self.rows(),
        })
    }
}

/// The products `x[i]·x[j]` of the pairs given added to `page[0]`, `page[1]`, … in turn,
/// written out (a slot beyond the page is skipped; none is, for the sizes that use it).
macro_rules! products {
    ($page:ident, $x:ident; $(($i:literal, $j:literal)),* $(,)?) => {{
        let mut k = 0usize;
        $(
            if let Some(p) = $page.get_mut(k) {
                *p += $x[$i] * $x[$j];
            }
            k += 1;
        )*
        let _ = k;
    }};
}
use products;

/// Each product of `pairs` (its sum and its page's) scaled by `c` for each of its two indices
/// below `scaled` or equal to `target` (one function for every size: the firmware's flash).
#[cold]
#[inline(never)]
fn scale_products<T: Real>(
    sums: &mut [f64],
    page: &mut [T],
    pairs: &[[u8; 2]],
    (scaled, target): (usize, usize),
    c: f32,
) {
    let f = |i: u8| {
        let i = usize::from(i);
        if i < scaled || i == target {
            f64::from(c)
        } else {
            1.0
        }
    };
    for ((s, p), &[i, j]) in sums.iter_mut().zip(page.iter_mut()).zip(pairs) {
        let k = f(i) * f(j);
        *s *= k;
        *p = *p * T::from_f64(k);
    }
}

/// [`PagedNormal::PAIRS`]: (i, j) for each of the `K` products of `N` regressors and a target
/// (index `N`): S's upper triangle row by row, then c (i, N), then t² (N, N).
const fn pairs<const N: usize, const K: usize>() -> [(usize, usize); K] {
    let mut out = [(0, 0); K];
    let (mut i, mut k) = (0, 0);
    while i < N {
        let mut j = i;
        while j < N {
            if k < K {
                out[k] = (i, j);
            }
            (k, j) = (k + 1, j + 1);
        }
        i += 1;
    }
    i = 0;
    while i <= N {
        if k < K {
            out[k] = (i, N);
        }
        (k, i) = (k + 1, i + 1);
    }
    out
}

/// Largest number of regressors.
pub const MAX_N: usize = 4;
const MAX_K: usize = MAX_N * (MAX_N + 1) / 2 + MAX_N + 1;

/// The fit of the first `m` of `n` regressors from packed sums `v` (one code for every size: the
/// firmware's flash holds it once).
#[inline(never)]
#[allow(clippy::needless_range_loop, clippy::type_complexity)]
fn solve_packed(
    v: &[f64; MAX_K],
    n: usize,
    m: usize,
    rows: f64,
    sigma2: Option<f64>,
) -> Option<([f64; MAX_N], [[f64; MAX_N]; MAX_N])> {
    if m == 0 || m > n || n > MAX_N || rows <= m as f64 {
        return None;
    }
    let tri = |i: usize, j: usize| {
        let (i, j) = (i.min(j), i.max(j));
        i * n - i * (i + 1) / 2 + j
    };
    let c0 = n * (n + 1) / 2;
    let mut s = [[0.0f64; MAX_N]; MAX_N];
    for i in 0..m {
        for j in 0..m {
            s[i][j] = v[tri(i, j)];
        }
    }
    let inv = invert_spd(&s, m)?;
    let mut theta = [0.0f64; MAX_N];
    for i in 0..m {
        theta[i] = (0..m).map(|j| inv[i][j] * v[c0 + j]).sum();
    }
    let fit: f64 = (0..m).map(|i| theta[i] * v[c0 + i]).sum();
    let sigma2 = sigma2.unwrap_or(libm::fmax(v[c0 + n] - fit, 0.0) / (rows - m as f64));
    let mut cov = [[0.0f64; MAX_N]; MAX_N];
    for i in 0..m {
        for j in 0..m {
            cov[i][j] = sigma2 * inv[i][j];
        }
    }
    Some((theta, cov))
}

/// The inverse of a symmetric positive definite matrix by Cholesky (`None` if it is not
/// positive definite to working precision).
#[allow(clippy::needless_range_loop)]
fn invert_spd(a: &[[f64; MAX_N]; MAX_N], n: usize) -> Option<[[f64; MAX_N]; MAX_N]> {
    let mut l = [[0.0f64; MAX_N]; MAX_N];
    for i in 0..n {
        for j in 0..=i {
            let mut sum = a[i][j];
            for k in 0..j {
                sum -= l[i][k] * l[j][k];
            }
            if i == j {
                if sum <= 1e-9 * a[i][i].abs() || !sum.is_finite() {
                    return None;
                }
                l[i][i] = libm::sqrt(sum);
            } else {
                l[i][j] = sum / l[j][j];
            }
        }
    }
    // L⁻¹ (lower), then S⁻¹ = L⁻ᵀ·L⁻¹.
    let mut li = [[0.0f64; MAX_N]; MAX_N];
    for i in 0..n {
        li[i][i] = 1.0 / l[i][i];
        for j in 0..i {
            let mut sum = 0.0;
            for k in j..i {
                sum -= l[i][k] * li[k][j];
            }
            li[i][j] = sum / l[i][i];
        }
    }
    let mut inv = [[0.0f64; MAX_N]; MAX_N];
    for i in 0..n {
        for j in 0..n {
            inv[i][j] = (i.max(j)..n).map(|k| li[k][i] * li[k][j]).sum();
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A known linear model with a deterministic perturbation: the fit against the generating
    /// parameters, and a leading sub-fit.
    #[test]
    fn fits_a_known_linear_model() {
        let mut n = PagedNormal::<f32, 3, 10>::new(1.0);
        let mut m = PagedNormal::<f32, 3, 10>::new(1.0);
        for k in 0..5000 {
            let x = (k as f32 * 0.37).sin();
            let s = if (k / 50) % 2 == 0 { 1.0 } else { -1.0 };
            let e = 1e-3 * (k as f32 * 1.7).cos();
            n.add(&[x, s, 1.0], 0.5 * x + 2.0 * s - 0.3 + e);
            // Only the first two regressors matter: the leading fit.
            m.add(&[x, s, 0.0], 0.5 * x + 2.0 * s + e);
        }
        let f = n.solve::<3>().unwrap();
        assert!((f.theta[0] - 0.5).abs() < 1e-4, "{f:?}");
        assert!((f.theta[1] - 2.0).abs() < 1e-4, "{f:?}");
        assert!((f.theta[2] + 0.3).abs() < 1e-4, "{f:?}");
        assert!(f.cov[0][0] > 0.0 && f.cov[0][0] < 1e-8);
        assert!(m.solve::<3>().is_none(), "a zero regressor: singular");
        let g = m.solve::<2>().unwrap();
        assert!((g.theta[0] - 0.5).abs() < 1e-4 && (g.theta[1] - 2.0).abs() < 1e-4);
        assert_eq!(n.added(), 5000);
    }

    /// The written-out products (N = 3, 4) are the pairs' table's, in its order, bit for bit;
    /// N = 2 takes the table itself.
    #[test]
    fn written_out_products_follow_the_pairs() {
        fn check<const N: usize, const K: usize>() {
            let mut n = PagedNormal::<f32, N, K>::new(1.0);
            let mut want = [0.0f32; K];
            for r in 0..10 {
                let phi: [f32; N] = core::array::from_fn(|i| ((r * 7 + i * 3) as f32).sin());
                let t = (r as f32 * 0.3).cos();
                n.add(&phi, t);
                let x = |i: usize| if i < N { phi[i] } else { t };
                for (w, &(i, j)) in want.iter_mut().zip(PagedNormal::<f32, N, K>::PAIRS.iter()) {
                    *w += x(i) * x(j);
                }
            }
            assert_eq!(n.page.map(f32::to_bits), want.map(f32::to_bits), "N = {N}");
        }
        check::<2, 6>();
        check::<3, 10>();
        check::<4, 15>();
        assert_eq!(
            PagedNormal::<f32, 3, 10>::PAIRS,
            [
                (0, 0),
                (0, 1),
                (0, 2),
                (1, 1),
                (1, 2),
                (2, 2),
                (0, 3),
                (1, 3),
                (2, 3),
                (3, 3)
            ]
        );
    }

    /// Pages of [`PAGE`] rows summed in f32 against the same rows in f64, on the sliding
    /// identification's case made hard: a lightly damped oscillation's block averages at ~110
    /// blocks per period (regressors y1 and y1 − y2 nearly collinear, the target a second
    /// difference ~3e-3 of them), a friction term that changes sign every 2 000 blocks and an
    /// offset, noise of 1e-5 (a lab's accelerometer gives ~3e-3 on such block averages: the
    /// rounding matters more the quieter the rows), 200 000 rows with forgetting. The f64 fit
    /// recovers the generating parameters; the f32 pages agree with it to 8.7e-4 of the
    /// standard deviations (PAGE 32: 2.5e-4), which agree to 5.5e-4 (7.1e-5). (With noise of
    /// 1e-6, 3 000 times below a lab's: 6e-3 and 5.7 %, the residual σ² from the sums
    /// cancelling; with 1e-4: 2.5e-4 and 1.2e-5.)
    #[test]
    fn f32_pages_match_f64_on_a_hard_case() {
        let rho = libm::pow(0.99999, 13.0);
        let mut n32 = PagedNormal::<f32, 4, 15>::new(rho);
        let mut n64 = PagedNormal::<f64, 4, 15>::new(rho);
        let (w, zeta, h) = (2.0 * core::f64::consts::PI * 7.0, 0.05, 1.3e-3);
        let r = libm::exp(-zeta * w * h);
        let c = libm::cos(w * h * libm::sqrt(1.0 - zeta * zeta));
        // y − 2·y1 + y2 = α·y1 + β·(y1 − y2) + γ·s + δ + e.
        let truth = [2.0 * r * c - r * r - 1.0, r * r - 1.0, 1e-3, 1e-4];
        let (mut y1, mut y2) = (1.0f64, 1.0f64);
        for k in 0..200_000u64 {
            let s = if (k / 2000) % 2 == 0 { 1.0 } else { -1.0 };
            let e = 1e-5 * libm::sin(k as f64 * 12.9898) * libm::cos(k as f64 * 78.233);
            let phi = [y1, y1 - y2, s, 1.0];
            let t = truth[0] * y1 + truth[1] * (y1 - y2) + truth[2] * s + truth[3] + e;
            n64.add(&phi, t);
            n32.add(&phi.map(|x| x as f32), t as f32);
            (y1, y2) = (t + 2.0 * y1 - y2, y1);
        }
        let (a, b) = (n32.solve::<4>().unwrap(), n64.solve::<4>().unwrap());
        for (i, &truth) in truth.iter().enumerate() {
            let sd = libm::sqrt(b.cov[i][i]);
            let (d, r) = (
                (a.theta[i] - b.theta[i]).abs() / sd,
                (libm::sqrt(a.cov[i][i]) / sd - 1.0).abs(),
            );
            std::println!(
                "theta[{i}] {:.6e} (f64 {:.6e} ± {sd:.2e}): f32 off by {d:.2e} sd, its sd by {r:.2e}",
                truth,
                b.theta[i]
            );
            assert!((b.theta[i] - truth).abs() < 5.0 * sd, "f64 theta[{i}]");
            assert!(d.is_finite() && d < 2e-3, "theta[{i}]: {d} sd");
            assert!(r.is_finite() && r < 1e-3, "sd[{i}]: {r}");
        }
    }
}
