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
//! The normalisation first scales every mass by the largest one,
//! `b_i = a_i * (1 / max_j a_j)` (each operation rounded; so `b_i` is in `(0, 1]`, and
//! exactly 1 for the largest), then evaluates
//! `s_i = OS / (1 + R_i / b_i)` with `R_i = sum_{j<i} b_j + sum_{j>i} b_j`, the other
//! classes' mass. Raising `a_i` either leaves the maximum alone (then `R_i` is
//! unchanged and `b_i` grows) or raises it (then `b_i = 1` and every other `b_j`, so
//! `R_i`, can only shrink); every rounded operation is monotone, so raising `L_i` can
//! never lower `s_i`, not even by one rounding step (invariant 3), and `s_i <= OS` holds
//! exactly (invariant 1). Equal masses all become exactly 1, `R_i = K - 1` exactly, and
//! each score is exactly `OS / K`: in particular when every `L_i` (ML) or every
//! `L_i * P_i` (MAP) is 0 (invariant 2), and with no special case that could disagree
//! with the general formula by a rounding step. Nothing overflows: `b_i <= 1`,
//! `R_i <= K - 1`. The ML head uses no transcendental function; the MAP head calls `exp`
//! only for classes whose likelihood is not 0.
//!
//! The functions here work on slices, so the const-generic [`Table`](crate::Table) and
//! the host's runtime-shaped table run the very same code.

use crate::diagnostics::error::InferError;
use crate::math::gaussian::Gaussian;
use crate::math::histogram::{Histogram, UpperTail};
use crate::math::{Backend, Libm};

/// The MAP head's backend when none is named ([`Table::map`](crate::Table::map),
/// `score_into`, the quantized MAP masses, the C API): `libm`'s `exp`, so that the prior
/// is as accurate as the platform's maths library.
pub type MapBackend = Libm;

/// The K calibrated scores of one detection (they sum to the objectness).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scores<const K: usize>(pub [f32; K]);

impl<const K: usize> Scores<K> {
    /// The predicted class: the index of the largest score, the lowest index on ties.
    ///
    /// # Examples
    ///
    /// ```
    /// # use mlmap_core as mlmap;
    /// let s = mlmap::Scores([0.2, 0.4, 0.4]);
    /// assert_eq!(s.argmax(), 1);
    /// ```
    #[inline]
    pub fn argmax(&self) -> usize {
        argmax(&self.0)
    }

    /// The predicted class with ties broken by the detection's own logits (DESIGN §1.7):
    /// among the classes sharing the largest score, the one with the largest logit
    /// (the lowest index if those tie too).
    ///
    /// A detection that every histogram calls "I don't know" gets `OS / K` for every
    /// class; [`Scores::argmax`] would then always answer class 0, while `decide` keeps
    /// the detector's ranking. The scores themselves are not changed.
    ///
    /// # Examples
    ///
    /// ```
    /// # use mlmap_core as mlmap;
    /// let s = mlmap::Scores([0.3, 0.3, 0.3]);
    /// assert_eq!(s.argmax(), 0);
    /// assert_eq!(s.decide(&[-1.0, 2.5, 0.4]), 1);
    /// ```
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn decide(&self, logits: &[f32; K]) -> usize {
        decide(&self.0, logits)
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

/// The tie-safe decision of DESIGN §1.7 on any scores and logits: the index of the
/// largest score; among equal largest scores, the one whose logit is largest; among
/// those, the lowest index.
///
/// This is the one implementation of the rule: [`Scores::decide`] on the device and the
/// host's metrics and reports (`*_pred`, `accuracy`, the true/false positive split) all
/// call it. A logit missing (a shorter `logits`) or NaN never wins a tie. Returns 0 for
/// empty `scores`.
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// // Scores in f64 (host), logits as read from the data.
/// assert_eq!(mlmap::decide(&[0.25f64, 0.5, 0.5], &[9.0f64, 1.0, 2.0]), 2);
/// assert_eq!(mlmap::decide(&[0.25f64, 0.5, 0.5], &[9.0f64, 2.0, 2.0]), 1);
/// ```
///
/// # Panics
///
/// Never.
#[inline]
pub fn decide<S: Copy + PartialOrd, L: Copy + PartialOrd>(scores: &[S], logits: &[L]) -> usize {
    let mut best = 0;
    let (mut best_s, mut best_l): (Option<S>, Option<L>) = (None, None);
    for (i, &s) in scores.iter().enumerate() {
        let l = logits.get(i).copied();
        let wins = match best_s {
            None => comparable(s), // the first comparable score
            Some(b) if s > b => true,
            Some(b) if s == b => match (l, best_l) {
                (Some(l), Some(bl)) => l > bl,
                (Some(l), None) => comparable(l),
                _ => false,
            },
            Some(_) => false,
        };
        if wins {
            best = i;
            best_s = Some(s);
            best_l = l.filter(|&l| comparable(l));
        }
    }
    best
}

/// False for NaN (a value not equal to itself), true for every other value.
#[inline]
fn comparable<T: PartialOrd>(v: T) -> bool {
    v.partial_cmp(&v).is_some()
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

/// Masses below this are scaled up by [`TWO_POW_64`] first, so `1 / max` cannot overflow.
const TINY_MAX: f32 = f32::from_bits(0x0d80_0000); // 2^-100
/// An exact scale factor (a power of two).
const TWO_POW_64: f32 = f32::from_bits(0x5f80_0000); // 2^64

/// Turns the unnormalised masses in `a` (each finite and > 0) into scores summing to
/// `objectness`; see the module docs. `suffix` is scratch space of the same length.
#[inline(always)]
pub(crate) fn normalise(a: &mut [f32], suffix: &mut [f32], objectness: f32) {
    let mut max = a.iter().copied().fold(0.0f32, f32::max);
    if max < TINY_MAX {
        // Exact: a power of two, and every product stays far below f32::MAX.
        for v in a.iter_mut() {
            *v *= TWO_POW_64;
        }
        max *= TWO_POW_64;
    }
    // b_j = a_j / max as one rounded product with the rounded reciprocal (one division
    // instead of K); the largest masses are exactly 1. The map a_j -> b_j is monotone in
    // a_j and, for a_j < max, in 1 / max, and never exceeds 1.
    let inv = 1.0 / max;
    for v in a.iter_mut() {
        *v = if *v >= max { 1.0 } else { *v * inv };
    }
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

/// The ML head's unnormalised mass of one class for logit `x`: `L(x) + lambda`. The
/// quantized table (`QTable`) precomputes its masses with this very function.
#[inline(always)]
pub(crate) fn ml_mass<F: AsRef<[f32]>>(
    h: &Histogram<F>,
    lambda: f32,
    tail: UpperTail,
    x: f32,
) -> f32 {
    h.likelihood(x, tail) + lambda
}

/// The MAP head's unnormalised mass of one class for logit `x`: `L(x) P(x) + lambda`,
/// with `P` evaluated only where `L(x) > 0`. The quantized table precomputes its masses
/// with this very function.
#[inline(always)]
pub(crate) fn map_mass<F: AsRef<[f32]>, M: Backend>(
    h: &Histogram<F>,
    g: &Gaussian,
    lambda: f32,
    tail: UpperTail,
    x: f32,
) -> f32 {
    let l = h.likelihood(x, tail);
    let lp = if l > 0.0 { l * g.pdf::<M>(x) } else { 0.0 };
    lp + lambda
}

/// ML scores of one detection into `out` (length K); `suffix` is scratch of length K.
#[inline(always)]
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
    for ((o, h), &x) in out.iter_mut().zip(hists).zip(logits) {
        *o = ml_mass(h, lambda, tail, x);
    }
    normalise(out, suffix, objectness);
    Ok(())
}

/// MAP scores of one detection into `out` (length K); `suffix` is scratch of length K.
#[inline(always)]
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
    for (((o, h), g), &x) in out.iter_mut().zip(hists).zip(priors).zip(logits) {
        *o = map_mass::<_, M>(h, g, lambda, tail, x);
    }
    normalise(out, suffix, objectness);
    Ok(())
}

/// Scores from per-class evidence, with the layer's exact arithmetic.
///
/// `evidence[i]` is `L_i` (ML head) or `L_i * P_i` (MAP head) as the layer computes
/// it; `out[i]` receives `OS * (e_i + lambda) / sum_j (e_j + lambda)`, or exactly
/// `OS / K` when every `e_i` is 0. A host tuner that has looked up the likelihoods once
/// can re-score them for many lambdas and get bit for bit what the layer would return.
/// `scratch` is any K floats.
///
/// # Errors
///
/// [`InferError::Length`] when the slices differ in length or are empty;
/// [`InferError::Evidence`] for a lambda outside `(0, MAX_LAMBDA]` or evidence that is
/// negative, above `1e30` or not finite; [`InferError::Objectness`] for an objectness
/// outside `[0, 1]`.
///
/// # Panics
///
/// Never.
pub fn scores_from_evidence(
    evidence: &[f32],
    lambda: f32,
    objectness: f32,
    out: &mut [f32],
    scratch: &mut [f32],
) -> Result<(), InferError> {
    let k = evidence.len();
    if k == 0 || out.len() != k || scratch.len() != k {
        return Err(InferError::Length);
    }
    let finite = |v: f32| (0.0..=1e30).contains(&v);
    if !(lambda > 0.0 && lambda <= crate::MAX_LAMBDA && evidence.iter().all(|&e| finite(e))) {
        return Err(InferError::Evidence);
    }
    if !(0.0..=1.0).contains(&objectness) {
        return Err(InferError::Objectness);
    }
    for (o, &e) in out.iter_mut().zip(evidence) {
        *o = e + lambda;
    }
    normalise(out, scratch, objectness);
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
    fn decide_breaks_ties_by_logit() {
        // No tie: the largest score wins whatever the logits.
        assert_eq!(decide(&[0.1f32, 0.7, 0.2], &[5.0f32, -1.0, 3.0]), 1);
        // Three-way tie at OS / K: the largest logit.
        assert_eq!(decide(&[0.3f32; 3], &[-1.0f32, 0.5, 0.2]), 1);
        // Tie between two of three: only the tied classes compete.
        assert_eq!(decide(&[0.4f32, 0.2, 0.4], &[1.0f32, 9.0, 2.0]), 2);
        // Logits tie too: the lowest index.
        assert_eq!(decide(&[0.5f32, 0.5], &[1.0f32, 1.0]), 0);
        // A NaN or missing logit never wins a tie.
        assert_eq!(decide(&[0.5f32, 0.5], &[f32::NAN, 1.0]), 1);
        assert_eq!(decide(&[0.5f32, 0.5], &[1.0f32, f32::NAN]), 0);
        assert_eq!(decide(&[0.5f32, 0.5, 0.5], &[1.0f32]), 0);
        // A NaN score never wins; empty scores give 0.
        assert_eq!(decide(&[f32::NAN, 0.1], &[9.0f32, 0.0]), 1);
        assert_eq!(decide::<f32, f32>(&[], &[]), 0);
        // Same as argmax when no score ties.
        assert_eq!(
            decide(&[0.1f64, 0.2, 0.3], &[3.0f64, 2.0, 1.0]),
            argmax(&[0.1, 0.2, 0.3])
        );
    }

    #[test]
    fn normalise_matches_plain_division() {
        let mut a = [0.5f32, 0.25, 0.25];
        let mut scratch = [0.0; 3];
        normalise(&mut a, &mut scratch, 0.8);
        assert_eq!(a, [0.4, 0.2, 0.2]);
    }

    /// Masses spread over the whole positive `f32` range, subnormals included.
    fn masses() -> impl Iterator<Item = f32> {
        (1u32..0x7f00_0000).step_by(0x00f0_0f01).map(f32::from_bits)
    }

    #[test]
    fn equal_masses_give_exactly_os_over_k() {
        let mut a = [0.0f32; 64];
        let mut scratch = [0.0f32; 64];
        for k in 2..=64 {
            for m in masses() {
                for os in [1.0f32, 0.93, 1e-30, 0.0] {
                    let a = &mut a[..k];
                    a.fill(m);
                    normalise(a, &mut scratch[..k], os);
                    let want = os / k as f32;
                    assert!(
                        a.iter().all(|s| s.to_bits() == want.to_bits()),
                        "K {k}, mass {m:e}, OS {os}: {a:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn raising_one_mass_never_lowers_its_score() {
        let mut scratch = [0.0f32; 11];
        for k in [2usize, 3, 6, 7, 11] {
            for m in masses() {
                for i in 0..k {
                    // From all-equal, raise mass i by one ulp, a little, and a lot; and
                    // from a spread of masses, the same.
                    let spread: std::vec::Vec<f32> =
                        (0..k).map(|j| m * (1.0 + j as f32 / 3.0)).collect();
                    for base in [std::vec![m; k], spread] {
                        if base.iter().any(|v| !v.is_finite()) {
                            continue;
                        }
                        let mut before = base.clone();
                        normalise(&mut before, &mut scratch[..k], 1.0);
                        for up in [base[i].next_up(), base[i] * 1.0001, base[i] * 3.0] {
                            if !up.is_finite() {
                                continue;
                            }
                            let mut after = base.clone();
                            after[i] = up;
                            normalise(&mut after, &mut scratch[..k], 1.0);
                            assert!(
                                after[i] >= before[i],
                                "K {k}, class {i}, {base:?} -> {up:e}: {} < {}",
                                after[i],
                                before[i]
                            );
                        }
                    }
                }
            }
        }
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
