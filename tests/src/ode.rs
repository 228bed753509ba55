//! An independent reference solution of the paper's equations of motion (1)-(2), for checking the
//! closed forms of `ssvr-core` (issue 2).
//!
//! The two masses are integrated in **absolute coordinates** y = [u1, u̇1, u2, u̇2]:
//!
//! ```text
//! m1 ü1 + C(u̇1 − u̇2) + K(u1 − u2) = 0          (1)
//! m2 ü2 + C(u̇2 − u̇1) + K(u2 − u1) = F(t)       (2)
//! ```
//!
//! with K = m1 p², C = 2 m1 p ξ (eq 11-12) and a prescribed piecewise-constant friction force
//! F(t) = F0·s(t), F0 = μ(m1 + m2)g. With this sign a step to F = +F0 drives ü1 → +gμ (the physics
//! notes' eq 25 form δ'' + 2Mpξδ' + Mp²δ = −F/m2). The top-mass acceleration ü1 is read from the state
//! through eq (1).
//!
//! The integrator is the Dormand–Prince 8(5,3) embedded Runge–Kutta pair (Hairer, Nørsett & Wanner,
//! *Solving ODEs I*, DOP853) with its 5th/3rd-order blended error estimate, written here from the
//! published coefficients. The force is constant between its discontinuities, so the integration runs
//! segment by segment: every step ends exactly on the next discontinuity or requested output time,
//! and the step size is restarted after each discontinuity. Nothing here calls `ssvr-core`: only the
//! raw [`StructureParams`] are read.
//!
//! The error of a step is measured on the four absolute components **and** on the relative motion
//! δ = u1 − u2, δ̇ = u̇1 − u̇2, each against `abs·scale + rel·|value|`, with the physical scales
//! L = gμ/p² (the static relative displacement under F0) and L·ω0/max(1, 2ζ) (ω0 = p√M, ζ = √M·ξ:
//! a velocity error of that size moves ü1 = −(Cδ̇ + Kδ)/m1 by at most gμ). The absolute
//! displacements can drift far beyond L while δ, which alone sets ü1, stays of order L; controlling
//! δ directly keeps ü1 accurate to the tolerance relative to gμ.

use ssvr_core::StructureParams;

/// State in absolute coordinates: [u1, u̇1, u2, u̇2] (m, m/s).
pub type State = [f64; 4];

/// A discontinuity of the prescribed friction: from `time_s` on, F = `level`·F0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceStep {
    /// Time of the change (s).
    pub time_s: f64,
    /// Friction level after it, in units of F0 = μ(m1 + m2)g.
    pub level: f64,
}

/// Error tolerance of the integrator (see the module docs for the scales).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// Relative tolerance.
    pub rel: f64,
    /// Absolute tolerance, in units of the physical scales L and L·ω0.
    pub abs: f64,
}

impl Tolerance {
    /// 1e-12 relative and absolute.
    pub const TIGHT: Tolerance = Tolerance {
        rel: 1e-12,
        abs: 1e-12,
    };
    /// 1e-13 relative and absolute: for undamped runs, whose global error grows with time.
    pub const REFERENCE: Tolerance = Tolerance {
        rel: 1e-13,
        abs: 1e-13,
    };
}

/// The solution at the requested output times.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// State at each output time.
    pub states: Vec<State>,
    /// Top-mass absolute acceleration ü1 (m/s²) at each output time, from eq (1).
    pub top_accel: Vec<f64>,
    /// Accepted steps.
    pub accepted_steps: usize,
    /// Rejected steps.
    pub rejected_steps: usize,
}

/// The two-mass model of Fig. 1 with its raw physical constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoMassModel {
    /// Top mass m1 (kg).
    pub m1: f64,
    /// Base mass m2 (kg).
    pub m2: f64,
    /// Storey stiffness K = m1 p² (N/m).
    pub k: f64,
    /// Storey damping C = 2 m1 p ξ (N·s/m).
    pub c: f64,
    /// Friction force amplitude F0 = μ(m1 + m2)g (N).
    pub f0: f64,
    /// Length scale L = gμ/p² (m) of the error control.
    pub length_scale: f64,
    /// Velocity scale L·ω0/max(1, 2ζ) (m/s) of the error control, ζ = √M·ξ.
    pub velocity_scale: f64,
    /// An upper bound on the modulus of the system's eigenvalues (1/s), for the first step size.
    pub rate_bound: f64,
}

/// Hard cap on the number of step attempts of one solve.
const MAX_ATTEMPTS: usize = 50_000_000;

impl TwoMassModel {
    /// The model of a structure, from its raw parameters only.
    pub fn new(params: &StructureParams) -> Self {
        let (m1, m2) = (params.m1_kg, params.m2_kg);
        let p = 2.0 * std::f64::consts::PI * params.natural_frequency_hz;
        let k = m1 * p * p;
        let c = 2.0 * m1 * p * params.damping_ratio;
        let gmu = params.gravity_m_s2 * params.friction_coefficient;
        let f0 = gmu * (m1 + m2);
        let inv_mass = 1.0 / m1 + 1.0 / m2;
        let omega0 = (k * inv_mass).sqrt();
        let length_scale = gmu / (p * p);
        Self {
            m1,
            m2,
            k,
            c,
            f0,
            length_scale,
            // ü1 = −(C δ̇ + K δ)/m1: a relative velocity error of L·ω0 moves ü1 by 2ζ·gμ, so the
            // velocity scale is divided by max(1, 2ζ) (2ζ = C(1/m1 + 1/m2)/ω0).
            velocity_scale: length_scale * omega0 / (c * inv_mass / omega0).max(1.0),
            // Eigenvalues of the relative motion solve s² + C(1/m1+1/m2)s + K(1/m1+1/m2) = 0, so
            // |s| ≤ C(1/m1+1/m2) + ω0; the rigid-body mode has s = 0.
            rate_bound: c * inv_mass + omega0,
        }
    }

    /// Top-mass absolute acceleration from eq (1): ü1 = −[C(u̇1 − u̇2) + K(u1 − u2)]/m1.
    pub fn top_accel(&self, y: &State) -> f64 {
        -(self.c * (y[1] - y[3]) + self.k * (y[0] - y[2])) / self.m1
    }

    /// Right-hand side of (1)-(2) with F = level·F0.
    pub fn derivative(&self, level: f64, y: &State) -> State {
        let spring_damper = self.c * (y[1] - y[3]) + self.k * (y[0] - y[2]);
        [
            y[1],
            -spring_damper / self.m1,
            y[3],
            (level * self.f0 + spring_damper) / self.m2,
        ]
    }

    /// Integrate from state `y0` at time `t0` (friction level before the first step: 0; steps at or
    /// before `t0` apply from `t0`) and return the solution at `outputs` (non-decreasing, ≥ `t0`).
    /// `steps` must have strictly increasing times.
    ///
    /// # Panics
    /// On unsorted inputs or if the step count explodes (test-support code).
    pub fn solve(
        &self,
        y0: State,
        t0: f64,
        steps: &[ForceStep],
        outputs: &[f64],
        tol: Tolerance,
    ) -> Solution {
        assert!(
            steps.windows(2).all(|w| w[0].time_s < w[1].time_s),
            "force steps must be strictly increasing"
        );
        assert!(
            outputs.windows(2).all(|w| w[0] <= w[1]),
            "outputs must be sorted"
        );
        assert!(
            outputs.iter().all(|&t| t >= t0),
            "outputs must not precede t0"
        );
        let mut next_step = steps.partition_point(|s| s.time_s <= t0);
        let mut level = next_step.checked_sub(1).map_or(0.0, |j| steps[j].level);
        let h_start = 0.05 / self.rate_bound;
        let mut sol = Solution {
            states: Vec::with_capacity(outputs.len()),
            top_accel: Vec::with_capacity(outputs.len()),
            accepted_steps: 0,
            rejected_steps: 0,
        };
        let (mut t, mut y) = (t0, y0);
        let mut h_nat = h_start;
        let mut out = 0usize;
        while out < outputs.len() {
            let seg_end = steps.get(next_step).map_or(f64::INFINITY, |s| s.time_s);
            let target = outputs[out].min(seg_end);
            while t < target {
                let remaining = target - t;
                let clipped = h_nat >= remaining;
                let h = if clipped { remaining } else { h_nat };
                let (y_new, err) = self.dop853_step(level, &y, h, tol);
                if !err.is_finite() {
                    // Overflowed trial step: retry much smaller.
                    h_nat = h * 0.1;
                    sol.rejected_steps += 1;
                } else {
                    let fac = if err == 0.0 {
                        5.0
                    } else {
                        (0.9 * err.powf(-1.0 / 8.0)).clamp(0.2, 5.0)
                    };
                    if err <= 1.0 {
                        y = y_new;
                        t = if clipped { target } else { t + h };
                        sol.accepted_steps += 1;
                        // A step shortened to land on a target must not shrink the natural step.
                        h_nat = if clipped { h_nat.max(h * fac) } else { h * fac };
                    } else {
                        h_nat = h * fac.min(1.0);
                        sol.rejected_steps += 1;
                    }
                }
                assert!(
                    sol.accepted_steps + sol.rejected_steps < MAX_ATTEMPTS,
                    "integrator did not progress (t = {t})"
                );
            }
            while out < outputs.len() && outputs[out] <= t {
                sol.states.push(y);
                sol.top_accel.push(self.top_accel(&y));
                out += 1;
            }
            if seg_end <= t {
                // Friction discontinuity: switch the level and restart the step size.
                level = steps[next_step].level;
                next_step += 1;
                h_nat = h_nat.min(h_start);
            }
        }
        sol
    }

    /// One DOP853 step of size h from y: the 8th-order solution and the scaled error norm
    /// (≤ 1 accepts), Hairer's blend of the 5th- and 3rd-order estimates.
    fn dop853_step(&self, level: f64, y: &State, h: f64, tol: Tolerance) -> (State, f64) {
        let mut k = [[0.0f64; 4]; 12];
        k[0] = self.derivative(level, y);
        for i in 1..12 {
            let mut yi = *y;
            for (j, kj) in k.iter().enumerate().take(i) {
                let a = A[i][j];
                if a != 0.0 {
                    for (yc, kc) in yi.iter_mut().zip(kj) {
                        *yc += h * a * kc;
                    }
                }
            }
            k[i] = self.derivative(level, &yi);
        }
        let mut y_new = *y;
        let mut e5 = [0.0f64; 4];
        let mut e3 = [0.0f64; 4];
        for i in 0..12 {
            for c in 0..4 {
                y_new[c] += h * B[i] * k[i][c];
                e5[c] += E5[i] * k[i][c];
                e3[c] += (B[i] - BHH[i]) * k[i][c];
            }
        }
        // Error components: the four absolute ones and the relative motion (δ, δ̇).
        let scales = [
            self.length_scale,
            self.velocity_scale,
            self.length_scale,
            self.velocity_scale,
            self.length_scale,
            self.velocity_scale,
        ];
        let old = [y[0], y[1], y[2], y[3], y[0] - y[2], y[1] - y[3]];
        let new = [
            y_new[0],
            y_new[1],
            y_new[2],
            y_new[3],
            y_new[0] - y_new[2],
            y_new[1] - y_new[3],
        ];
        let err5 = [e5[0], e5[1], e5[2], e5[3], e5[0] - e5[2], e5[1] - e5[3]];
        let err3 = [e3[0], e3[1], e3[2], e3[3], e3[0] - e3[2], e3[1] - e3[3]];
        let (mut s5, mut s3) = (0.0f64, 0.0f64);
        for c in 0..6 {
            let sk = tol.abs * scales[c] + tol.rel * old[c].abs().max(new[c].abs());
            s5 += (err5[c] / sk).powi(2);
            s3 += (err3[c] / sk).powi(2);
        }
        let deno = s5 + 0.01 * s3;
        let err = if deno > 0.0 {
            h.abs() * s5 / (6.0 * deno).sqrt()
        } else {
            0.0
        };
        (y_new, err)
    }
}

// ---- Dormand–Prince 8(5,3) coefficients (Hairer's DOP853), stages 1..12 as indices 0..11. ----
// They keep the published 30 digits (rounded by the compiler) so that they can be compared with the
// source digit by digit; the order-condition unit test below checks them.

/// Nodes c_i.
#[allow(clippy::excessive_precision)]
pub const C: [f64; 12] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510e+00,
    0.281649658092772603273242802490e+00,
    0.333333333333333333333333333333e+00,
    0.25e+00,
    0.307692307692307692307692307692e+00,
    0.651282051282051282051282051282e+00,
    0.6e+00,
    0.857142857142857142857142857142e+00,
    1.0,
];

/// Runge–Kutta matrix a_ij (row i, column j < i).
#[allow(clippy::excessive_precision)]
pub const A: [[f64; 12]; 12] = {
    let mut a = [[0.0f64; 12]; 12];
    a[1][0] = 5.26001519587677318785587544488e-2;
    a[2][0] = 1.97250569845378994544595329183e-2;
    a[2][1] = 5.91751709536136983633785987549e-2;
    a[3][0] = 2.95875854768068491816892993775e-2;
    a[3][2] = 8.87627564304205475450678981324e-2;
    a[4][0] = 2.41365134159266685502369798665e-1;
    a[4][2] = -8.84549479328286085344864962717e-1;
    a[4][3] = 9.24834003261792003115737966543e-1;
    a[5][0] = 3.7037037037037037037037037037e-2;
    a[5][3] = 1.70828608729473871279604482173e-1;
    a[5][4] = 1.25467687566822425016691814123e-1;
    a[6][0] = 3.7109375e-2;
    a[6][3] = 1.70252211019544039314978060272e-1;
    a[6][4] = 6.02165389804559606850219397283e-2;
    a[6][5] = -1.7578125e-2;
    a[7][0] = 3.70920001185047927108779319836e-2;
    a[7][3] = 1.70383925712239993810214054705e-1;
    a[7][4] = 1.07262030446373284651809199168e-1;
    a[7][5] = -1.53194377486244017527936158236e-2;
    a[7][6] = 8.27378916381402288758473766002e-3;
    a[8][0] = 6.24110958716075717114429577812e-1;
    a[8][3] = -3.36089262944694129406857109825e0;
    a[8][4] = -8.68219346841726006818189891453e-1;
    a[8][5] = 2.75920996994467083049415600797e1;
    a[8][6] = 2.01540675504778934086186788979e1;
    a[8][7] = -4.34898841810699588477366255144e1;
    a[9][0] = 4.77662536438264365890433908527e-1;
    a[9][3] = -2.48811461997166764192642586468e0;
    a[9][4] = -5.90290826836842996371446475743e-1;
    a[9][5] = 2.12300514481811942347288949897e1;
    a[9][6] = 1.52792336328824235832596922938e1;
    a[9][7] = -3.32882109689848629194453265587e1;
    a[9][8] = -2.03312017085086261358222928593e-2;
    a[10][0] = -9.3714243008598732571704021658e-1;
    a[10][3] = 5.18637242884406370830023853209e0;
    a[10][4] = 1.09143734899672957818500254654e0;
    a[10][5] = -8.14978701074692612513997267357e0;
    a[10][6] = -1.85200656599969598641566180701e1;
    a[10][7] = 2.27394870993505042818970056734e1;
    a[10][8] = 2.49360555267965238987089396762e0;
    a[10][9] = -3.0467644718982195003823669022e0;
    a[11][0] = 2.27331014751653820792359768449e0;
    a[11][3] = -1.05344954667372501984066689879e1;
    a[11][4] = -2.00087205822486249909675718444e0;
    a[11][5] = -1.79589318631187989172765950534e1;
    a[11][6] = 2.79488845294199600508499808837e1;
    a[11][7] = -2.85899827713502369474065508674e0;
    a[11][8] = -8.87285693353062954433549289258e0;
    a[11][9] = 1.23605671757943030647266201528e1;
    a[11][10] = 6.43392746015763530355970484046e-1;
    a
};

/// Weights b_i of the 8th-order solution.
#[allow(clippy::excessive_precision)]
pub const B: [f64; 12] = [
    5.42937341165687622380535766363e-2,
    0.0,
    0.0,
    0.0,
    0.0,
    4.45031289275240888144113950566e0,
    1.89151789931450038304281599044e0,
    -5.8012039600105847814672114227e0,
    3.1116436695781989440891606237e-1,
    -1.52160949662516078556178806805e-1,
    2.01365400804030348374776537501e-1,
    4.47106157277725905176885569043e-2,
];

/// Weights of the 3rd-order embedded solution (the error estimate uses B − BHH).
#[allow(clippy::excessive_precision)]
pub const BHH: [f64; 12] = [
    0.244094488188976377952755905512e+00,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.733846688281611857341361741547e+00,
    0.0,
    0.0,
    0.220588235294117647058823529412e-01,
];

/// The 5th-order error estimate weights.
#[allow(clippy::excessive_precision)]
pub const E5: [f64; 12] = [
    0.1312004499419488073250102996e-01,
    0.0,
    0.0,
    0.0,
    0.0,
    -0.1225156446376204440720569753e+01,
    -0.4957589496572501915214079952e+00,
    0.1664377182454986536961530415e+01,
    -0.3503288487499736816886487290e+00,
    0.3341791187130174790297318841e+00,
    0.8192320648511571246570742613e-01,
    -0.2235530786388629525884427845e-01,
];

#[cfg(test)]
mod tests {
    use super::*;

    /// The coefficients satisfy the consistency and quadrature order conditions to order 8, so a
    /// typing error in the table would show here.
    #[test]
    fn dop853_coefficients_satisfy_order_conditions() {
        for i in 0..12 {
            let row: f64 = A[i].iter().sum();
            assert!((row - C[i]).abs() < 1e-14, "row {i}: {row} vs c = {}", C[i]);
        }
        // Σ b_i c_i^{q−1} = 1/q, q = 1..8.
        for q in 1..=8 {
            let s: f64 = (0..12).map(|i| B[i] * C[i].powi(q - 1)).sum();
            assert!((s - 1.0 / q as f64).abs() < 1e-14, "q = {q}: {s}");
        }
        // Σ b_i a_ij c_j^{q−1} = 1/(q(q+1)), q = 1..7.
        for q in 1..=7 {
            let s: f64 = (0..12)
                .map(|i| B[i] * (0..12).map(|j| A[i][j] * C[j].powi(q - 1)).sum::<f64>())
                .sum();
            let want = 1.0 / (q * (q + 1)) as f64;
            assert!((s - want).abs() < 1e-13, "q = {q}: {s} vs {want}");
        }
        // The 3rd-order embedded weights are consistent to order 3; E5 annihilates low orders.
        for q in 1..=3 {
            let s: f64 = (0..12).map(|i| BHH[i] * C[i].powi(q - 1)).sum();
            assert!((s - 1.0 / q as f64).abs() < 1e-14, "bhh q = {q}: {s}");
        }
        for q in 1..=5 {
            let s: f64 = (0..12).map(|i| E5[i] * C[i].powi(q - 1)).sum();
            assert!(s.abs() < 1e-13, "e5 q = {q}: {s}");
        }
    }

    /// y' = λy over one unit: error falls as h⁸ when the step is halved (fixed steps).
    #[test]
    fn dop853_is_eighth_order() {
        let lambda = -1.3f64;
        let run = |n: usize| {
            let h = 1.0 / n as f64;
            let mut y = 1.0f64;
            for _ in 0..n {
                let mut k = [0.0f64; 12];
                for i in 0..12 {
                    let yi = y + h * (0..i).map(|j| A[i][j] * k[j]).sum::<f64>();
                    k[i] = lambda * yi;
                }
                y += h * (0..12).map(|i| B[i] * k[i]).sum::<f64>();
            }
            (y - lambda.exp()).abs()
        };
        let (e1, e2) = (run(2), run(4));
        let order = (e1 / e2).log2();
        assert!(order > 7.5, "observed order {order} ({e1:e}, {e2:e})");
    }
}
