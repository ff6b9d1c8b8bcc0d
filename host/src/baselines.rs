//! The prediction layers mlmap is compared with, in `f64` on the host (DESIGN §1.4):
//! Sigmoid, Softmax, temperature-scaled Softmax and per-class isotonic regression, each
//! multiplied by the objectness, the fits of the temperature and of the isotonic maps
//! on validation data, and the energy score that ranks unknown objects.
//!
//! The per-row functions ([`sigmoid`], [`softmax`], [`temperature`]) write the `K`
//! scores of one detection into a slice the caller owns. [`score_rows`] scores a whole
//! set of [`Rows`], and [`fit_temperature`] picks the `T` that minimises the mean
//! negative log-likelihood of the labelled rows of a validation set.
//!
//! The `f32` versions that run on the device are in [`mlmap_core::baseline`].

use core::fmt;

use mlmap_core::InferError;

mod isotonic;

pub use self::isotonic::{
    fit_isotonic, negative_energies, negative_energy, score_isotonic, Isotonic, IsotonicMap,
};

/// Probability floor of the negative log-likelihood, `-ln(max(s_label, NLL_FLOOR))`
/// (DESIGN §1.5); shared with [`metrics`](super::metrics).
pub const NLL_FLOOR: f64 = 1e-12;

/// Initial bracket of the temperature search, `[1e-2, 1e2]`.
pub const T_BRACKET: (f64, f64) = (1e-2, 1e2);

/// Outermost bracket the temperature search widens to, `[1e-6, 1e6]`.
pub const T_LIMITS: (f64, f64) = (1e-6, 1e6);

/// Width in `ln T` at which the golden-section search stops (`T` to about 1e-8
/// relative).
pub const LN_T_TOLERANCE: f64 = 1e-8;

/// A set of detections for the baselines: logits, labels and objectness.
///
/// The fields borrow the caller's buffers, so a dataset reader can fill them without a
/// copy. Row `r` owns `logits[r * k .. (r + 1) * k]`, `labels[r]` and `objectness[r]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rows<'a> {
    /// `N x K` logits, row-major. NaN is refused; `±inf` is allowed.
    pub logits: &'a [f64],
    /// `K`, the number of classes (at least 1).
    pub k: usize,
    /// One label per row: `Some(class)` or `None` for background. May be empty when
    /// the rows are only scored ([`score_rows`]); [`fit_temperature`] needs `N`.
    pub labels: &'a [Option<usize>],
    /// One objectness per row, in `[0, 1]`; an empty slice means `1.0` for every row.
    pub objectness: &'a [f64],
}

impl<'a> Rows<'a> {
    /// Groups the buffers, checking that their lengths agree.
    ///
    /// # Errors
    ///
    /// [`BaselineError::Shape`] when `k` is 0, `logits.len()` is not a multiple of
    /// `k`, or `labels` / `objectness` are neither empty nor one per row.
    pub fn new(
        logits: &'a [f64],
        k: usize,
        labels: &'a [Option<usize>],
        objectness: &'a [f64],
    ) -> Result<Self, BaselineError> {
        let rows = Self {
            logits,
            k,
            labels,
            objectness,
        };
        rows.row_count()?;
        Ok(rows)
    }

    /// The number of rows `N`.
    ///
    /// # Errors
    ///
    /// [`BaselineError::Shape`] as in [`Rows::new`].
    pub fn row_count(&self) -> Result<usize, BaselineError> {
        if self.k == 0 || !self.logits.len().is_multiple_of(self.k) {
            return Err(BaselineError::Shape);
        }
        let n = self.logits.len() / self.k;
        let ok = |len: usize| len == 0 || len == n;
        if !ok(self.labels.len()) || !ok(self.objectness.len()) {
            return Err(BaselineError::Shape);
        }
        Ok(n)
    }

    /// Logits and objectness of row `r` (objectness 1 when none were given).
    fn row(&self, r: usize) -> Option<(&'a [f64], f64)> {
        let start = r.checked_mul(self.k)?;
        let logits = self.logits.get(start..start.checked_add(self.k)?)?;
        let os = if self.objectness.is_empty() {
            1.0
        } else {
            *self.objectness.get(r)?
        };
        Some((logits, os))
    }
}

/// One of the three baseline layers, for [`score_rows`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Baseline {
    /// `OS * sigma(x_i)`, the paper's "SG".
    Sigmoid,
    /// `OS * softmax(x)_i`.
    Softmax,
    /// `OS * softmax(x / T)_i` with the given `T > 0`.
    Temperature(f64),
}

/// Why the baselines could not score or fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum BaselineError {
    /// `K` is 0, or the logits, labels and objectness do not describe the same rows.
    Shape,
    /// Row `row` has a NaN logit or an objectness that is NaN or outside `[0, 1]`.
    Row {
        /// Index of the first invalid row.
        row: usize,
        /// What is wrong with it.
        error: InferError,
    },
    /// Row `row` is labelled with a class index `>= K`.
    Label {
        /// Index of the row.
        row: usize,
    },
    /// The temperature is not finite and positive.
    Temperature,
    /// The validation set has no row labelled with a class, so no `T` can be fitted.
    NoLabelledRows,
    /// The validation set has no rows, so no isotonic map can be fitted.
    NoRows,
}

impl fmt::Display for BaselineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Shape => f.write_str(
                "logits, labels and objectness do not describe the same rows of K > 0 classes",
            ),
            Self::Row { row, error } => write!(f, "row {row}: {error}"),
            Self::Label { row } => write!(f, "row {row}: label is not a class index"),
            Self::Temperature => f.write_str("temperature is not finite and positive"),
            Self::NoLabelledRows => {
                f.write_str("no row is labelled with a class: cannot fit a temperature")
            }
            Self::NoRows => f.write_str("no rows: cannot fit the isotonic maps"),
        }
    }
}

impl core::error::Error for BaselineError {}

/// Checks one row's inputs: `out_len` logits, no NaN logit, objectness in `[0, 1]`.
fn check(logits: &[f64], objectness: f64, out_len: usize) -> Result<(), InferError> {
    if logits.is_empty() || logits.len() != out_len {
        return Err(InferError::Length);
    }
    if let Some(i) = logits.iter().position(|x| x.is_nan()) {
        return Err(InferError::NanLogit {
            class: u16::try_from(i).unwrap_or(u16::MAX),
        });
    }
    if !(0.0..=1.0).contains(&objectness) {
        return Err(InferError::Objectness);
    }
    Ok(())
}

/// `OS * sigma(x_i)` for every class of one row, written into `out`.
///
/// `sigma(+inf) = 1` and `sigma(-inf) = 0`; `exp` only ever sees a non-positive
/// argument, so nothing overflows.
///
/// # Examples
///
/// ```
/// let mut s = [0.0; 2];
/// mlmap_host::baselines::sigmoid(&[0.0, f64::INFINITY], 0.5, &mut s)?;
/// assert_eq!(s, [0.25, 0.5]);
/// # Ok::<(), mlmap_core::InferError>(())
/// ```
///
/// # Errors
///
/// * [`InferError::Length`]: `logits` is empty or `out` has another length.
/// * [`InferError::NanLogit`]: a logit is NaN.
/// * [`InferError::Objectness`]: `objectness` is NaN or outside `[0, 1]`.
///
/// Nothing is written on error.
///
/// # Panics
///
/// Never.
pub fn sigmoid(logits: &[f64], objectness: f64, out: &mut [f64]) -> Result<(), InferError> {
    check(logits, objectness, out.len())?;
    for (o, &x) in out.iter_mut().zip(logits) {
        let s = if x >= 0.0 {
            1.0 / (1.0 + (-x).exp())
        } else {
            let e = x.exp();
            e / (1.0 + e)
        };
        *o = objectness * s;
    }
    Ok(())
}

/// `OS * softmax(x)_i` for every class of one row, written into `out`.
///
/// The maximum is subtracted before `exp`, so large logits neither overflow nor lose
/// the small scores. Infinite logits take the limit: when some logits are `+inf` they
/// share `OS` equally and the others get 0; when all are `-inf` every class gets
/// `OS / K`.
///
/// # Examples
///
/// ```
/// let mut s = [0.0; 3];
/// mlmap_host::baselines::softmax(&[1e308, 1e308, f64::NEG_INFINITY], 0.8, &mut s)?;
/// assert_eq!(s, [0.4, 0.4, 0.0]);
/// # Ok::<(), mlmap_core::InferError>(())
/// ```
///
/// # Errors
///
/// As [`sigmoid`].
///
/// # Panics
///
/// Never.
pub fn softmax(logits: &[f64], objectness: f64, out: &mut [f64]) -> Result<(), InferError> {
    check(logits, objectness, out.len())?;
    scaled_softmax(logits, 1.0, objectness, out);
    Ok(())
}

/// `OS * softmax(x / T)_i` for every class of one row, written into `out`.
///
/// Computed as `exp((x_i - max x) / T)`, normalised, so neither a large logit nor a
/// small `T` overflows; infinite logits behave as in [`softmax`].
///
/// # Examples
///
/// ```
/// let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
/// mlmap_host::baselines::temperature(&[2.0, 4.0], 1.0, 2.0, &mut a)?;
/// mlmap_host::baselines::softmax(&[1.0, 2.0], 1.0, &mut b)?;
/// assert_eq!(a, b);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
///
/// * [`BaselineError::Temperature`]: `t` is not finite and positive.
/// * [`BaselineError::Row`] (with `row: 0`) for the errors of [`sigmoid`].
///
/// # Panics
///
/// Never.
pub fn temperature(
    logits: &[f64],
    objectness: f64,
    t: f64,
    out: &mut [f64],
) -> Result<(), BaselineError> {
    if !(t > 0.0 && t.is_finite()) {
        return Err(BaselineError::Temperature);
    }
    check(logits, objectness, out.len()).map_err(|error| BaselineError::Row { row: 0, error })?;
    scaled_softmax(logits, t, objectness, out);
    Ok(())
}

/// `OS * softmax(x / t)` into `out`; inputs already checked (`t > 0`, no NaN).
fn scaled_softmax(logits: &[f64], t: f64, objectness: f64, out: &mut [f64]) {
    let max = logits.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max.is_infinite() {
        // All -inf (uniform), or some +inf (they share the mass): the limits of softmax.
        let n = logits.iter().filter(|&&x| x == max).count() as f64;
        for (o, &x) in out.iter_mut().zip(logits) {
            *o = if x == max { objectness / n } else { 0.0 };
        }
        return;
    }
    let mut sum = 0.0;
    for (o, &x) in out.iter_mut().zip(logits) {
        *o = ((x - max) / t).exp();
        sum += *o;
    }
    // sum >= 1: the maximum contributes exp(0).
    let scale = objectness / sum;
    for o in out.iter_mut() {
        *o *= scale;
    }
}

/// Scores every row with one baseline: `N x K` scores, row-major.
///
/// # Errors
///
/// * [`BaselineError::Shape`]: as [`Rows::new`].
/// * [`BaselineError::Row`]: the first row with a NaN logit or a bad objectness.
/// * [`BaselineError::Temperature`]: `Baseline::Temperature(t)` with `t` not finite
///   and positive.
///
/// # Panics
///
/// Never.
pub fn score_rows(baseline: Baseline, rows: &Rows<'_>) -> Result<Vec<f64>, BaselineError> {
    let n = rows.row_count()?;
    if let Baseline::Temperature(t) = baseline {
        if !(t > 0.0 && t.is_finite()) {
            return Err(BaselineError::Temperature);
        }
    }
    let mut out = vec![0.0; rows.logits.len()];
    for (r, o) in out.chunks_exact_mut(rows.k).enumerate().take(n) {
        let (logits, os) = rows.row(r).ok_or(BaselineError::Shape)?;
        let res = match baseline {
            Baseline::Sigmoid => sigmoid(logits, os, o),
            Baseline::Softmax => softmax(logits, os, o),
            Baseline::Temperature(t) => check(logits, os, o.len()).map(|()| {
                scaled_softmax(logits, t, os, o);
            }),
        };
        res.map_err(|error| BaselineError::Row { row: r, error })?;
    }
    Ok(out)
}

/// The result of [`fit_temperature_detailed`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TemperatureFit {
    /// The fitted temperature, `T > 0`.
    pub t: f64,
    /// Mean NLL of the labelled rows at `t`.
    pub nll: f64,
    /// Number of labelled rows the NLL averages over.
    pub labelled: usize,
    /// Whether `t` is an end of [`T_LIMITS`]: the NLL still decreased towards it, so
    /// the data has no interior optimum (e.g. every labelled row is already correct
    /// with a margin, which drives `T` towards 0).
    pub at_limit: bool,
}

/// Fits the temperature `T` of the temperature baseline on a validation set.
///
/// Same as [`fit_temperature_detailed`], returning only `T`.
///
/// # Errors
///
/// As [`fit_temperature_detailed`].
///
/// # Panics
///
/// Never.
pub fn fit_temperature(rows: &Rows<'_>) -> Result<f64, BaselineError> {
    fit_temperature_detailed(rows).map(|fit| fit.t)
}

/// Fits the `T > 0` that minimises the mean NLL, `-ln(max(s_label, 1e-12))` with
/// `s = OS * softmax(x / T)`, over the rows labelled with a class (background rows do
/// not count).
///
/// # Method
///
/// Golden-section search over `u = ln T`, which keeps `T > 0` by construction. Without
/// the probability floor the NLL is convex in `1 / T` (a log-sum-exp of linear
/// functions), hence unimodal in `ln T`, which is what golden section needs. The search
/// starts on [`T_BRACKET`], `[1e-2, 1e2]`; when the minimum lands on an end of the
/// bracket, the bracket moves a factor 100 past that end and the search repeats, up to
/// [`T_LIMITS`], `[1e-6, 1e6]`. It stops when the bracket is [`LN_T_TOLERANCE`] wide in
/// `ln T`; the NLL is flat at its minimum, so `T` itself is known to about 1e-7 relative
/// while the NLL is known to `f64` precision. Each step costs one pass over the
/// labelled rows; a fit takes about 50 passes per bracket.
///
/// # Errors
///
/// * [`BaselineError::Shape`]: as [`Rows::new`], or `labels` does not have one entry
///   per row.
/// * [`BaselineError::Label`]: a label is not a class index.
/// * [`BaselineError::Row`]: a labelled row has a NaN logit or a bad objectness.
/// * [`BaselineError::NoLabelledRows`]: no row is labelled with a class (this includes
///   an empty set).
///
/// # Panics
///
/// Never.
pub fn fit_temperature_detailed(rows: &Rows<'_>) -> Result<TemperatureFit, BaselineError> {
    let n = rows.row_count()?;
    if rows.labels.len() != n {
        return Err(BaselineError::Shape);
    }
    // Keep the labelled rows once: (logits, objectness, label).
    let mut labelled = Vec::new();
    for (r, label) in rows.labels.iter().enumerate() {
        let Some(c) = *label else { continue };
        if c >= rows.k {
            return Err(BaselineError::Label { row: r });
        }
        let (logits, os) = rows.row(r).ok_or(BaselineError::Shape)?;
        check(logits, os, rows.k).map_err(|error| BaselineError::Row { row: r, error })?;
        labelled.push((logits, os, c));
    }
    if labelled.is_empty() {
        return Err(BaselineError::NoLabelledRows);
    }
    let mut buf = vec![0.0; rows.k];
    let mut nll = |u: f64| mean_nll(&labelled, u.exp(), &mut buf);

    let (lim_lo, lim_hi) = (T_LIMITS.0.ln(), T_LIMITS.1.ln());
    let (mut a, mut b) = (T_BRACKET.0.ln(), T_BRACKET.1.ln());
    let step = 100f64.ln();
    let edge = 2.0 * LN_T_TOLERANCE;
    // Which way the bracket has moved: it never turns back, so the loop ends (the
    // minimum of a unimodal function cannot be past both ends).
    let mut moving: Option<bool> = None;
    let (u, f) = loop {
        let (u, f) = golden_section(&mut nll, a, b);
        if u - a <= edge && a > lim_lo && moving != Some(true) {
            moving = Some(false);
            (a, b) = ((a - step).max(lim_lo), a + edge);
        } else if b - u <= edge && b < lim_hi && moving != Some(false) {
            moving = Some(true);
            (a, b) = (b - edge, (b + step).min(lim_hi));
        } else {
            break (u, f);
        }
    };
    Ok(TemperatureFit {
        t: u.exp(),
        nll: f,
        labelled: labelled.len(),
        at_limit: u - lim_lo <= edge || lim_hi - u <= edge,
    })
}

/// Mean of `-ln(max(OS * softmax(x / t)_label, NLL_FLOOR))` over the labelled rows.
fn mean_nll(labelled: &[(&[f64], f64, usize)], t: f64, buf: &mut [f64]) -> f64 {
    let mut sum = 0.0;
    for &(logits, os, c) in labelled {
        scaled_softmax(logits, t, os, buf);
        let s = buf.get(c).copied().unwrap_or(0.0);
        sum -= s.max(NLL_FLOOR).ln();
    }
    sum / labelled.len() as f64
}

/// Minimises a unimodal `f` on `[a, b]` by golden-section search; returns the best
/// point seen and its value. Stops when the bracket is [`LN_T_TOLERANCE`] wide.
fn golden_section(f: &mut impl FnMut(f64) -> f64, mut a: f64, mut b: f64) -> (f64, f64) {
    // 1 / phi: each step keeps this fraction of the bracket.
    const INV_PHI: f64 = 0.618_033_988_749_894_9;
    let mut c = b - INV_PHI * (b - a);
    let mut d = a + INV_PHI * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    // The ends are evaluated too, so a minimum on the bracket's edge is reported there.
    let (fa, fb) = (f(a), f(b));
    // Ties go to the smaller u (smaller T), as do ties between c and d below.
    let better = |p: (f64, f64), m: (f64, f64)| p.1 < m.1 || (p.1 == m.1 && p.0 < m.0);
    let mut best = [(a, fa), (b, fb), (d, fd)]
        .into_iter()
        .fold((c, fc), |m, p| if better(p, m) { p } else { m });
    // At most ~100 steps for any bracket within T_LIMITS; the cap only guards the loop.
    for _ in 0..200 {
        if b - a <= LN_T_TOLERANCE {
            break;
        }
        if fc <= fd {
            (b, d, fd) = (d, c, fc);
            c = b - INV_PHI * (b - a);
            fc = f(c);
            if better((c, fc), best) {
                best = (c, fc);
            }
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + INV_PHI * (b - a);
            fd = f(d);
            if better((d, fd), best) {
                best = (d, fd);
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigmoid_and_softmax_values() {
        let mut s = [0.0; 3];
        sigmoid(&[0.0, 2.0, -2.0], 0.5, &mut s).unwrap();
        // sigma(2) = 0.8807970779778823 (numpy), times 0.5.
        assert_eq!(s[0], 0.25);
        assert!((s[1] - 0.440_398_538_988_941_15).abs() < 1e-16);
        assert!((s[1] + s[2] - 0.5).abs() < 1e-16);

        softmax(&[1.0, 2.0, 3.0], 1.0, &mut s).unwrap();
        let want = [
            0.090_030_573_170_380_46,
            0.244_728_471_054_797_64,
            0.665_240_955_774_821_9,
        ];
        for (g, w) in s.iter().zip(want) {
            assert!((g - w).abs() <= 2.0 * f64::EPSILON, "{g} vs {w}");
        }
    }

    #[test]
    fn softmax_handles_huge_and_infinite_logits() {
        let mut s = [0.0; 3];
        softmax(&[1000.0, 1000.0, -1000.0], 1.0, &mut s).unwrap();
        assert_eq!(s, [0.5, 0.5, 0.0]);
        softmax(&[f64::INFINITY, 3.0, f64::INFINITY], 0.6, &mut s).unwrap();
        assert_eq!(s, [0.3, 0.0, 0.3]);
        softmax(&[f64::NEG_INFINITY; 3], 0.9, &mut s).unwrap();
        assert_eq!(s, [0.3, 0.3, 0.3]);
        softmax(&[f64::NEG_INFINITY, 0.0, f64::NEG_INFINITY], 1.0, &mut s).unwrap();
        assert_eq!(s, [0.0, 1.0, 0.0]);
        sigmoid(&[f64::NEG_INFINITY, f64::INFINITY, -800.0], 1.0, &mut s).unwrap();
        assert_eq!(s[..2], [0.0, 1.0]);
        assert!(s[2] >= 0.0 && s[2] < 1e-300);
    }

    #[test]
    fn temperature_limits() {
        let mut s = [0.0; 2];
        // Tiny T: the larger logit takes everything, without overflow.
        temperature(&[1.0, 1.5], 1.0, 1e-300, &mut s).unwrap();
        assert_eq!(s, [0.0, 1.0]);
        // Huge T: uniform.
        temperature(&[-50.0, 50.0], 1.0, 1e300, &mut s).unwrap();
        assert_eq!(s, [0.5, 0.5]);
        for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(
                temperature(&[1.0, 2.0], 1.0, t, &mut s),
                Err(BaselineError::Temperature)
            );
        }
    }

    #[test]
    fn bad_rows_are_errors_and_leave_out_untouched() {
        let mut s = [7.0; 2];
        assert_eq!(
            softmax(&[1.0, f64::NAN], 1.0, &mut s),
            Err(InferError::NanLogit { class: 1 })
        );
        assert_eq!(
            sigmoid(&[1.0, 2.0], 1.5, &mut s),
            Err(InferError::Objectness)
        );
        assert_eq!(
            sigmoid(&[1.0, 2.0], f64::NAN, &mut s),
            Err(InferError::Objectness)
        );
        assert_eq!(sigmoid(&[1.0], 1.0, &mut s), Err(InferError::Length));
        assert_eq!(sigmoid(&[], 1.0, &mut []), Err(InferError::Length));
        assert_eq!(s, [7.0; 2]);
    }

    #[test]
    fn rows_shape_checks() {
        let logits = [0.0; 6];
        assert_eq!(Rows::new(&logits, 0, &[], &[]), Err(BaselineError::Shape));
        assert_eq!(Rows::new(&logits, 4, &[], &[]), Err(BaselineError::Shape));
        assert_eq!(
            Rows::new(&logits, 3, &[None], &[]),
            Err(BaselineError::Shape)
        );
        assert_eq!(
            Rows::new(&logits, 3, &[], &[1.0; 3]),
            Err(BaselineError::Shape)
        );
        let rows = Rows::new(&logits, 3, &[None, Some(1)], &[]).unwrap();
        assert_eq!(rows.row_count(), Ok(2));
        assert_eq!(Rows::new(&[], 3, &[], &[]).unwrap().row_count(), Ok(0));
    }

    #[test]
    fn score_rows_reports_the_bad_row() {
        let logits = [0.0, 1.0, 2.0, f64::NAN];
        let rows = Rows::new(&logits, 2, &[], &[]).unwrap();
        assert_eq!(
            score_rows(Baseline::Softmax, &rows),
            Err(BaselineError::Row {
                row: 1,
                error: InferError::NanLogit { class: 1 }
            })
        );
        let rows = Rows::new(&logits[..2], 2, &[], &[0.5]).unwrap();
        let s = score_rows(Baseline::Temperature(1.0), &rows).unwrap();
        let mut want = [0.0; 2];
        softmax(&[0.0, 1.0], 0.5, &mut want).unwrap();
        assert_eq!(s, want);
        assert_eq!(
            score_rows(Baseline::Temperature(0.0), &rows),
            Err(BaselineError::Temperature)
        );
    }

    #[test]
    fn fit_temperature_errors() {
        let logits = [0.0, 1.0, 2.0, 0.5];
        let rows = Rows::new(&logits, 2, &[None, None], &[]).unwrap();
        assert_eq!(fit_temperature(&rows), Err(BaselineError::NoLabelledRows));
        let rows = Rows::new(&[], 2, &[], &[]).unwrap();
        assert_eq!(fit_temperature(&rows), Err(BaselineError::NoLabelledRows));
        let rows = Rows::new(&logits, 2, &[None, Some(2)], &[]).unwrap();
        assert_eq!(fit_temperature(&rows), Err(BaselineError::Label { row: 1 }));
        let rows = Rows::new(&logits, 2, &[], &[]).unwrap();
        assert_eq!(fit_temperature(&rows), Err(BaselineError::Shape));
        let rows = Rows::new(&logits, 2, &[Some(0), Some(1)], &[1.0, 2.0]).unwrap();
        assert_eq!(
            fit_temperature(&rows),
            Err(BaselineError::Row {
                row: 1,
                error: InferError::Objectness
            })
        );
    }

    #[test]
    fn fit_temperature_two_class_closed_form() {
        // Three rows with logits (0, d), two labelled 1 and one labelled 0: the score
        // of class 1 is p = sigma(d / T), the NLL -(2 ln p + ln(1 - p)) / 3 is least at
        // p = 2/3, so T* = d / ln 2.
        let d = 3.0;
        let logits = [0.0, d, 0.0, d, 0.0, d];
        let labels = [Some(1), Some(1), Some(0)];
        let rows = Rows::new(&logits, 2, &labels, &[]).unwrap();
        let fit = fit_temperature_detailed(&rows).unwrap();
        let want = d / 2f64.ln();
        assert!((fit.t / want - 1.0).abs() < 1e-6, "{} vs {want}", fit.t);
        assert!(!fit.at_limit);
        assert_eq!(fit.labelled, 3);
        let nll_want = -((2.0f64 / 3.0).ln() * 2.0 + (1.0f64 / 3.0).ln()) / 3.0;
        assert!((fit.nll - nll_want).abs() < 1e-14);
    }

    #[test]
    fn fit_temperature_widens_to_the_limits() {
        // Every row correct: the NLL falls as T -> 0, down to the lower limit.
        let logits = [0.0, 1.0, 2.0, 0.0];
        let rows = Rows::new(&logits, 2, &[Some(1), Some(0)], &[]).unwrap();
        let fit = fit_temperature_detailed(&rows).unwrap();
        assert!(fit.at_limit);
        assert!((fit.t / T_LIMITS.0 - 1.0).abs() < 1e-6, "{}", fit.t);
        // Every row wrong by the same margin as it is right elsewhere: T -> inf.
        let labels = [Some(0), Some(1)];
        let rows = Rows::new(&logits, 2, &labels, &[]).unwrap();
        let fit = fit_temperature_detailed(&rows).unwrap();
        assert!(fit.at_limit);
        assert!((fit.t / T_LIMITS.1 - 1.0).abs() < 1e-6, "{}", fit.t);
        // Minimum just outside the initial bracket: T* = 500 / ln 2 ~ 721.
        let d = 500.0;
        let logits = [0.0, d, 0.0, d, 0.0, d];
        let rows = Rows::new(&logits, 2, &[Some(1), Some(1), Some(0)], &[]).unwrap();
        let fit = fit_temperature_detailed(&rows).unwrap();
        assert!(!fit.at_limit);
        assert!((fit.t / (d / 2f64.ln()) - 1.0).abs() < 1e-6, "{}", fit.t);
    }
}
