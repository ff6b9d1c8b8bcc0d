//! The quantized heads over a parsed section ([`QView`]): one implementation shared by
//! the fixed-size [`QTable`] and the host's `DynQTable`.

use super::*;

/// A validated section with its per-class data located: the one implementation of the
/// quantized heads, shared by [`QTable`] and the host's `DynQTable`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct QView<'r, 'a> {
    pub(crate) meta: &'r Meta<'a>,
    pub(crate) classes: &'r [QClass<'a>],
    pub(crate) logits: &'r [QLogit<'a>],
}

impl<'a> QView<'_, 'a> {
    /// The ML mass of class `c`'s code `q` (`lambda_ML` outside its window).
    #[inline(always)]
    pub(super) fn ml_mass(&self, c: &QClass<'a>, q: i32) -> f32 {
        let wide = self.meta.bins_ml > 256;
        index_at(c.ml_index, wide, offset(q, c.ml_start))
            .and_then(|b| f32_at(c.ml_masses, b))
            .unwrap_or(self.meta.lambda_ml)
    }

    /// The MAP mass of class `c`'s code `q` (`lambda_MAP` outside its window).
    #[inline(always)]
    pub(super) fn map_mass(&self, c: &QClass<'a>, q: i32) -> f32 {
        f32_at(c.map_masses, offset(q, c.map_start)).unwrap_or(self.meta.lambda_map)
    }

    /// The masses of one head into `out`, then the layer's normalisation. `codes` holds
    /// K codes already in the code range.
    #[inline(always)]
    pub(crate) fn masses_into(
        &self,
        head: Head,
        codes: impl Iterator<Item = i32>,
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if !(0.0..=1.0).contains(&objectness) {
            return Err(InferError::Objectness);
        }
        if out.len() != self.classes.len() || scratch.len() != out.len() {
            return Err(InferError::Length);
        }
        for ((o, c), q) in out.iter_mut().zip(self.classes).zip(codes) {
            *o = match head {
                Head::Map => self.map_mass(c, q),
                _ => self.ml_mass(c, q),
            };
        }
        layer::normalise(out, scratch, objectness);
        self.recalibrate(if head == Head::Map { 1 } else { 0 }, out);
        Ok(())
    }

    /// Applies the map in slot `slot` (0 ML, 1 MAP, 2 Bayes, 3 open), if any, as the
    /// `f32` layer does (DESIGN §1.9).
    #[inline(always)]
    fn recalibrate(&self, slot: usize, out: &mut [f32]) {
        if let Some(knots) = self.meta.maps.get(slot).filter(|k| !k.is_empty()) {
            recal::apply(&KnotBytes(knots), out);
        }
    }

    /// Bayes scores: the log-scores from the stored rows, then the `f32` head's softmax
    /// with backend `M`. `scratch` holds C floats.
    #[inline(always)]
    pub(crate) fn bayes_into<M: Backend>(
        &self,
        codes: impl Iterator<Item = i32>,
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if self.logits.is_empty() {
            return Err(InferError::NoBayesHead);
        }
        self.log_scores_into(codes, objectness, out, scratch)?;
        bayes::softmax::<M>(scratch, objectness, out);
        self.recalibrate(2, out);
        Ok(())
    }

    /// Open-head scores (DESIGN §1.8): the Bayes log-scores from the stored rows, then
    /// the open head's normalisation on the dequantized logits, which `x` (K floats)
    /// receives. `scratch` holds C floats.
    #[inline(always)]
    pub(crate) fn open_into<M: Backend>(
        &self,
        codes: impl Iterator<Item = i32> + Clone,
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
        x: &mut [f32],
    ) -> Result<(), InferError> {
        let params = match (&self.meta.open, self.logits.is_empty()) {
            (Some(p), false) => p,
            _ => return Err(InferError::NoOpenHead),
        };
        if x.len() != out.len() {
            return Err(InferError::Length);
        }
        self.log_scores_into(codes.clone(), objectness, out, scratch)?;
        for ((x, c), q) in x.iter_mut().zip(self.classes).zip(codes) {
            *x = dequantize(q, c.scale, c.zero_point);
        }
        open::score_from_log_scores::<M>(scratch, params, x, objectness, out);
        self.recalibrate(3, out);
        Ok(())
    }

    /// The Bayes log-scores `l[c] = ln pi[c] + sum_j t[c][j][bin_j]` of one detection
    /// into `scratch` (C floats), in the order of the `f32` head (the prior, then each
    /// logit's row, left to right). Checks the objectness and the lengths of `out` and
    /// `scratch` first.
    #[inline(always)]
    fn log_scores_into(
        &self,
        codes: impl Iterator<Item = i32>,
        objectness: f32,
        out: &[f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if !(0.0..=1.0).contains(&objectness) {
            return Err(InferError::Objectness);
        }
        // The length of `scratch` (not the header's field) sizes the rows, so that a
        // caller with a compile-time C gets loops of known length.
        let cats = scratch.len();
        if out.len() != self.classes.len() || cats != usize::from(self.meta.categories) {
            return Err(InferError::Length);
        }
        for (l, &p) in scratch.iter_mut().zip(self.meta.log_prior) {
            *l = f32::from_le_bytes(p);
        }
        let wide = self.meta.bins_bayes > 256;
        let rows = self.logits.iter().zip(codes).map(|(lg, q)| {
            index_at(lg.index, wide, offset(q, lg.start)).and_then(|b| {
                let at = b.checked_mul(cats)?;
                lg.terms.get(at..at.checked_add(cats)?)
            })
        });
        bayes::add_rows(scratch, rows, self.meta.log_lambda);
        // The objectness feature last, as the f32 head adds it.
        if let Some((axis, terms)) = &self.meta.objectness {
            bayes::add_objectness_row(axis, terms, objectness, scratch);
        }
        Ok(())
    }
}
