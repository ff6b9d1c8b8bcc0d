//! The ML and MAP prediction layers (DESIGN §1.2; paper §III-A, Algorithm 1).
//!
//! For class `i` with logit `x_i`, likelihood `L_i` (histogram frequency) and prior
//! `P_i` (Gaussian pdf):
//!
//! ```text
//! a_i    = L_i + lambda_ML              (ML)      a_i = L_i * P_i + lambda_MAP   (MAP)
//! s_i    = OS * a_i / sum_j a_j
//! ```
//!
//! The normalisation is evaluated as `s_i = OS / (1 + R_i / a_i)` with
//! `R_i = sum_{j<i} a_j + sum_{j>i} a_j`, the other classes' mass. `R_i` does not depend
//! on `a_i`, and every operation after it is monotone, so raising `L_i` can never lower
//! `s_i`, not even by one rounding step (invariant 3), and `s_i <= OS` holds exactly
//! (invariant 1). When every `L_i` (ML) or every `L_i * P_i` (MAP) is 0, each score is
//! exactly `OS / K` (invariant 2). The ML head uses no transcendental function; the MAP
//! head calls `exp` only for classes whose likelihood is not 0.
//!
//! The functions here work on slices, so the const-generic [`Table`](crate::Table) and
//! the host's runtime-shaped table run the very same code.

use crate::error::InferError;
use crate::gaussian::Gaussian;
use crate::histogram::{Histogram, UpperTail};
use crate::math::Backend;

/// The K calibrated scores of one detection (they sum to the objectness).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scores<const K: usize>(pub [f32; K]);

impl<const K: usize> Scores<K> {
    /// The predicted class: the index of the largest score, the lowest index on ties.
    ///
    /// # Examples
    ///
    /// ```
    /// let s = mlmap::Scores([0.2, 0.4, 0.4]);
    /// assert_eq!(s.argmax(), 1);
    /// ```
    #[inline]
    pub fn argmax(&self) -> usize {
        argmax(&self.0)
    }

    /// The largest score (the detection's confidence).
    #[inline]
    pub fn confidence(&self) -> f32 {
        self.0.iter().copied().fold(0.0, f32::max)
    }

    /// The scores as an array, in class order.
    #[inline]
    pub fn as_array(&self) -> &[f32; K] {
        &self.0
    }
}

/// Index of the largest value, the lowest index on ties; 0 for an empty slice.
///
/// # Panics
///
/// Never.
#[inline]
pub fn argmax(values: &[f32]) -> usize {
    let mut best = 0;
    let mut best_v = f32::NEG_INFINITY;
    for (i, &v) in values.iter().enumerate() {
        if v > best_v {
            best = i;
            best_v = v;
        }
    }
    best
}

/// Checks a detection's inputs against a table with `k` classes.
#[inline]
pub(crate) fn check(
    logits: &[f32],
    objectness: f32,
    k: usize,
    out: usize,
) -> Result<(), InferError> {
    if logits.len() != k || out != k {
        return Err(InferError::Length);
    }
    for (i, x) in logits.iter().enumerate() {
        if x.is_nan() {
            return Err(InferError::NanLogit {
                class: u16::try_from(i).unwrap_or(u16::MAX),
            });
        }
    }
    if !(0.0..=1.0).contains(&objectness) {
        return Err(InferError::Objectness);
    }
    Ok(())
}

/// Turns the unnormalised masses in `a` into scores summing to `objectness`.
/// `suffix` is scratch space of the same length.
#[inline]
fn normalise(a: &mut [f32], suffix: &mut [f32], objectness: f32) {
    let mut acc = 0.0f32;
    for (s, &v) in suffix.iter_mut().zip(a.iter()).rev() {
        *s = acc;
        acc += v;
    }
    let mut prefix = 0.0f32;
    for (v, &s) in a.iter_mut().zip(suffix.iter()) {
        let own = *v;
        let rest = prefix + s;
        *v = objectness / (1.0 + rest / own);
        prefix += own;
    }
}

/// Every score `objectness / K`: the answer when no class has any evidence.
#[inline]
fn uniform(out: &mut [f32], objectness: f32) {
    let share = objectness / out.len() as f32;
    for v in out.iter_mut() {
        *v = share;
    }
}

/// ML scores of one detection into `out` (length K); `suffix` is scratch of length K.
#[inline]
pub(crate) fn ml_into<F: AsRef<[f32]>>(
    hists: &[Histogram<F>],
    lambda: f32,
    tail: UpperTail,
    logits: &[f32],
    objectness: f32,
    out: &mut [f32],
    suffix: &mut [f32],
) -> Result<(), InferError> {
    check(logits, objectness, hists.len(), out.len())?;
    // The sum of the K likelihoods is > 0 exactly when one of them is (they are finite,
    // >= 0, and at most 1 each); a sum is cheaper than a flag.
    let mut evidence = 0.0f32;
    for ((o, h), &x) in out.iter_mut().zip(hists).zip(logits) {
        let l = h.likelihood(x, tail);
        evidence += l;
        *o = l + lambda;
    }
    if evidence > 0.0 {
        normalise(out, suffix, objectness);
    } else {
        uniform(out, objectness);
    }
    Ok(())
}

/// MAP scores of one detection into `out` (length K); `suffix` is scratch of length K.
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn map_into<F: AsRef<[f32]>, M: Backend>(
    hists: &[Histogram<F>],
    priors: &[Gaussian],
    lambda: f32,
    tail: UpperTail,
    logits: &[f32],
    objectness: f32,
    out: &mut [f32],
    suffix: &mut [f32],
) -> Result<(), InferError> {
    check(logits, objectness, hists.len(), out.len())?;
    // As in `ml_into`; each `L * P` is at most the largest prior density (about 1e19
    // for the smallest variance a table accepts), so the sum of K of them is finite.
    let mut evidence = 0.0f32;
    for (((o, h), g), &x) in out.iter_mut().zip(hists).zip(priors).zip(logits) {
        let l = h.likelihood(x, tail);
        let lp = if l > 0.0 { l * g.pdf::<M>(x) } else { 0.0 };
        evidence += lp;
        *o = lp + lambda;
    }
    if evidence > 0.0 {
        normalise(out, suffix, objectness);
    } else {
        uniform(out, objectness);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn argmax_prefers_lowest_index() {
        assert_eq!(argmax(&[0.1, 0.5, 0.5]), 1);
        assert_eq!(argmax(&[0.3, 0.3, 0.3]), 0);
        assert_eq!(argmax(&[0.0, 0.0]), 0);
        assert_eq!(argmax(&[]), 0);
    }

    #[test]
    fn normalise_matches_plain_division() {
        let mut a = [0.5f32, 0.25, 0.25];
        let mut scratch = [0.0; 3];
        normalise(&mut a, &mut scratch, 0.8);
        assert_eq!(a, [0.4, 0.2, 0.2]);
    }

    #[test]
    fn check_rejects_bad_inputs() {
        assert_eq!(
            check(&[0.0, f32::NAN], 1.0, 2, 2),
            Err(InferError::NanLogit { class: 1 })
        );
        assert_eq!(check(&[0.0, 1.0], 1.5, 2, 2), Err(InferError::Objectness));
        assert_eq!(
            check(&[0.0, 1.0], -0.0001, 2, 2),
            Err(InferError::Objectness)
        );
        assert_eq!(
            check(&[0.0, 1.0], f32::NAN, 2, 2),
            Err(InferError::Objectness)
        );
        assert_eq!(check(&[0.0], 1.0, 2, 2), Err(InferError::Length));
        assert_eq!(check(&[0.0, 1.0], 1.0, 2, 3), Err(InferError::Length));
        assert_eq!(check(&[f32::INFINITY, 1.0], 0.0, 2, 2), Ok(()));
    }
}
