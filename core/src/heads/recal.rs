//! Recalibration maps (docs/DESIGN.md §1.9): a monotone, piecewise-linear `g` on
//! `[0, 1]`, stored per head, applied to a detection's scores after the head.
//!
//! ```text
//! knots (x_0, y_0) .. (x_{n-1}, y_{n-1}),  2 <= n <= MAX_KNOTS,
//!       x_0 = 0, x_{n-1} = 1, x strictly increasing, 0 < y_0 <= .. <= y_{n-1} <= 1
//! g(t)  = min(y_i + (y_{i+1} - y_i) * min((t - x_i) / (x_{i+1} - x_i), 1), y_{i+1})
//!         on the segment [x_i, x_{i+1}] that holds t
//! s_c  <- g(top)                                        when s_c = top
//! s_c  <- min((s_c / top) * g(top), next_below(g(top)))  when s_c < top
//!         with top = max_c s_c; scores stay 0 when top = 0
//! ```
//!
//! The top scores become `g(top) > 0` exactly and every other score stays strictly
//! below them, so the decision is kept; division, multiplication by a positive number
//! and the `min` never reverse two floats, so the order of the classes is kept too (two
//! scores below the top may become equal). Each rounding step of `g` is monotone and the
//! `min` with `y_{i+1}` keeps a segment's end from passing the next segment's start, so
//! `g` never decreases in `f32` either.

use crate::diagnostics::error::{Head, MapError};

/// Most knots a map may have.
pub const MAX_KNOTS: usize = 32;

/// One knot of a recalibration map: the map sends the top score `x` to `y`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Knot {
    /// A top score, in `[0, 1]`.
    pub x: f32,
    /// What it becomes, in `[0, 1]`.
    pub y: f32,
}

impl Knot {
    /// The knot at the origin, for storage filled before use.
    pub(crate) const ZERO: Self = Self { x: 0.0, y: 0.0 };
}

/// A validated recalibration map, borrowed from its table (DESIGN §1.9).
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::{Knot, RecalMap};
///
/// let knots = [Knot { x: 0.0, y: 0.1 }, Knot { x: 0.5, y: 0.2 }, Knot { x: 1.0, y: 0.9 }];
/// let g = RecalMap::new(&knots)?;
/// assert_eq!(g.eval(0.5), 0.2);
/// let mut scores = [0.5, 0.25, 0.0];
/// g.apply(&mut scores);
/// assert_eq!(scores, [0.2, 0.1, 0.0]);
/// # Ok::<(), mlmap::MapError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecalMap<'a> {
    knots: &'a [Knot],
}

impl<'a> RecalMap<'a> {
    /// Checks the knots against DESIGN §1.9: 2 to [`MAX_KNOTS`] of them, the first at
    /// `x = 0` and the last at `x = 1`, `x` strictly increasing, every `y` in `(0, 1]`
    /// and non-decreasing.
    ///
    /// # Errors
    ///
    /// The first rule broken, as a [`MapError`].
    pub fn new(knots: &'a [Knot]) -> Result<Self, MapError> {
        check(knots)?;
        Ok(Self { knots })
    }

    /// A map from knots already checked (a validated table's storage).
    #[inline]
    pub(crate) const fn trusted(knots: &'a [Knot]) -> Self {
        Self { knots }
    }

    /// The knots.
    #[inline]
    pub fn knots(&self) -> &'a [Knot] {
        self.knots
    }

    /// `g(t)` for a top score `t` in `[0, 1]` (`t` below 0 is taken as 0, above 1 as 1).
    #[inline]
    pub fn eval(&self, t: f32) -> f32 {
        eval(self.knots, t)
    }

    /// Rescales one detection's scores in place: the largest, `top`, becomes `g(top)`,
    /// every other score `s` becomes `(s / top) * g(top)`, kept strictly below `g(top)`;
    /// all-zero scores stay zero.
    #[inline]
    pub fn apply(&self, scores: &mut [f32]) {
        apply(self.knots, scores);
    }
}

/// Knots as stored: a slice of [`Knot`] (a table) or little-endian bytes (a quantized
/// section in flash). The map's arithmetic is written once, over this.
pub(crate) trait Knots {
    /// Number of knots.
    fn count(&self) -> usize;
    /// Knot `i`.
    fn knot(&self, i: usize) -> Option<Knot>;
}

impl Knots for [Knot] {
    #[inline(always)]
    fn count(&self) -> usize {
        self.len()
    }
    #[inline(always)]
    fn knot(&self, i: usize) -> Option<Knot> {
        self.get(i).copied()
    }
}

/// Knots as 8 little-endian bytes each (`x`, then `y`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct KnotBytes<'a>(pub(crate) &'a [[u8; 8]]);

impl Knots for KnotBytes<'_> {
    #[inline(always)]
    fn count(&self) -> usize {
        self.0.len()
    }
    #[inline(always)]
    fn knot(&self, i: usize) -> Option<Knot> {
        let b = self.0.get(i)?;
        let (x, y) = b.split_at(4);
        let f = |h: &[u8]| h.try_into().ok().map(f32::from_le_bytes);
        Some(Knot { x: f(x)?, y: f(y)? })
    }
}

/// `g(t)` of valid knots: the segment starts at the last knot at or below `t` (a
/// binary search of at most 5 steps for 32 knots), the last segment holds `t = 1`.
#[inline(always)]
pub(crate) fn eval<S: Knots + ?Sized>(k: &S, t: f32) -> f32 {
    // Candidates for the segment's first knot: [lo, lo + len).
    let mut lo = 0usize;
    let mut len = k.count().saturating_sub(1);
    while len > 1 {
        let half = len / 2;
        let mid = lo + half;
        if k.knot(mid).is_some_and(|p| p.x <= t) {
            lo = mid;
        }
        len -= half;
    }
    match (k.knot(lo), k.knot(lo + 1)) {
        (Some(a), Some(b)) => {
            let f = ((t - a.x) / (b.x - a.x)).clamp(0.0, 1.0);
            (a.y + (b.y - a.y) * f).min(b.y)
        }
        _ => t,
    }
}

/// One detection's scores after the map of valid knots `k` (see [`RecalMap::apply`]).
#[inline(always)]
pub(crate) fn apply<S: Knots + ?Sized>(k: &S, scores: &mut [f32]) {
    let top = scores
        .iter()
        .fold(0.0f32, |m, &s| if s > m { s } else { m });
    if !(top > 0.0) {
        return;
    }
    let g = eval(k, top);
    // The largest float below g: g is positive and finite (every y is), so its bits
    // minus one.
    let below = f32::from_bits(g.to_bits().wrapping_sub(1));
    for s in scores.iter_mut() {
        *s = if *s == top {
            g
        } else {
            ((*s / top) * g).min(below)
        };
    }
}

/// The knots' rule (see [`RecalMap::new`]).
pub(crate) fn check<S: Knots + ?Sized>(knots: &S) -> Result<(), MapError> {
    let n = knots.count();
    if !(2..=MAX_KNOTS).contains(&n) {
        return Err(MapError::KnotCount);
    }
    let (Some(first), Some(last)) = (knots.knot(0), knots.knot(n - 1)) else {
        return Err(MapError::KnotCount);
    };
    // `== 0.0` also holds for -0.0, which is not the stored origin: refuse it so that the
    // table has one encoding.
    if first.x != 0.0 || first.x.is_sign_negative() || last.x != 1.0 {
        return Err(MapError::Ends);
    }
    let mut prev: Option<Knot> = None;
    for i in 0..n {
        let Some(k) = knots.knot(i) else {
            return Err(MapError::KnotCount);
        };
        if !(k.y > 0.0 && k.y <= 1.0) {
            return Err(MapError::Values);
        }
        if let Some(p) = prev {
            if !(k.x > p.x) {
                return Err(MapError::Order);
            }
            if !(k.y >= p.y) {
                return Err(MapError::Values);
            }
        }
        prev = Some(k);
    }
    Ok(())
}

/// The maps of a table, one slot per head in the order ML, MAP, Bayes, open; an empty
/// slice is no map.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Maps<'a>(pub(crate) [&'a [Knot]; 4]);

impl<'a> Maps<'a> {
    /// No map for any head.
    pub(crate) const NONE: Self = Self([&[]; 4]);

    /// The map of `head`, if the table has one.
    #[inline]
    pub(crate) fn get(&self, head: Head) -> Option<RecalMap<'a>> {
        self.0
            .get(head_slot(head))
            .filter(|k| !k.is_empty())
            .map(|k| RecalMap::trusted(k))
    }

    /// Whether any head has a map.
    pub(crate) fn any(&self) -> bool {
        self.0.iter().any(|k| !k.is_empty())
    }
}

/// The heads in slot order (and in the order of the format's map records).
pub(crate) const HEADS: [Head; 4] = [Head::Ml, Head::Map, Head::Bayes, Head::Open];

/// The slot of `head` in a table's maps, and its code in the format.
#[inline]
pub(crate) const fn head_slot(head: Head) -> usize {
    match head {
        Head::Ml => 0,
        Head::Map => 1,
        Head::Bayes => 2,
        Head::Open => 3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn k(x: f32, y: f32) -> Knot {
        Knot { x, y }
    }

    #[test]
    fn rule() {
        let ok = [k(0.0, 0.1), k(0.4, 0.1), k(1.0, 0.95)];
        assert_eq!(
            RecalMap::new(&[k(0.0, 0.0), k(1.0, 1.0)]),
            Err(MapError::Values)
        );
        assert!(RecalMap::new(&ok).is_ok());
        assert_eq!(RecalMap::new(&ok[..1]), Err(MapError::KnotCount));
        assert_eq!(RecalMap::new(&[k(0.0, 0.5); 33]), Err(MapError::KnotCount));
        assert_eq!(
            RecalMap::new(&[k(0.1, 0.5), k(1.0, 1.0)]),
            Err(MapError::Ends)
        );
        assert_eq!(
            RecalMap::new(&[k(-0.0, 0.5), k(1.0, 1.0)]),
            Err(MapError::Ends)
        );
        assert_eq!(
            RecalMap::new(&[k(0.0, 0.5), k(0.9, 1.0)]),
            Err(MapError::Ends)
        );
        assert_eq!(
            RecalMap::new(&[k(0.0, 0.1), k(0.5, 0.3), k(0.5, 0.4), k(1.0, 1.0)]),
            Err(MapError::Order)
        );
        assert_eq!(
            RecalMap::new(&[k(0.0, 0.5), k(0.5, 0.4), k(1.0, 1.0)]),
            Err(MapError::Values)
        );
        assert_eq!(
            RecalMap::new(&[k(0.0, 0.5), k(1.0, 1.5)]),
            Err(MapError::Values)
        );
        assert_eq!(
            RecalMap::new(&[k(0.0, f32::NAN), k(1.0, 1.0)]),
            Err(MapError::Values)
        );
        assert_eq!(
            RecalMap::new(&[k(0.0, 0.1), k(f32::NAN, 0.5), k(1.0, 1.0)]),
            Err(MapError::Order)
        );
    }

    /// Values worked by hand.
    #[test]
    fn eval_by_hand() {
        let knots = [k(0.0, 0.125), k(0.5, 0.25), k(0.75, 0.25), k(1.0, 1.0)];
        let g = RecalMap::new(&knots).unwrap();
        assert_eq!(g.eval(0.0), 0.125);
        assert_eq!(g.eval(0.25), 0.1875);
        assert_eq!(g.eval(0.5), 0.25);
        assert_eq!(g.eval(0.6), 0.25);
        assert_eq!(g.eval(0.875), 0.625);
        assert_eq!(g.eval(1.0), 1.0);
        assert_eq!(g.eval(2.0), 1.0);
        assert_eq!(g.eval(-1.0), 0.125);
        let mut s = [0.5, 0.25, 0.125, 0.5];
        g.apply(&mut s);
        assert_eq!(s, [0.25, 0.125, 0.0625, 0.25]);
        // A score one step below the top stays below the mapped top.
        let mut s = [0.75, 0.75f32.next_down()];
        g.apply(&mut s);
        assert_eq!(s, [0.25, 0.25f32.next_down()]);
        let mut zero = [0.0; 3];
        g.apply(&mut zero);
        assert_eq!(zero, [0.0; 3]);
    }

    /// `g` never decreases, in `f32`, across a segment boundary where the interpolation
    /// would round past the next knot.
    #[test]
    fn monotone_at_knots() {
        let knots = [k(0.0, 0.1), k(0.3, 0.7), k(0.7, 0.7000001), k(1.0, 1.0)];
        let g = RecalMap::new(&knots).unwrap();
        let mut prev = g.eval(0.0);
        let mut t = 0.0f32;
        while t <= 1.0 {
            let v = g.eval(t);
            assert!(v >= prev, "g({t}) = {v} < {prev}");
            prev = v;
            t = f32::from_bits(t.to_bits() + 997);
        }
    }
}
