//! Event location on a piece: the event function (breakaway when stuck, stop when sliding) is
//! walked on a grid ([`Walker`]), crossings hidden between grid points are found through the sign
//! of its derivative, and roots are refined by Brent's method ([`scan`]).

use super::model::Model;
use super::phase::Phase;
use super::piece::Piece;
use super::roots::{brent, time_tol};

/// The first τ in (lo, hi] where the event function becomes > 0, given e(lo) ≤ 0 < e(hi): the
/// boundary between the sets {e ≤ 0} and {e > 0} (values ≤ 0 are mapped below zero so that an exact
/// zero at `lo` does not end the search there).
fn locate(piece: &Piece, m: &Model, lo: f64, elo: f64, hi: f64, ehi: f64) -> f64 {
    if elo > 0.0 {
        return lo;
    }
    let g = |e: f64| {
        if e > 0.0 {
            e
        } else {
            e.min(-f64::MIN_POSITIVE)
        }
    };
    let tol = time_tol(piece.t0, hi);
    let (b, fb, c, _) = brent(|x| g(piece.event_fn(m, x).0), lo, g(elo), hi, g(ehi), tol);
    if fb > 0.0 {
        b
    } else {
        c
    }
}

/// The extremum of the event function between a and b, where its derivative changes sign.
fn extremum(piece: &Piece, m: &Model, a: f64, da: f64, b: f64, db: f64) -> f64 {
    let tol = time_tol(piece.t0, b);
    brent(|x| piece.event_fn(m, x).1, a, da, b, db, tol).0
}

/// Result of scanning a piece for its first event.
pub(super) struct Scan {
    /// Local time of the event, if one happens on the piece.
    pub(super) event: Option<f64>,
    /// Whether the event function has been clearly negative (soft starts become armed).
    pub(super) armed: bool,
}

/// Walks the event function of one piece forward in time.
///
/// Armed: e ≤ 0 at the current point; the event is the first crossing to e > 0 (a crossing between
/// grid points shows as e > 0 at the next point, or as a maximum above 0 where e' changes sign).
/// Unarmed (soft start right after a transition, e ≈ 0): the walk waits until e < −tol; a clear
/// excursion e > tol before that is an event (the transition went the other way), and excursions
/// within ±tol are rounding. Unarmed stretches are walked on a fine sub-grid, geometric near the
/// start (a transition with e = e' = 0 leaves only quadratically).
struct Walker<'a> {
    piece: &'a Piece,
    m: &'a Model,
    tol: f64,
    armed: bool,
    ta: f64,
    ea: f64,
    da: f64,
}

impl Walker<'_> {
    fn ev(&self, x: f64) -> (f64, f64) {
        self.piece.event_fn(self.m, x)
    }

    /// Walk to the grid point tb; `Some(τ)` at the first event.
    fn step(&mut self, tb: f64) -> Option<f64> {
        if !self.armed {
            let (ta, w) = (self.ta, tb - self.ta);
            let geometric = (7..=40).rev().map(|k| ta + w * 0.5f64.powi(k));
            let uniform = (1..=64).map(|j| ta + w * (j as f64 / 64.0));
            for x in geometric.chain(uniform) {
                if x <= self.ta || x > tb {
                    continue;
                }
                let (e, d) = self.ev(x);
                if let Some(hit) = self.advance(x, e, d) {
                    return Some(hit);
                }
            }
            return None;
        }
        let (eb, db) = self.ev(tb);
        self.advance(tb, eb, db)
    }

    fn advance(&mut self, tb: f64, eb: f64, db: f64) -> Option<f64> {
        let (ta, ea, da) = (self.ta, self.ea, self.da);
        (self.ta, self.ea, self.da) = (tb, eb, db);
        let (piece, m) = (self.piece, self.m);
        if self.armed {
            if eb > 0.0 {
                return Some(locate(piece, m, ta, ea, tb, eb));
            }
            if da > 0.0 && db < 0.0 {
                let tm = extremum(piece, m, ta, da, tb, db);
                let em = self.ev(tm).0;
                if em > 0.0 {
                    return Some(locate(piece, m, ta, ea, tm, em));
                }
            }
            return None;
        }
        let mut peak = (tb, eb);
        if da > 0.0 && db < 0.0 {
            let tm = extremum(piece, m, ta, da, tb, db);
            let em = self.ev(tm).0;
            if em > peak.1 {
                peak = (tm, em);
            }
        }
        if peak.1 > self.tol {
            return Some(if ea <= 0.0 {
                locate(piece, m, ta, ea, peak.0, peak.1)
            } else {
                ta
            });
        }
        if eb < -self.tol {
            self.armed = true;
        }
        None
    }
}

/// Find the first event on a piece of length `len`. `soft`: the piece starts right at a transition
/// (event function ≈ 0), so the walk starts unarmed.
/// `age0`: time from the last transition to the piece start (sets the grid, see [`Model::grid_step`]).
pub(super) fn scan(piece: &Piece, m: &Model, len: f64, soft: bool, age0: f64) -> Scan {
    let tol = if piece.phase == Phase::Stuck {
        m.tol_f
    } else {
        m.tol_v
    };
    let (e0, d0) = piece.event_fn(m, 0.0);
    if !soft && e0 > 0.0 {
        // Already beyond the threshold at the start (a jump of the table acceleration).
        return Scan {
            event: Some(0.0),
            armed: true,
        };
    }
    let mut w = Walker {
        piece,
        m,
        tol,
        armed: !soft || e0 < -tol,
        ta: 0.0,
        ea: e0,
        da: d0,
    };
    loop {
        let tb = (w.ta + m.grid_step(piece.phase, age0 + w.ta)).min(len);
        if let Some(hit) = w.step(tb) {
            return Scan {
                event: Some(hit),
                armed: true,
            };
        }
        if tb >= len {
            return Scan {
                event: None,
                armed: w.armed,
            };
        }
    }
}
