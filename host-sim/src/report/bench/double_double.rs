//! A double-double reference of the undamped closed-form sum (the `long-train` scene), to measure
//! the rounding of the f64 closed form itself.

use ssvr_core::Reversal;

/// a + b exactly, as an unevaluated sum (s, error) (Knuth's two-sum).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// ü1(t) of an undamped structure (ecm(τ) = cos nτ) with every term in double-double: the
/// arguments t − t_j and n·(t − t_j) and the reduction mod 2π are carried to ~1e-30 relative, so the
/// only rounding left is that of cos and of the final sum (~1e-16 per term).
pub(super) fn dd_undamped(n: f64, gmu: f64, train: &[Reversal], t: f64) -> f64 {
    const TWO_PI_HI: f64 = std::f64::consts::TAU;
    const TWO_PI_LO: f64 = 2.449_293_598_294_706_4e-16;
    let last = train.partition_point(|r| r.time_s <= t);
    if last == 0 {
        return 0.0;
    }
    let level = train[last - 1].level;
    let (mut sum, mut comp) = (0.0f64, 0.0f64);
    let mut prev_level = 0.0;
    for r in &train[..last] {
        let jump = r.level - prev_level;
        prev_level = r.level;
        let (th, tl) = two_sum(t, -r.time_s);
        let ph = n * th;
        let pl = n.mul_add(th, -ph) + n * tl;
        let k = (ph / TWO_PI_HI).round();
        let kh = k * TWO_PI_HI;
        let kl = k.mul_add(TWO_PI_HI, -kh);
        let rh = ph - kh; // exact (Sterbenz)
        let rl = pl - kl - k * TWO_PI_LO;
        let (rs, re) = two_sum(rh, rl);
        let c = rs.cos() - rs.sin() * re;
        let term = jump * c;
        let s = sum + term;
        comp += if sum.abs() >= term.abs() {
            (sum - s) + term
        } else {
            (term - s) + sum
        };
        sum = s;
    }
    gmu * (level - (sum + comp))
}

#[cfg(test)]
mod tests {
    use super::super::scenes::table1;
    use super::*;
    use ssvr_core::closed_form::duhamel::DuhamelClosedForm;
    use ssvr_core::ReversalTrain;

    #[test]
    fn double_double_reference_matches_the_closed_form_at_small_times() {
        let s = table1(0.0).unwrap();
        let train: Vec<Reversal> = (0..40)
            .map(|j| Reversal {
                time_s: j as f64 * 0.0715 + 1e-5,
                level: if j % 2 == 0 { 1.0 } else { -1.0 },
            })
            .collect();
        let cf = DuhamelClosedForm::new(&s);
        let tr = ReversalTrain::Explicit(&train);
        for k in 0..3000 {
            let t = k as f64 * 1e-3;
            let want = cf.accel(&tr, t);
            let got = dd_undamped(s.omega_d(), s.gmu(), &train, t);
            // The f64 closed form rounds n·τ (~3e-14 rad per term at τ ~ 1 s).
            assert!(
                (got - want).abs() < 1e-12 * s.gmu(),
                "t = {t}: {got} vs {want}"
            );
        }
    }
}
