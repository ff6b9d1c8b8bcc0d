//! Random Bayes heads as counts, and the run-time shaped tables built from them (shared
//! with the quantized tests).

use mlmap::host::{BayesSpec, DynTable};

use super::*;

/// A Bayes head before validation, as counts.
#[derive(Debug, Clone)]
pub(crate) struct BayesParams {
    pub(crate) lambda: f32,
    pub(crate) bins: usize,
    pub(crate) ranges: Vec<(f32, f32)>,
    /// Rows per category (K classes, then background if present).
    pub(crate) rows: Vec<u64>,
    /// Counts, category-major: `(c K + j) B + b`.
    pub(crate) counts: Vec<u64>,
}

impl BayesParams {
    /// The terms `ln(count / n_c + lambda)` in `f64`, rounded to `f32`, logit-major.
    pub(crate) fn spec(&self) -> BayesSpec {
        let (k, b, cats) = (self.ranges.len(), self.bins, self.rows.len());
        let mut terms = Vec::with_capacity(k * b * cats);
        for j in 0..k {
            for bin in 0..b {
                for (c, &n) in self.rows.iter().enumerate() {
                    let count = self.counts[(c * k + j) * b + bin];
                    let h = count as f64 / n as f64;
                    terms.push((h + f64::from(self.lambda)).ln() as f32);
                }
            }
        }
        BayesSpec {
            lambda: self.lambda,
            rows: self.rows.clone(),
            ranges: self.ranges.clone(),
            terms,
            objectness: None,
        }
    }
}

pub(crate) fn bayes_params(
    k: usize,
    bins: usize,
    background: bool,
) -> impl Strategy<Value = BayesParams> {
    let cats = k + usize::from(background);
    let range = (
        prop_oneof![1 => Just(0.0f32), 4 => signed(decades(-3.0, 3.0))],
        decades(-2.0, 3.0),
    )
        .prop_map(|(lo, span)| (lo, lo + span));
    // Each category's training rows: a bin per logit.
    let category = prop::collection::vec(prop::collection::vec(0..bins, k), 1..=30);
    (
        prop_oneof![8 => decades(-6.0, 0.0), 1 => Just(1.0f32), 1 => Just(1e-6f32)],
        prop::collection::vec(range, k),
        prop::collection::vec(category, cats),
        prop_oneof![Just(1u64), Just(1000), Just(1_000_000_000_000)],
    )
        .prop_map(move |(lambda, ranges, data, scale)| {
            let mut counts = vec![0u64; cats * k * bins];
            let mut rows = Vec::with_capacity(cats);
            for (c, category_rows) in data.iter().enumerate() {
                rows.push(category_rows.len() as u64 * scale);
                for row in category_rows {
                    for (j, &b) in row.iter().enumerate() {
                        counts[(c * k + j) * bins + b] += scale;
                    }
                }
            }
            BayesParams {
                lambda,
                bins,
                ranges,
                rows,
                counts,
            }
        })
}

/// A random run-time shaped table of `k` classes (ML and MAP heads of 3 and 2 bins)
/// with a random Bayes head of `bins` bins.
pub(crate) fn dyn_table(
    k: usize,
    bins: usize,
    background: bool,
) -> impl Strategy<Value = (BayesParams, DynTable)> {
    (params(k, 3, 2), bayes_params(k, bins, background)).prop_filter_map(
        "parameters must make a valid table",
        move |(p, b)| {
            let classes = p
                .classes
                .iter()
                .enumerate()
                .map(|(i, c)| ClassSpec {
                    name: NAMES[i],
                    rows: c.rows,
                    mean: c.mean,
                    variance: c.variance,
                    ml_range: (c.ml.lo, c.ml.hi),
                    ml_freqs: c.ml.freqs.clone(),
                    map_range: (c.map.lo, c.map.hi),
                    map_freqs: c.map.freqs.clone(),
                })
                .collect();
            let t = DynTable::new(p.settings, classes).ok()?;
            // Every fitted head is valid: only the base table may be refused.
            let d = t
                .with_bayes(b.spec())
                .expect("a fitted Bayes head is valid");
            Some((b, d))
        },
    )
}
