//! Per-class isotonic regression (DESIGN §1.4), the post-hoc calibration baseline:
//! for class `c`, a non-decreasing map from the detector's own score of the class,
//! `OS * softmax(x)_c`, to the share of rows labelled `c`, fitted by
//! pool-adjacent-violators on validation rows and applied by linear interpolation
//! between the fitted values. The map's output is the final score: its target already
//! counts the background rows, so the objectness is not applied a second time.
//!
//! And the energy score (DESIGN §1.4), the unknown-object ranking baseline:
//! `E(x) = -logsumexp(x)` (temperature 1), ranked by `-E`.

use super::{check, scaled_softmax, BaselineError, Rows};
use mlmap_core::InferError;

/// One class's fitted map: knots `(x, y)` with `x` strictly increasing (the distinct
/// softmax scores of the validation rows) and `y` non-decreasing in `[0, 1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct IsotonicMap {
    x: Vec<f64>,
    y: Vec<f64>,
}

impl IsotonicMap {
    /// Fits the map to `(score, positive)` points by pool-adjacent-violators.
    ///
    /// Equal scores are pooled first (their target is the share of positives among
    /// them, weighted by their count), as `sklearn.isotonic.IsotonicRegression` does;
    /// blocks are compared and merged on exact integer counts, so the fitted values are
    /// `positives / rows` of each block, correctly rounded. `None` without points or
    /// with a NaN score.
    pub fn fit(points: &mut [(f64, bool)]) -> Option<Self> {
        if points.is_empty() || points.iter().any(|p| p.0.is_nan()) {
            return None;
        }
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        // (score, positives, rows) per distinct score, then blocks of the same.
        let mut distinct: Vec<(f64, u64, u64)> = Vec::new();
        for &(x, positive) in points.iter() {
            let x = x + 0.0; // -0.0 pools with 0.0
            match distinct.last_mut() {
                Some(last) if last.0 == x => {
                    last.1 += u64::from(positive);
                    last.2 += 1;
                }
                _ => distinct.push((x, u64::from(positive), 1)),
            }
        }
        // Each block: (positives, rows, number of distinct scores it covers).
        let mut blocks: Vec<(u64, u64, usize)> = Vec::with_capacity(distinct.len());
        for &(_, pos, n) in &distinct {
            let mut cur = (pos, n, 1usize);
            // Merge while the previous block's mean exceeds the current one's:
            // p1 / n1 > p2 / n2  <=>  p1 * n2 > p2 * n1, exactly in u128.
            while let Some(&prev) = blocks.last() {
                if u128::from(prev.0) * u128::from(cur.1) > u128::from(cur.0) * u128::from(prev.1) {
                    blocks.pop();
                    cur = (prev.0 + cur.0, prev.1 + cur.1, prev.2 + cur.2);
                } else {
                    break;
                }
            }
            blocks.push(cur);
        }
        let mut y = Vec::with_capacity(distinct.len());
        for &(pos, n, covers) in &blocks {
            let v = pos as f64 / n as f64;
            y.extend(std::iter::repeat_n(v, covers));
        }
        let x = distinct.iter().map(|d| d.0).collect();
        Some(Self { x, y })
    }

    /// The knots: the distinct fitted scores and their values.
    pub fn knots(&self) -> (&[f64], &[f64]) {
        (&self.x, &self.y)
    }

    /// The map at `v`: the first knot's value at or below the first score, the last
    /// knot's at or above the last, linear between neighbouring knots (as
    /// `numpy.interp`); NaN stays NaN.
    pub fn apply(&self, v: f64) -> f64 {
        let (Some(&x0), Some(&y0)) = (self.x.first(), self.y.first()) else {
            return 0.0;
        };
        let (Some(&xn), Some(&yn)) = (self.x.last(), self.y.last()) else {
            return 0.0;
        };
        if v.is_nan() {
            return v;
        }
        if v <= x0 {
            return y0;
        }
        if v >= xn {
            return yn;
        }
        // x[i] <= v < x[i + 1].
        let i = self.x.partition_point(|&x| x <= v).saturating_sub(1);
        match (
            self.x.get(i),
            self.x.get(i + 1),
            self.y.get(i),
            self.y.get(i + 1),
        ) {
            (Some(&xa), Some(&xb), Some(&ya), Some(&yb)) => {
                let t = (v - xa) / (xb - xa);
                (ya + (yb - ya) * t).clamp(ya, yb)
            }
            _ => yn,
        }
    }
}

/// The isotonic baseline: one [`IsotonicMap`] per class, from [`fit_isotonic`].
#[derive(Debug, Clone, PartialEq)]
pub struct Isotonic {
    maps: Vec<IsotonicMap>,
}

impl Isotonic {
    /// The map of each class, in class order.
    pub fn maps(&self) -> &[IsotonicMap] {
        &self.maps
    }

    /// `g_c(OS * softmax(x)_c)` for every class of one row, written into `out`.
    ///
    /// # Errors
    ///
    /// As [`softmax`](super::softmax); [`InferError::Length`] also when the row does
    /// not have one logit per fitted class. Nothing is written on error.
    pub fn score(
        &self,
        logits: &[f64],
        objectness: f64,
        out: &mut [f64],
    ) -> Result<(), InferError> {
        if self.maps.len() != out.len() {
            return Err(InferError::Length);
        }
        check(logits, objectness, out.len())?;
        scaled_softmax(logits, 1.0, objectness, out);
        for (o, map) in out.iter_mut().zip(&self.maps) {
            *o = map.apply(*o).clamp(0.0, 1.0);
        }
        Ok(())
    }
}

/// Fits the isotonic baseline on validation rows: for each class `c`, the map from
/// `OS * softmax(x)_c` (the softmax baseline's score, temperature 1) to "the row is
/// labelled `c`", over every row (background rows are negatives of every class).
///
/// # Errors
///
/// * [`BaselineError::Shape`]: as [`Rows::new`], or `labels` does not have one entry
///   per row.
/// * [`BaselineError::NoRows`]: there are no rows.
/// * [`BaselineError::Label`]: a label is not a class index.
/// * [`BaselineError::Row`]: a row has a NaN logit or a bad objectness.
///
/// # Panics
///
/// Never.
pub fn fit_isotonic(rows: &Rows<'_>) -> Result<Isotonic, BaselineError> {
    let n = rows.row_count()?;
    if rows.labels.len() != n {
        return Err(BaselineError::Shape);
    }
    if n == 0 {
        return Err(BaselineError::NoRows);
    }
    let k = rows.k;
    let mut soft = vec![0.0; n * k];
    for (r, out) in soft.chunks_exact_mut(k).enumerate() {
        let (logits, os) = rows.row(r).ok_or(BaselineError::Shape)?;
        check(logits, os, k).map_err(|error| BaselineError::Row { row: r, error })?;
        if rows
            .labels
            .get(r)
            .copied()
            .flatten()
            .is_some_and(|c| c >= k)
        {
            return Err(BaselineError::Label { row: r });
        }
        scaled_softmax(logits, 1.0, os, out);
    }
    let mut maps = Vec::with_capacity(k);
    let mut points = Vec::with_capacity(n);
    for c in 0..k {
        points.clear();
        for (row, label) in soft.chunks_exact(k).zip(rows.labels) {
            points.push((row.get(c).copied().unwrap_or(0.0), *label == Some(c)));
        }
        maps.push(IsotonicMap::fit(&mut points).ok_or(BaselineError::NoRows)?);
    }
    Ok(Isotonic { maps })
}

/// Scores every row with a fitted isotonic baseline: `N x K` scores, row-major.
///
/// # Errors
///
/// * [`BaselineError::Shape`]: as [`Rows::new`], or `K` differs from the fit's.
/// * [`BaselineError::Row`]: the first row with a NaN logit or a bad objectness.
///
/// # Panics
///
/// Never.
pub fn score_isotonic(iso: &Isotonic, rows: &Rows<'_>) -> Result<Vec<f64>, BaselineError> {
    let n = rows.row_count()?;
    if iso.maps.len() != rows.k {
        return Err(BaselineError::Shape);
    }
    let mut out = vec![0.0; rows.logits.len()];
    for (r, o) in out.chunks_exact_mut(rows.k).enumerate().take(n) {
        let (logits, os) = rows.row(r).ok_or(BaselineError::Shape)?;
        iso.score(logits, os, o)
            .map_err(|error| BaselineError::Row { row: r, error })?;
    }
    Ok(out)
}

/// The negative energy of one row, `logsumexp(x)` (temperature 1): larger is more
/// like a known object. `+inf` when a logit is `+inf`, `-inf` when all are `-inf`.
///
/// # Errors
///
/// [`InferError::Length`] for no logits, [`InferError::NanLogit`] for a NaN one.
///
/// # Panics
///
/// Never.
pub fn negative_energy(logits: &[f64]) -> Result<f64, InferError> {
    check(logits, 1.0, logits.len())?;
    let max = logits.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max.is_infinite() {
        return Ok(max);
    }
    let sum: f64 = logits.iter().map(|&x| (x - max).exp()).sum();
    Ok(max + sum.ln())
}

/// [`negative_energy`] of every row: `N` values.
///
/// # Errors
///
/// [`BaselineError::Shape`] as [`Rows::new`]; [`BaselineError::Row`] for the first row
/// with a NaN logit.
///
/// # Panics
///
/// Never.
pub fn negative_energies(rows: &Rows<'_>) -> Result<Vec<f64>, BaselineError> {
    let n = rows.row_count()?;
    let mut out = Vec::with_capacity(n);
    for (r, logits) in rows.logits.chunks_exact(rows.k).enumerate() {
        out.push(negative_energy(logits).map_err(|error| BaselineError::Row { row: r, error })?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fit(points: &[(f64, bool)]) -> IsotonicMap {
        IsotonicMap::fit(&mut points.to_vec()).unwrap()
    }

    #[test]
    fn pool_adjacent_violators_by_hand() {
        // Scores 0.1 .. 0.5 with targets 1, 0, 1, 0, 1: blocks {0.1, 0.2} at 1/2,
        // {0.3, 0.4} at 1/2 merge into one block of 1/2, then 0.5 at 1.
        let m = fit(&[
            (0.3, true),
            (0.1, true),
            (0.2, false),
            (0.4, false),
            (0.5, true),
        ]);
        let (x, y) = m.knots();
        assert_eq!(x, [0.1, 0.2, 0.3, 0.4, 0.5]);
        assert_eq!(y, [0.5, 0.5, 0.5, 0.5, 1.0]);
        assert_eq!(m.apply(0.0), 0.5);
        assert_eq!(m.apply(0.45), 0.75);
        assert_eq!(m.apply(2.0), 1.0);
        // Equal scores pool first: 0.2 twice with one positive is 1/2, below 0.6's 1.
        let m = fit(&[(0.2, true), (0.2, false), (0.6, true), (0.1, false)]);
        assert_eq!(m.knots().1, [0.0, 0.5, 1.0]);
        assert_eq!(m.apply(0.4), 0.75);
        assert!(IsotonicMap::fit(&mut []).is_none());
        assert!(IsotonicMap::fit(&mut [(f64::NAN, true)]).is_none());
    }

    #[test]
    fn isotonic_scores_and_errors() {
        let logits = [2.0, 0.0, 0.0, 2.0, 1.0, 1.0, -1.0, 3.0];
        let labels = [Some(0), Some(1), None, Some(1)];
        let rows = Rows::new(&logits, 2, &labels, &[]).unwrap();
        let iso = fit_isotonic(&rows).unwrap();
        assert_eq!(iso.maps().len(), 2);
        let s = score_isotonic(&iso, &Rows::new(&logits[..2], 2, &[], &[1.0]).unwrap()).unwrap();
        // Class 0's score of row 0 is its largest validation score, labelled 0.
        assert_eq!(s[0], 1.0);
        // At objectness 0 every score is below all of class 0's validation scores,
        // whose lowest (rows 1 and 3) are not labelled 0.
        let s = score_isotonic(&iso, &Rows::new(&logits[..2], 2, &[], &[0.0]).unwrap()).unwrap();
        assert_eq!(s[0], 0.0);
        assert_eq!(
            fit_isotonic(&Rows::new(&[], 2, &[], &[]).unwrap()),
            Err(BaselineError::NoRows)
        );
        let bad = Rows::new(&logits[..2], 2, &[Some(2)], &[]).unwrap();
        assert_eq!(fit_isotonic(&bad), Err(BaselineError::Label { row: 0 }));
        let three = Rows::new(&[0.0; 3], 3, &[], &[]).unwrap();
        assert_eq!(score_isotonic(&iso, &three), Err(BaselineError::Shape));
    }

    #[test]
    fn energy_values() {
        let e = negative_energy(&[1.0, 2.0, 3.0]).unwrap();
        // ln(e + e^2 + e^3) = 3.40760596444438 (numpy).
        assert!((e - 3.407_605_964_444_38).abs() < 1e-13, "{e}");
        assert_eq!(negative_energy(&[f64::INFINITY, 0.0]), Ok(f64::INFINITY));
        assert_eq!(
            negative_energy(&[f64::NEG_INFINITY; 2]),
            Ok(f64::NEG_INFINITY)
        );
        assert!(negative_energy(&[0.0, f64::NAN]).is_err());
        assert!((negative_energy(&[1000.0, 1000.0]).unwrap() - (1000.0 + 2f64.ln())).abs() < 1e-9);
    }
}
