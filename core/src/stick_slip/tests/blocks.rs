//! `update_block`: blocks bit for bit the per-sample updates.

use super::*;

/// Events of sample k in a repeating pattern: slip, stick (late), slip back, stick, slip.
fn pattern(k: u64) -> Option<(i8, f32)> {
    match k % 1000 {
        40 => Some((1, 0.25)),
        300 => Some((0, 10.5)),
        330 => Some((-1, 3.75)),
        700 => Some((0, 20.0)),
        705 => Some((1, 0.0)),
        _ => None,
    }
}

/// Inputs of sample k with a non-finite table acceleration now and then, a missing top
/// acceleration now and then, and stretches of a third of the samples without a top (as in
/// predict mode), broken by one finite top and holding an infinite one in stuck phases.
fn gappy_inputs(k: u64) -> (f32, f32) {
    let (u, y) = inputs(k);
    let u = if k % 997 == 500 { f32::NAN } else { u };
    let y = match k % 3000 {
        1690 => f32::INFINITY,
        1310 => y,
        1000..2000 => f32::NAN,
        _ if k % 389 == 7 => f32::NAN,
        _ => y,
    };
    (u, y)
}

fn block_vs_samples<const H: usize>(cfg: StickSlipConfig, history: usize, n: u64) {
    let s = structure(0.2, 0.05);
    let mut a = StickSlipEstimator::<f32, F32Poly, H>::with_history(&s, 1e4, cfg, history).unwrap();
    let mut b = a.clone();
    let want: std::vec::Vec<u32> = (0..n)
        .map(|k| {
            if let Some((p, age)) = pattern(k) {
                a.push_event(p, age).unwrap();
            }
            let (u, y) = gappy_inputs(k);
            a.update(u, y).to_bits()
        })
        .collect();
    // Blocks of 1 to 40 samples, split where an event is pushed.
    let mut got = std::vec::Vec::new();
    let (mut k, mut len) = (0u64, 1u64);
    while k < n {
        if let Some((p, age)) = pattern(k) {
            b.push_event(p, age).unwrap();
        }
        let end = (k + len).min(n);
        let end = (k + 1..end).find(|&j| pattern(j).is_some()).unwrap_or(end);
        let (table, top): (std::vec::Vec<f32>, std::vec::Vec<f32>) =
            (k..end).map(gappy_inputs).unzip();
        let mut out = std::vec![0.0f32; table.len()];
        b.update_block(&table, &top, &mut out).unwrap();
        got.extend(out.iter().map(|x| x.to_bits()));
        k = end;
        len = len * 7 % 41 + 1;
    }
    assert_eq!(got.len(), want.len());
    let first = got.iter().zip(&want).position(|(g, w)| g != w);
    assert_eq!(first, None, "first difference at sample {first:?}");
    assert_eq!(a.mu_estimate(), b.mu_estimate());
    assert!(a.mu_estimate().is_some());
}

#[test]
fn blocks_give_the_per_sample_predictions_bit_for_bit() {
    let cfg = StickSlipConfig {
        use_identified_mu: true,
        min_blocks: 50,
        ..StickSlipConfig::DEFAULT
    };
    // The firmware's layout (storage = a multiple of the block plus one) and a plain one.
    block_vs_samples::<{ storage_for(39, 32) }>(cfg, 39, 30_000);
    block_vs_samples::<144>(cfg, 144, 30_000);
    block_vs_samples::<64>(StickSlipConfig::DEFAULT.for_rate(1e3), 40, 30_000);
}

/// A non-finite table acceleration in the first slot after the ring's wrap, inside a block
/// whose run reached the ring's last slot (found by fuzzing `update_block` against `update`):
/// the redone sample reads its predecessor from the copy slot, not from the last slot the
/// aborted run overwrote.
#[test]
fn a_redone_run_after_the_wrap_reads_the_copy_slot() {
    let s = structure(0.2, 0.05);
    let cfg = StickSlipConfig {
        identify_mu: false,
        ..StickSlipConfig::DEFAULT
    };
    for phase in [0, 1] {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let mut a =
                StickSlipEstimator::<f32, F32Poly, 8>::with_history(&s, 1e4, cfg, 7).unwrap();
            a.push_event(phase, 0.0).unwrap();
            let mut b = a.clone();
            let (mut want, mut got) = (std::vec::Vec::new(), std::vec::Vec::new());
            for k in 0..7 {
                let (u, y) = inputs(k);
                want.push(a.update(u, y).to_bits());
                got.push(b.update(u, y).to_bits());
            }
            let (mut table, top): (std::vec::Vec<f32>, std::vec::Vec<f32>) =
                (7..30).map(inputs).unzip();
            table[0] = bad;
            want.extend(
                table
                    .iter()
                    .zip(&top)
                    .map(|(&u, &y)| a.update(u, y).to_bits()),
            );
            let mut out = std::vec![0.0f32; table.len()];
            b.update_block(&table, &top, &mut out).unwrap();
            got.extend(out.iter().map(|x| x.to_bits()));
            assert_eq!(got, want, "phase {phase}, table {bad}");
            assert!(out.iter().all(|x| x.is_finite()));
        }
    }
}

#[test]
fn blocks_of_unequal_lengths_are_an_error() {
    let s = structure(0.2, 0.05);
    let mut e =
        StickSlipEstimator::<f32, F32Poly, 64>::new(&s, 1e4, StickSlipConfig::DEFAULT).unwrap();
    let mut out = [0.0f32; 3];
    let err = e.update_block(&[1.0; 3], &[1.0; 2], &mut out).unwrap_err();
    assert_eq!(err.param(), Param::BlockLength);
    assert!(e.update_block(&[1.0; 2], &[1.0; 2], &mut out).is_err());
    assert_eq!(e.sample_index(), 0, "nothing processed");
    assert!(e.update_block(&[], &[], &mut []).is_ok());
}
