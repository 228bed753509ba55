//! Closed-form propagation of a stuck phase: the fixed-base drift δ'' + 2ξp δ' + p² δ = −ü_g, exact
//! for an affine table acceleration (polynomial particular solution) and for a sinusoid (Duhamel
//! integral through φ1, exact at resonance), with the small complex arithmetic it needs.

use super::forcing::Forcing;
use super::model::Model;
use super::piece::Piece;

impl Piece {
    /// Exact fixed-base drift δ'' + 2ξp δ' + p² δ = −ü_g from the piece's initial state.
    pub(super) fn stuck_drift(&self, m: &Model, tau: f64) -> (f64, f64) {
        let (alpha, n) = (m.fb_alpha, m.fb_n);
        let e = (-alpha * tau).exp();
        let (sn, cs) = (n * tau).sin_cos();
        let ec = e * cs;
        let es = e * sn / n;
        let (ecp, ecm) = (ec + alpha * es, ec - alpha * es);
        let hom = |y0: f64, v0: f64| (ecp * y0 + es * v0, -m.p2 * es * y0 + ecm * v0);
        let s0 = self.state;
        match self.forcing {
            Forcing::Affine { u0, u1 } => {
                // Particular solution c0 + c1 τ of y'' + 2αy' + p²y = −u0 − u1 τ.
                let c1 = -u1 / m.p2;
                let c0 = (-u0 - 2.0 * alpha * c1) / m.p2;
                let (y, v) = hom(s0.delta - c0, s0.delta_dot - c1);
                (y + c0 + c1 * tau, v + c1)
            }
            Forcing::Harmonic { amp, omega, phase } => {
                let (y, v) = hom(s0.delta, s0.delta_dot);
                if tau == 0.0 {
                    return (y, v);
                }
                // Zero-state response to q(u) = −amp sin(ω(t0+u)) = Im(Q e^{iωu}), Q = −amp e^{iωt0}:
                // ∫₀^τ h(τ−u) e^{iωu} du with h(s) = (e^{μ1 s} − e^{μ2 s})/(2in), and
                // ∫₀^τ e^{μ(τ−u)} e^{iωu} du = τ e^{iωτ} φ1((μ − iω)τ) (exact at resonance).
                let mu1 = Cx::new(-alpha, n);
                let mu2 = Cx::new(-alpha, -n);
                let io = Cx::new(0.0, omega);
                let rot = Cx::cis(omega * tau).scale(tau);
                let j1 = rot.mul(phi1(mu1.sub(io).scale(tau)));
                let j2 = rot.mul(phi1(mu2.sub(io).scale(tau)));
                let q = Cx::cis(omega * self.t0 - phase).scale(-amp);
                let inv = Cx::new(0.0, -0.5 / n);
                let yf = q.mul(j1.sub(j2)).mul(inv).im;
                let vf = q.mul(mu1.mul(j1).sub(mu2.mul(j2))).mul(inv).im;
                (y + yf, v + vf)
            }
        }
    }
}

/// A complex number (for the exact stuck response to a sinusoid).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Cx {
    re: f64,
    im: f64,
}

impl Cx {
    const fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }
    fn cis(theta: f64) -> Self {
        let (s, c) = theta.sin_cos();
        Self::new(c, s)
    }
    fn add(self, o: Self) -> Self {
        Self::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: Self) -> Self {
        Self::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: Self) -> Self {
        Self::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn scale(self, k: f64) -> Self {
        Self::new(self.re * k, self.im * k)
    }
    fn div(self, o: Self) -> Self {
        // Smith's algorithm (no overflow of |o|²).
        if o.re.abs() >= o.im.abs() {
            let r = o.im / o.re;
            let d = o.re + o.im * r;
            Self::new((self.re + self.im * r) / d, (self.im - self.re * r) / d)
        } else {
            let r = o.re / o.im;
            let d = o.re * r + o.im;
            Self::new((self.re * r + self.im) / d, (self.im * r - self.re) / d)
        }
    }
    fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }
}

/// φ1(z) = (eᶻ − 1)/z, exact near 0 (series) and through a cancellation-free eᶻ − 1 elsewhere.
fn phi1(z: Cx) -> Cx {
    if z.abs() < 0.5 {
        // 1 + z/2 (1 + z/3 (1 + …)): Σ z^k/(k+1)!, truncated where 0.5^21/22! < 1e-27.
        let mut acc = Cx::new(1.0, 0.0);
        for k in (1..=20).rev() {
            acc = Cx::new(1.0, 0.0).add(acc.mul(z).scale(1.0 / (k as f64 + 1.0)));
        }
        acc
    } else {
        let (s, c) = z.im.sin_cos();
        let half = (0.5 * z.im).sin();
        let em1 = Cx::new(z.re.exp_m1() * c - 2.0 * half * half, z.re.exp() * s);
        em1.div(z)
    }
}
