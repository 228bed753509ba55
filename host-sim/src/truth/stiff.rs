//! Stiff sliding phases: a velocity-dependent law with a large rate `a` makes the slip speed's
//! equation stiff near v = 0 (relaxation ≈ a·(μ_fast − μ_slow)·N/m2 per second, where the base
//! creeps at a speed ~1/a instead of sticking). Such phases are integrated by the linearly
//! implicit Rodas5 method (Di Marzo 1993, Hairer–Wanner's transformed form: 8 stages, order 5 with
//! an embedded order-4 error estimate, stiffly accurate and L-stable) with the exact Jacobian and
//! the table's time derivative. As for the explicit pair ([`super::integrate`]), a piece is one
//! accepted step and its dense output is one step of length τ from the piece's start.
//!
//! The coefficients are copied as published (some with more digits than an f64 holds).
#![allow(clippy::excessive_precision)]

use super::model::Model;
use super::phase::Direction;
use super::piece::Piece;

const GAMMA: f64 = 0.19;
/// Stage coefficients of stages 1–6 (stages 7 and 8 start from the previous stage's result:
/// their rows are row 6 plus ones on the subdiagonal).
const A: [[f64; 5]; 6] = [
    [0.0; 5],
    [2.0, 0.0, 0.0, 0.0, 0.0],
    [3.040894194418781, 1.041747909077569, 0.0, 0.0, 0.0],
    [
        2.576417536461461,
        1.622083060776640,
        -0.9089668560264532,
        0.0,
        0.0,
    ],
    [
        2.760842080225597,
        1.446624659844071,
        -0.3036980084553738,
        0.2877498600325443,
        0.0,
    ],
    [
        -14.09640773051259,
        6.925207756232704,
        -41.47510893210728,
        2.343771018586405,
        24.13215229196062,
    ],
];
const C: [[f64; 7]; 8] = [
    [0.0; 7],
    [-10.31323885133993, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [
        -21.04823117650003,
        -7.234992135176716,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        32.22751541853323,
        -4.943732386540191,
        19.44922031041879,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        -20.69865579590063,
        -8.816374604402768,
        1.260436877740897,
        -0.7495647613787146,
        0.0,
        0.0,
        0.0,
    ],
    [
        -46.22004352711257,
        -17.49534862857472,
        -289.6389582892057,
        93.60855400400906,
        318.3822534212147,
        0.0,
        0.0,
    ],
    [
        34.20013733472935,
        -14.15535402717690,
        57.82335640988400,
        25.83362985412365,
        1.408950972071624,
        -6.551835421242162,
        0.0,
    ],
    [
        42.57076742291101,
        -13.80770672017997,
        93.98938432427124,
        18.77919633714503,
        -31.58359187223370,
        -6.685968952921985,
        -5.810979938412932,
    ],
];
/// Stage times (fractions of the step).
const CT: [f64; 8] = [
    0.0,
    0.38,
    0.3878509998321533,
    0.4839718937873840,
    0.4570477008819580,
    1.0,
    1.0,
    1.0,
];
/// Coefficients of h·∂f/∂t per stage.
const D: [f64; 8] = [
    GAMMA,
    -0.1823079225333714636,
    -0.319231832186874912,
    0.3449828624725343,
    -0.377417564392089818,
    0.0,
    0.0,
    0.0,
];

type Y = [f64; 4];
type M4 = [[f64; 4]; 4];

impl Model {
    /// ∂f/∂y of the sliding equations ([`super::integrate`]) at slip velocity `v`.
    fn jacobian(&self, s: f64, v: f64) -> M4 {
        // dF/dv = −a·(μ_fast − μ_slow)·N·e^{−a·s·v}.
        let x = (-self.rate * s * v).min(50.0);
        let df = -self.rate * self.mu_drop * self.normal * x.exp();
        let (mp2, m2xp) = (self.mass_ratio * self.p2, self.mass_ratio * self.two_xi_p);
        let r = self.m1 / self.m2;
        [
            [0.0, 1.0, 0.0, 0.0],
            [-mp2, -m2xp, 0.0, -df / self.m2],
            [0.0, 0.0, 0.0, 1.0],
            [r * self.p2, r * self.two_xi_p, 0.0, df / self.m2],
        ]
    }
}

/// Solve (I/(γh) − J)·x = b (Gaussian elimination with partial pivoting; 4×4).
fn solve(mut m: M4, mut b: Y) -> Y {
    for col in 0..4 {
        let piv = (col..4)
            .max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))
            .unwrap_or(col);
        m.swap(col, piv);
        b.swap(col, piv);
        let d = m[col][col];
        let pivot_row = m[col];
        let pivot_b = b[col];
        for (row, rb) in m.iter_mut().zip(b.iter_mut()).skip(col + 1) {
            let f = row[col] / d;
            if f != 0.0 {
                for (x, p) in row.iter_mut().zip(pivot_row.iter()).skip(col) {
                    *x -= f * p;
                }
                *rb -= f * pivot_b;
            }
        }
    }
    let mut x = [0.0; 4];
    for row in (0..4).rev() {
        let mut acc = b[row];
        for k in row + 1..4 {
            acc -= m[row][k] * x[k];
        }
        x[row] = acc / m[row][row];
    }
    x
}

impl Piece {
    /// One Rodas5 step of length `tau` from the piece's initial state, sliding in direction
    /// `dir`: the 5th-order state and the error estimate (the last stage's increment).
    pub(super) fn rodas(&self, m: &Model, dir: Direction, tau: f64) -> (Y, Y) {
        let s = dir.sign();
        let s0 = self.state;
        let y0 = [s0.delta, s0.delta_dot, s0.slip, s0.slip_vel];
        if tau <= 0.0 {
            return (y0, [0.0; 4]);
        }
        let j = m.jacobian(s, y0[3]);
        let mut w = j.map(|row| row.map(|x| -x));
        for (i, row) in w.iter_mut().enumerate() {
            row[i] += 1.0 / (GAMMA * tau);
        }
        // ∂f/∂t: only ẍ2 depends on t (through −ü_g); δ'' does not.
        let ug_dot = self.forcing.accel(self.t0, 0.0).1;
        let ft = [0.0, 0.0, 0.0, -ug_dot];
        let mut k = [[0.0; 4]; 8];
        let mut y = y0;
        for i in 0..8 {
            let mut u = y0;
            if let Some(row) = A.get(i) {
                for (&a, kj) in row.iter().zip(&k).take(i) {
                    for c in 0..4 {
                        u[c] += a * kj[c];
                    }
                }
            } else {
                // Stages 7 and 8 start from the previous stage's result (a_{i,i−1} = 1).
                u = y;
            }
            if i == 5 {
                y = u;
            }
            let ug = self.forcing.accel(self.t0, CT[i] * tau).0;
            let f = m.rhs(s, &u, ug);
            let mut b = [0.0; 4];
            for c in 0..4 {
                b[c] = f[c] + tau * D[i] * ft[c];
                for (jj, kj) in k.iter().enumerate().take(i) {
                    b[c] += C[i][jj] / tau * kj[c];
                }
            }
            k[i] = solve(w, b);
            if i >= 5 {
                // y: the stage-6 point, then + k6, + k7, + k8.
                for c in 0..4 {
                    y[c] += k[i][c];
                }
            }
        }
        (y, k[7])
    }
}
