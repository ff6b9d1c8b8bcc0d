//! The host side of the conformal class sets (DESIGN §8): thresholds fitted on labelled
//! calibration rows, the conformal section written into a table file, the sets of many
//! rows, their coverage, and the split-conformal LAC baseline on the softmax that the
//! evaluation compares them with.
//!
//! Every score comes from the layer's [`TableView::score_into`](mlmap_core::TableView),
//! and every set from the layer's [`ConformalSpec`], so what the host fits and reports
//! is what the device computes.

use mlmap_core::{
    conformal_section_len, section_of, set_words, table_of, threshold_rank,
    write_conformal_section, ConformalError, ConformalSpec, DynTable, Head, InferError,
    CONFORMAL_MAGIC, MONITOR_MAGIC, QUANTIZED_MAGIC,
};

/// Thresholds fitted for one head and level.
#[derive(Debug, Clone, PartialEq)]
pub struct Fitted {
    /// The head whose scores are thresholded.
    pub head: Head,
    /// The level, as stored (`f32`).
    pub alpha: f32,
    /// Calibration rows per class, `n_c`.
    pub rows: Vec<u32>,
    /// The threshold of each class, `t_c` (`-inf` when its rank is 0).
    pub thresholds: Vec<f32>,
}

/// The scores of `head` for every row (`logits`: n x K row-major, `objectness`: n), n x K.
///
/// # Errors
///
/// The first row the layer refuses, as its index and the error.
pub fn scores(
    table: &DynTable,
    head: Head,
    logits: &[f32],
    objectness: &[f32],
) -> Result<Vec<f32>, (usize, InferError)> {
    let k = table.k();
    let view = table.view();
    let cats = table.bayes_head().map_or(k, |b| b.categories()).max(k);
    let mut scratch = vec![0.0f32; cats];
    let mut out = vec![0.0f32; objectness.len() * k];
    for (i, (row, &os)) in out.chunks_exact_mut(k).zip(objectness).enumerate() {
        let x = logits
            .get(i * k..(i + 1) * k)
            .ok_or((i, InferError::Length))?;
        view.score_into(head, x, os, row, &mut scratch)
            .map_err(|e| (i, e))?;
    }
    Ok(out)
}

/// Fits the thresholds of DESIGN §8 from the scores of `head` (n x K, from [`scores`])
/// and the rows' labels (`Some(class)`; background and unlabelled rows, `None`, are
/// not calibration rows): per class `c`, `t_c` is the `floor((n_c + 1) alpha)`-th
/// smallest score of class `c` over the `n_c` rows labelled `c`, `-inf` when that rank is
/// 0. `alpha` is rounded to `f32` first, as the section stores it.
pub fn fit(head: Head, alpha: f64, k: usize, scores: &[f32], labels: &[Option<usize>]) -> Fitted {
    let alpha = alpha as f32;
    let mut per: Vec<Vec<f32>> = vec![Vec::new(); k];
    for (row, label) in scores.chunks_exact(k.max(1)).zip(labels) {
        if let Some(c) = *label {
            if let (Some(v), Some(&s)) = (per.get_mut(c), row.get(c)) {
                v.push(s);
            }
        }
    }
    let mut rows = Vec::with_capacity(k);
    let mut thresholds = Vec::with_capacity(k);
    for mut v in per {
        v.sort_by(f32::total_cmp);
        let n = u32::try_from(v.len()).unwrap_or(u32::MAX);
        let r = threshold_rank(n, alpha) as usize;
        rows.push(n);
        thresholds.push(
            r.checked_sub(1)
                .and_then(|i| v.get(i))
                .copied()
                .unwrap_or(f32::NEG_INFINITY),
        );
    }
    Fitted {
        head,
        alpha,
        rows,
        thresholds,
    }
}

/// The file `bytes` (a table, with or without sections) with a conformal section for
/// `fitted` in place of any it had: the table, then its quantized and monitor sections
/// when it has them, then the conformal section.
///
/// # Errors
///
/// The errors of [`write_conformal_section`].
pub fn with_conformal(bytes: &[u8], fitted: &Fitted) -> Result<Vec<u8>, ConformalError> {
    let table_bytes = table_of(bytes);
    let crc = table_bytes
        .len()
        .checked_sub(4)
        .and_then(|at| table_bytes.get(at..))
        .and_then(|b| <[u8; 4]>::try_from(b).ok())
        .map_or(0, u32::from_le_bytes);
    let mut section = vec![0u8; conformal_section_len(fitted.rows.len())];
    write_conformal_section(
        &mut section,
        crc,
        fitted.head,
        fitted.alpha,
        &fitted.rows,
        &fitted.thresholds,
    )?;
    let mut out = table_bytes.to_vec();
    for magic in [QUANTIZED_MAGIC, MONITOR_MAGIC] {
        if let Some(s) = section_of(bytes, magic) {
            out.extend_from_slice(s);
        }
    }
    out.extend_from_slice(&section);
    Ok(out)
}

/// Whether `bytes` has a conformal section (of any content).
pub fn has_conformal(bytes: &[u8]) -> bool {
    section_of(bytes, CONFORMAL_MAGIC).is_some()
}

/// The sets of every row of `scores` (n x K, the section's head's), one `Vec<bool>` of
/// K per row, from the layer's [`ConformalSpec::set_of`].
///
/// # Errors
///
/// The first row the layer refuses (a NaN score), as its index and the error.
pub fn sets(spec: &ConformalSpec<'_>, scores: &[f32]) -> Result<Vec<bool>, (usize, InferError)> {
    let k = spec.k();
    let mut mask = vec![0u32; set_words(k)];
    let mut out = Vec::with_capacity(scores.len());
    for (i, row) in scores.chunks_exact(k.max(1)).enumerate() {
        spec.set_of(row, &mut mask).map_err(|e| (i, e))?;
        out.extend((0..k).map(|c| mask.get(c / 32).is_some_and(|w| w >> (c % 32) & 1 == 1)));
    }
    Ok(out)
}

/// The split-conformal LAC baseline on a softmax (DESIGN §8): the nonconformity of a
/// calibration row is `1 - p_y` (`p`: its softmax scores, `y` its class); `qhat` is the
/// `ceil((n + 1)(1 - alpha))`-th smallest of the `n` of them (`+inf` beyond `n`), and a
/// row's set is `{c : 1 - p_c <= qhat}`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lac {
    /// The threshold on `1 - p`.
    pub qhat: f64,
    /// Calibration rows.
    pub rows: usize,
}

impl Lac {
    /// Fits `qhat` on the softmax scores `probs` (n x K) of the rows labelled with a
    /// class (`labels`; `None` rows are skipped).
    pub fn fit(alpha: f64, k: usize, probs: &[f64], labels: &[Option<usize>]) -> Self {
        let mut s: Vec<f64> = probs
            .chunks_exact(k.max(1))
            .zip(labels)
            .filter_map(|(p, l)| l.and_then(|c| p.get(c)).map(|&p| 1.0 - p))
            .collect();
        s.sort_by(f64::total_cmp);
        let n = s.len();
        let rank = ((n as f64 + 1.0) * (1.0 - alpha)).ceil() as usize;
        let qhat = rank
            .checked_sub(1)
            .and_then(|i| s.get(i))
            .copied()
            .unwrap_or(if rank == 0 {
                f64::NEG_INFINITY
            } else {
                f64::INFINITY
            });
        Self { qhat, rows: n }
    }

    /// Whether class `c`, of softmax score `p_c`, is in the set.
    #[inline]
    pub fn contains(&self, p: f64) -> bool {
        1.0 - p <= self.qhat
    }
}

/// Coverage and size of the sets of labelled rows, and the share of empty sets of
/// unseen rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Coverage {
    /// Per class: (rows labelled with it, the share of them whose set holds it).
    pub per_class: Vec<(usize, f64)>,
    /// Mean set size over the rows labelled with a class.
    pub mean_size: f64,
    /// Share of empty sets over the rows labelled with a class.
    pub empty_known: f64,
    /// Share of empty sets over the unseen rows, when there are any.
    pub empty_unseen: Option<f64>,
}

/// The coverage of sets (`sets`: n x K, `true` when the class is in the set) over rows
/// labelled `labels`, and the share of empty sets among `unseen` (m x K).
pub fn coverage(k: usize, sets: &[bool], labels: &[Option<usize>], unseen: &[bool]) -> Coverage {
    let mut hit = vec![(0usize, 0usize); k];
    let (mut size, mut empty, mut n) = (0usize, 0usize, 0usize);
    for (set, label) in sets.chunks_exact(k.max(1)).zip(labels) {
        let Some(c) = *label else { continue };
        let s = set.iter().filter(|&&b| b).count();
        size += s;
        empty += usize::from(s == 0);
        n += 1;
        if let Some(h) = hit.get_mut(c) {
            h.0 += 1;
            h.1 += usize::from(set.get(c).copied().unwrap_or(false));
        }
    }
    let share = |a: usize, b: usize| {
        if b == 0 {
            f64::NAN
        } else {
            a as f64 / b as f64
        }
    };
    let m = unseen.len() / k.max(1);
    let unseen_empty = unseen
        .chunks_exact(k.max(1))
        .filter(|s| s.iter().all(|&b| !b))
        .count();
    Coverage {
        per_class: hit.iter().map(|&(n, h)| (n, share(h, n))).collect(),
        mean_size: share(size, n),
        empty_known: share(empty, n),
        empty_unseen: (m > 0).then(|| share(unseen_empty, m)),
    }
}

/// The softmax baseline's scores `OS * softmax(x)` of every row (n x K, `f64`): what the
/// LAC baseline thresholds.
///
/// # Errors
///
/// The first row refused, as its index and the error.
pub fn softmax_scores(
    k: usize,
    logits: &[f64],
    objectness: &[f64],
) -> Result<Vec<f64>, (usize, InferError)> {
    let mut out = vec![0.0f64; objectness.len() * k];
    for (i, (row, &os)) in out.chunks_exact_mut(k.max(1)).zip(objectness).enumerate() {
        let x = logits
            .get(i * k..(i + 1) * k)
            .ok_or((i, InferError::Length))?;
        crate::baselines::softmax(x, os, row).map_err(|e| (i, e))?;
    }
    Ok(out)
}

/// What `eval` reports of the conformal sets (DESIGN §8): the coverage of the table's
/// sets and, when calibration rows are given, of the LAC baseline at the same alpha.
#[derive(Debug, Clone, PartialEq)]
pub struct ConformalEval {
    /// The head of the table's sets.
    pub head: Head,
    /// Their level.
    pub alpha: f32,
    /// The table's sets on the test (and unseen) rows.
    pub sets: Coverage,
    /// The LAC baseline fitted on the calibration rows, and its sets' coverage.
    pub lac: Option<(Lac, Coverage)>,
}

/// Rows as the evaluation reads them: n x K logits, n objectness, n labels.
#[derive(Debug, Clone, Copy)]
pub struct Rows<'a> {
    /// n x K logits, row-major.
    pub logits: &'a [f64],
    /// n objectness scores.
    pub objectness: &'a [f64],
    /// n labels (`None`: background or unlabelled).
    pub labels: &'a [Option<usize>],
}

/// Which rows an evaluation error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Which {
    /// The test rows.
    Test,
    /// The calibration rows of the LAC baseline.
    Calibration,
    /// The unseen rows.
    Unseen,
}

/// Evaluates the sets of `spec` (over `table`) on `test`, the share of empty sets on
/// `unseen`, and the LAC baseline calibrated on `calibration` at the same alpha.
///
/// # Errors
///
/// The rows, the row index and the layer's error of the first row refused.
pub fn evaluate(
    table: &DynTable,
    spec: &ConformalSpec<'_>,
    test: Rows<'_>,
    calibration: Option<Rows<'_>>,
    unseen: Option<Rows<'_>>,
) -> Result<ConformalEval, (Which, usize, InferError)> {
    let k = table.k();
    let f32s = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
    let ours = |r: Rows<'_>, w: Which| -> Result<Vec<bool>, (Which, usize, InferError)> {
        let s = scores(table, spec.head(), &f32s(r.logits), &f32s(r.objectness))
            .map_err(|(i, e)| (w, i, e))?;
        sets(spec, &s).map_err(|(i, e)| (w, i, e))
    };
    let test_sets = ours(test, Which::Test)?;
    let unseen_sets = unseen.map(|u| ours(u, Which::Unseen)).transpose()?;
    let sets_cov = coverage(
        k,
        &test_sets,
        test.labels,
        unseen_sets.as_deref().unwrap_or_default(),
    );
    let lac = match calibration {
        None => None,
        Some(cal) => {
            let p = softmax_scores(k, cal.logits, cal.objectness)
                .map_err(|(i, e)| (Which::Calibration, i, e))?;
            let lac = Lac::fit(f64::from(spec.alpha()), k, &p, cal.labels);
            let lac_sets = |r: Rows<'_>,
                            w: Which|
             -> Result<Vec<bool>, (Which, usize, InferError)> {
                let p = softmax_scores(k, r.logits, r.objectness).map_err(|(i, e)| (w, i, e))?;
                Ok(p.iter().map(|&p| lac.contains(p)).collect())
            };
            let t = lac_sets(test, Which::Test)?;
            let u = unseen.map(|u| lac_sets(u, Which::Unseen)).transpose()?;
            Some((
                lac,
                coverage(k, &t, test.labels, u.as_deref().unwrap_or_default()),
            ))
        }
    };
    Ok(ConformalEval {
        head: spec.head(),
        alpha: spec.alpha(),
        sets: sets_cov,
        lac,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_takes_the_ranked_score() {
        // Class 0: 19 rows of scores 0.01..0.19; alpha 0.1: rank floor(20 * 0.1) = 2.
        let k = 2;
        let mut scores = Vec::new();
        let mut labels = Vec::new();
        for i in 1..=19 {
            scores.extend([i as f32 / 100.0, 0.0]);
            labels.push(Some(0));
        }
        // Class 1: 3 rows, rank floor(4 * 0.1) = 0: -inf.
        for _ in 0..3 {
            scores.extend([0.0, 0.5]);
            labels.push(Some(1));
        }
        labels.push(None);
        scores.extend([0.0, 0.0]);
        let f = fit(Head::Ml, 0.1, k, &scores, &labels);
        assert_eq!(f.rows, vec![19, 3]);
        assert_eq!(f.thresholds, vec![0.02, f32::NEG_INFINITY]);
    }

    #[test]
    fn lac_rank() {
        // 9 rows, alpha 0.2: ceil(10 * 0.8) = 8th smallest of 1 - p.
        let probs: Vec<f64> = (1..=9).flat_map(|i| [i as f64 / 10.0, 0.0]).collect();
        let labels = vec![Some(0); 9];
        let l = Lac::fit(0.2, 2, &probs, &labels);
        assert!((l.qhat - 0.8).abs() < 1e-12);
        assert!(Lac::fit(0.01, 2, &probs, &labels).qhat.is_infinite());
    }
}
