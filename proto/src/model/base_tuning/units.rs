//! A change of the accelerometers' units mid-run (the table accelerometer's gain adopted):
//! what the base tuning found from the samples so far, rescaled ([`BaseTuning::rescale`]).

use super::BaseTuning;

impl BaseTuning {
    /// Every accelerometer's samples `c` times what they were from the next sample on (the table
    /// accelerometer's gain adopted, [`Model::rescale_units`](crate::Model::rescale_units)):
    /// what was identified from the samples so far rescaled to the new units, as if they had
    /// been read in them: the sliding identifier's rows and blocks (its ω and ζ are ratios and
    /// do not move; μ·g and the offset scale), fuse mode's top fit, the blocks still to reach
    /// them (the one being summed and those waiting for late events), the offsets in use, the
    /// friction coefficients found from the samples (the prior's stays: it is no measurement; a
    /// slip start's blend of the prior and its breakaway is scaled whole, (c − 1)·0.3 of the
    /// prior too much) and the slides' kinetic coefficients. Left as they are (a change of 1 %
    /// in them moves nothing the goals see): the standard deviations in use and the last
    /// estimate reported. A 1 % table gain found after its eight
    /// episodes had left predict mode's μ̂ +1 % and adopted, its rows in the old units
    /// outweighing the new ones for seconds (the default scene: 0.30 % RMS instead of 0.02 %).
    #[cold]
    #[inline(never)]
    pub fn rescale(&mut self, c: f32) {
        // (`c` is finite and positive: a table gain is adopted only within 10 % of 1.)
        self.id.rescale(c);
        self.top_fit.rescale(1, c);
        // (The blocks still to reach the fits: the one being summed and those waiting for late
        // events.)
        for b in self.ring.iter_mut().chain(core::iter::once(&mut self.cur)) {
            (b.base, b.top) = (b.base * c, b.top * c);
        }
        self.offset *= c;
        self.top_offset *= c;
        self.id_shift *= c;
        if self.mu_std_use > 0.0 {
            self.mu_use *= c;
        }
        for (m, &s) in self.mu_dir.iter_mut().zip(self.mu_dir_std.iter()) {
            if s != 0.0 {
                *m *= c;
            }
        }
        if self.mu_known {
            self.mu_dir = [self.mu_use; 2];
        }
        self.slides.rescale(c);
    }
}
