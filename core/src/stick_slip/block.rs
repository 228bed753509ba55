//! [`StickSlipEstimator::update_block`]: a block of samples, bit for bit as many updates, with
//! the steady-state runs kept in registers.

use super::estimator::{unlikely, Slot, StickSlipEstimator};
use super::maps::{slide_map, stuck_map};
use crate::error::{Error, Param};
use crate::math::{Real, Transcendentals};

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// [`Self::update`] of a block of samples: `out[i]` = the prediction of the sample with
    /// `table[i]` and `top[i]`, bit for bit as that many calls of [`Self::update`] (events go
    /// between blocks: [`Self::push_event`] before the sample it precedes), but cheaper: the
    /// steady-state runs (plain sliding or plain stuck up to the next mark) keep the map's
    /// coefficients and the state in registers. Lengths that differ are an error (nothing
    /// processed). (Once the state has overflowed to NaN, the sign of a NaN may differ: the
    /// compiler may commute an addition.)
    pub fn update_block(&mut self, table: &[T], top: &[T], out: &mut [T]) -> Result<(), Error> {
        if top.len() != table.len() || out.len() != table.len() {
            return Err(Error::OutOfRange {
                param: Param::BlockLength,
                value: top.len().max(out.len()) as f64,
                expected: "top and out as long as table",
            });
        }
        let mut i = 0;
        while let (Some(t), Some(y), Some(o)) = (table.get(i..), top.get(i..), out.get_mut(i..)) {
            let (Some(&u0), Some(&y0)) = (t.first(), y.first()) else {
                break;
            };
            let done = self.run(t, y, o);
            if done == 0 {
                if let Some(o0) = o.first_mut() {
                    *o0 = self.update_one(u0, y0);
                }
                i += 1;
            } else {
                i += done;
            }
        }
        Ok(())
    }

    /// [`Self::update`] out of line (one copy of its inline paths for [`Self::update_block`],
    /// and for callers' cold paths that would otherwise inline a block of their own).
    #[inline(never)]
    pub fn update_one(&mut self, table_accel: T, measured_top: T) -> T {
        self.update(table_accel, measured_top)
    }

    /// The steady-state run at the start of a block ([`Self::update_block`]): plain sliding or
    /// plain stuck samples up to the next mark (whose work, [`Self::at_mark`], it then does).
    /// Returns how many samples it processed (0: the next one takes [`Self::update`]). The inputs are not tested sample by sample: a
    /// non-finite one (table acceleration; or the measured top acceleration, which enters the
    /// maps through the observer) makes the run's sum of table accelerations or its final state
    /// non-finite, and the run is then redone sample by sample by [`Self::update`].
    #[inline(always)]
    pub(super) fn run(&mut self, table: &[T], top: &[T], out: &mut [T]) -> usize {
        let at = self.at;
        let sliding = at < self.fast_until;
        let until = if sliding {
            self.fast_until
        } else {
            self.stuck_until
        };
        if at >= until {
            return 0;
        }
        // `until` = mark − 2: the run may store up to slot mark − 1, then the mark's work.
        let m = (until + 1 - at).min(table.len());
        let (slide, drive, closed) = (self.slide, self.drive, self.closed);
        let Some((prev, run)) = self
            .slots
            .get_mut(at..=at + m)
            .and_then(|s| s.split_first_mut())
        else {
            return 0;
        };
        let samples = run
            .iter_mut()
            .zip(table.iter().zip(top))
            .zip(out.iter_mut());
        let finite = if sliding {
            let (mut z, mut y0, mut sum) = (prev.z, prev.y, T::ZERO);
            for ((s, (&u, &y)), o) in samples {
                z = slide_map(&slide, drive, z, y0);
                *s = Slot { u, y, z };
                *o = z[0];
                sum += u;
                y0 = y;
            }
            sum.is_finite() && z[0].is_finite() && z[1].is_finite()
        } else if prev.y.is_finite() {
            let Slot {
                u: mut u0,
                y: mut y0,
                mut z,
            } = *prev;
            for ((s, (&u, &y)), o) in samples {
                z = stuck_map(&closed, z, y0, u0, u);
                *s = Slot { u, y, z };
                *o = z[0];
                (u0, y0) = (u, y);
            }
            z[0].is_finite() && z[1].is_finite()
        } else {
            // No measured top (predict mode's stuck phases; a missing sample): the open map, as
            // `update` takes it, while the tops the maps read (each sample's predecessor's) stay
            // missing; a finite one (`seen`) makes the run redo sample by sample. (Before, the
            // closed map's NaN state sent every such run to that redo: ~30 instructions per
            // sample more in predict mode.)
            let open = self.open;
            let (mut u0, mut y0, mut z, mut seen) = (prev.u, prev.y, prev.z, false);
            for ((s, (&u, &y)), o) in samples {
                seen |= y0.is_finite();
                z = stuck_map(&open, z, T::ZERO, u0, u);
                *s = Slot { u, y, z };
                *o = z[0];
                (u0, y0) = (u, y);
            }
            !seen && z[0].is_finite() && z[1].is_finite()
        };
        if finite {
            self.stored(at + m, T::ZERO);
        } else {
            unlikely();
            for ((&u, &y), o) in table.iter().zip(top).zip(out.iter_mut()).take(m) {
                *o = self.update_one(u, y);
            }
        }
        m
    }
}
