//! Hyper-parameter search for both heads (`mlmap tune`).
//!
//! The ML head depends only on `(B_ML, lambda_ML)` and the MAP head only on
//! `(B_MAP, lambda_MAP)`, so each head is searched on its own grid. The expensive parts
//! are done once: the Gaussian prior of every validation logit once for the whole
//! search, the likelihoods once per bin count (one histogram lookup per class and row).
//! Each lambda candidate is then one pass of additions and the layer's own
//! normalisation ([`scores_from_evidence`]), so a candidate's scores are bit for bit
//! the scores the layer will produce with the written table. The objective is
//! accumulated on the fly, without storing scores.

use std::prelude::rust_2021::*;
use std::{format, vec};

use crate::host::metrics::{Binning, Edges};
use crate::{scores_from_evidence, Gaussian, Histogram, Libm, UpperTail};

/// What the search minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Objective {
    /// Expected calibration error, 10 bins `((m-1)/M, m/M]` (DESIGN §1.5 default).
    Ece,
    /// Mean negative log-likelihood of the labelled rows.
    Nll,
    /// Mean Brier score over all rows.
    Brier,
}

/// Validation rows, in the layer's precision.
#[derive(Debug, Clone, Copy)]
pub struct ValRows<'a> {
    /// Number of classes K.
    pub k: usize,
    /// N x K logits, row-major.
    pub logits: &'a [f32],
    /// N objectness scores.
    pub objectness: &'a [f32],
    /// N labels: `Some(class)` or `None` for background.
    pub labels: &'a [Option<usize>],
}

/// One scored grid point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Bin count.
    pub bins: usize,
    /// Smoothing lambda (as stored in the table, `f32`).
    pub lambda: f32,
    /// The objective's value (lower is better; a missing NLL counts as +inf).
    pub objective: f64,
    /// Expected calibration error (10 bins, DESIGN default binning); computed for the
    /// best candidates only (see [`search`]).
    pub ece: Option<f64>,
    /// Mean NLL of the labelled rows; for the best candidates only.
    pub nll: Option<f64>,
    /// Mean Brier score; for the best candidates only.
    pub brier: Option<f64>,
}

/// Why a search could not run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TuneError {
    /// The validation set is empty or its slices disagree in length.
    BadValidationSet(String),
    /// The grid is empty.
    EmptyGrid,
    /// A histogram could not be built for a bin count.
    Histogram(String),
}

impl std::fmt::Display for TuneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::BadValidationSet(m) => write!(f, "validation set: {m}"),
            Self::EmptyGrid => f.write_str("the search grid is empty"),
            Self::Histogram(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for TuneError {}

/// Parses a bin-count set: `N`, `A..B` (inclusive) or `A,B,C`; every count >= 1.
///
/// # Errors
///
/// A message naming what is wrong.
pub fn parse_bins(spec: &str) -> Result<Vec<usize>, String> {
    let num = |s: &str| -> Result<usize, String> {
        let n: usize = s
            .trim()
            .parse()
            .map_err(|_| format!("`{s}` is not a bin count"))?;
        if n == 0 || n > usize::from(u16::MAX) {
            return Err(format!("bin count {n} is not in 1..=65535"));
        }
        Ok(n)
    };
    let mut out: Vec<usize> = if let Some((a, b)) = spec.split_once("..") {
        let (a, b) = (num(a)?, num(b.trim_start_matches('='))?);
        if a > b {
            return Err(format!("empty range `{spec}`"));
        }
        (a..=b).collect()
    } else {
        spec.split(',').map(num).collect::<Result<_, _>>()?
    };
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// A log-spaced grid from `min` to `max` inclusive with `per_decade` points per decade,
/// rounded to `f32` (the precision the table stores).
///
/// # Errors
///
/// When the bounds are not `0 < min <= max <= MAX_LAMBDA` or `per_decade` is 0.
pub fn lambda_grid(min: f64, max: f64, per_decade: usize) -> Result<Vec<f32>, String> {
    if !(min > 0.0 && min <= max && max <= f64::from(crate::MAX_LAMBDA)) || per_decade == 0 {
        return Err(format!(
            "lambda grid needs 0 < min <= max <= {} and at least one point per decade",
            crate::MAX_LAMBDA
        ));
    }
    let decades = (max / min).log10();
    let steps = (decades * per_decade as f64).round() as usize;
    let mut out: Vec<f32> = (0..=steps)
        .map(|s| {
            let t = if steps == 0 {
                0.0
            } else {
                s as f64 / steps as f64
            };
            (min * (max / min).powf(t)) as f32
        })
        .filter(|&l| l > 0.0)
        .collect();
    out.dedup();
    Ok(out)
}

/// Running sums of the objectives over the rows of one candidate; `only` restricts
/// the work to one objective (the NLL's logarithm is the costly part).
struct Accumulator<'e> {
    only: Option<Objective>,
    /// The DESIGN §1.5 bins, shared with [`crate::host::metrics`].
    edges: &'e Edges,
    bins: [(u64, f64, f64); ECE_BINS],
    n: u64,
    nll_sum: f64,
    nll_n: u64,
    brier_sum: f64,
}

/// ECE bins of the tuning objective (DESIGN §1.5 default).
const ECE_BINS: usize = 10;

impl<'e> Accumulator<'e> {
    fn new(only: Option<Objective>, edges: &'e Edges) -> Self {
        Self {
            only,
            edges,
            bins: [(0, 0.0, 0.0); ECE_BINS],
            n: 0,
            nll_sum: 0.0,
            nll_n: 0,
            brier_sum: 0.0,
        }
    }

    fn wants(&self, o: Objective) -> bool {
        self.only.is_none_or(|x| x == o)
    }

    fn add(&mut self, scores: &[f32], label: Option<usize>) {
        self.n += 1;
        if self.wants(Objective::Ece) {
            let best = crate::argmax(scores);
            let conf = f64::from(scores.get(best).copied().unwrap_or(0.0));
            let correct = label == Some(best);
            if let Some(bin) = self.bins.get_mut(self.edges.bin(conf)) {
                bin.0 += 1;
                bin.1 += conf;
                bin.2 += if correct { 1.0 } else { 0.0 };
            }
        }
        if self.wants(Objective::Nll) {
            if let Some(l) = label {
                let s = f64::from(scores.get(l).copied().unwrap_or(0.0));
                self.nll_sum -= s.max(1e-12).ln();
                self.nll_n += 1;
            }
        }
        if self.wants(Objective::Brier) {
            for (i, &s) in scores.iter().enumerate() {
                let y = if label == Some(i) { 1.0 } else { 0.0 };
                let d = f64::from(s) - y;
                self.brier_sum += d * d;
            }
        }
    }

    fn finish(&self, bins: usize, lambda: f32, objective: Objective) -> Candidate {
        let n = self.n.max(1) as f64;
        let ece = self.wants(Objective::Ece).then(|| {
            self.bins
                .iter()
                .filter(|b| b.0 > 0)
                .map(|&(c, conf, acc)| (c as f64 / n) * (acc / c as f64 - conf / c as f64).abs())
                .sum()
        });
        let nll = (self.wants(Objective::Nll) && self.nll_n > 0)
            .then(|| self.nll_sum / self.nll_n as f64);
        let brier = self.wants(Objective::Brier).then(|| self.brier_sum / n);
        let value = match objective {
            Objective::Ece => ece,
            Objective::Nll => nll,
            Objective::Brier => brier,
        };
        Candidate {
            bins,
            lambda,
            objective: value.unwrap_or(f64::INFINITY),
            ece,
            nll,
            brier,
        }
    }
}

/// Which head a sweep scores.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum HeadKind {
    Ml,
    Map,
}

/// Per-row evidence of one head for one set of histograms: `L` (ML) or `L * P` (MAP,
/// `P` only where `L > 0`, as the layer computes it).
fn evidence_into(
    val: &ValRows<'_>,
    hists: &[Histogram<Vec<f32>>],
    pdf: &[f32],
    tail: UpperTail,
    head: HeadKind,
    out: &mut [f32],
) {
    let k = val.k;
    for ((e_row, x_row), p_row) in out
        .chunks_exact_mut(k)
        .zip(val.logits.chunks_exact(k))
        .zip(pdf.chunks_exact(k))
    {
        for (((e, &x), h), &p) in e_row.iter_mut().zip(x_row).zip(hists).zip(p_row) {
            let l = h.likelihood(x, tail);
            *e = match head {
                HeadKind::Ml => l,
                HeadKind::Map if l > 0.0 => l * p,
                HeadKind::Map => 0.0,
            };
        }
    }
}

/// Scores one lambda over every row given the evidence.
fn score(
    val: &ValRows<'_>,
    evidence: &[f32],
    bins: usize,
    lambda: f32,
    objective: Objective,
    only: Option<Objective>,
) -> Candidate {
    let k = val.k;
    let mut scores = vec![0.0f32; k];
    let mut scratch = vec![0.0f32; k];
    let edges = Edges::new(Binning::Design, ECE_BINS);
    let mut acc = Accumulator::new(only, &edges);
    for ((e, &os), &label) in evidence.chunks_exact(k).zip(val.objectness).zip(val.labels) {
        if scores_from_evidence(e, lambda, os, &mut scores, &mut scratch).is_ok() {
            acc.add(&scores, label);
        }
    }
    acc.finish(bins, lambda, objective)
}

/// The search's result: every candidate of each head, best first.
#[derive(Debug, Clone, PartialEq)]
pub struct TuneResult {
    /// ML candidates, best first.
    pub ml: Vec<Candidate>,
    /// MAP candidates, best first.
    pub map: Vec<Candidate>,
}

/// Searches both heads.
///
/// `histograms(b)` returns the K fitted histograms with `b` bins (called once per
/// distinct bin count); `priors` are the K fitted Gaussians. Every candidate gets its
/// objective; the best `detail` of each head also get all three metrics. The bin
/// counts are shared among the machine's cores. `progress(done, total)` is called as
/// bin counts complete.
///
/// # Errors
///
/// [`TuneError`] for an inconsistent validation set, an empty grid, or a failing
/// `histograms`.
#[allow(clippy::too_many_arguments)]
pub fn search<H>(
    mut histograms: H,
    priors: &[Gaussian],
    tail: UpperTail,
    val: &ValRows<'_>,
    bins_ml: &[usize],
    bins_map: &[usize],
    lambdas: &[f32],
    objective: Objective,
    detail: usize,
    progress: impl Fn(usize, usize) + Sync,
) -> Result<TuneResult, TuneError>
where
    H: FnMut(usize) -> Result<Vec<Histogram<Vec<f32>>>, String>,
{
    let k = val.k;
    let n = val.labels.len();
    if k < 2 || priors.len() != k || val.logits.len() != n * k || val.objectness.len() != n {
        return Err(TuneError::BadValidationSet(
            "logits, objectness, labels and priors disagree in size".into(),
        ));
    }
    if n == 0 {
        return Err(TuneError::BadValidationSet("no rows".into()));
    }
    if lambdas.is_empty() || (bins_ml.is_empty() && bins_map.is_empty()) {
        return Err(TuneError::EmptyGrid);
    }
    // The prior of every validation logit, once.
    let pdf: Vec<f32> = val
        .logits
        .chunks_exact(k)
        .flat_map(|row| row.iter().zip(priors).map(|(&x, g)| g.pdf::<Libm>(x)))
        .collect();
    let mut all: Vec<usize> = bins_ml.iter().chain(bins_map).copied().collect();
    all.sort_unstable();
    all.dedup();
    let mut work = Vec::with_capacity(all.len());
    for &b in &all {
        let hists = histograms(b).map_err(TuneError::Histogram)?;
        if hists.len() != k {
            return Err(TuneError::Histogram(format!(
                "{b} bins: expected {k} histograms"
            )));
        }
        work.push((b, hists));
    }
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .clamp(1, work.len());
    let done = std::sync::atomic::AtomicUsize::new(0);
    let sweep = |part: &[(usize, Vec<Histogram<Vec<f32>>>)]| {
        let mut evidence = vec![0.0f32; n * k];
        let (mut ml, mut map) = (Vec::new(), Vec::new());
        for (b, hists) in part {
            for (head, set, out) in [
                (HeadKind::Ml, bins_ml, &mut ml),
                (HeadKind::Map, bins_map, &mut map),
            ] {
                if set.contains(b) {
                    evidence_into(val, hists, &pdf, tail, head, &mut evidence);
                    for &l in lambdas {
                        out.push(score(val, &evidence, *b, l, objective, Some(objective)));
                    }
                }
            }
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(d, all.len());
        }
        (ml, map)
    };
    let chunk = work.len().div_ceil(threads);
    let parts: Vec<(Vec<Candidate>, Vec<Candidate>)> = std::thread::scope(|s| {
        let handles: Vec<_> = work
            .chunks(chunk)
            .map(|part| s.spawn(move || sweep(part)))
            .collect();
        handles.into_iter().filter_map(|h| h.join().ok()).collect()
    });
    let (mut ml, mut map): (Vec<Candidate>, Vec<Candidate>) = (Vec::new(), Vec::new());
    for (a, b) in parts {
        ml.extend(a);
        map.extend(b);
    }
    let expected = |set: &[usize]| set.len() * lambdas.len();
    if ml.len() != expected(bins_ml) || map.len() != expected(bins_map) {
        return Err(TuneError::Histogram("a search thread failed".into()));
    }
    // Stable order: objective, then fewer bins, then smaller lambda.
    let order = |a: &Candidate, b: &Candidate| {
        a.objective
            .total_cmp(&b.objective)
            .then(a.bins.cmp(&b.bins))
            .then(a.lambda.total_cmp(&b.lambda))
    };
    ml.sort_by(order);
    map.sort_by(order);
    // All three metrics for the best candidates.
    let mut evidence = vec![0.0f32; n * k];
    for (head, cands) in [(HeadKind::Ml, &mut ml), (HeadKind::Map, &mut map)] {
        for c in cands.iter_mut().take(detail) {
            if let Some((_, hists)) = work.iter().find(|(b, _)| *b == c.bins) {
                evidence_into(val, hists, &pdf, tail, head, &mut evidence);
                *c = score(val, &evidence, c.bins, c.lambda, objective, None);
            }
        }
    }
    Ok(TuneResult { ml, map })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bin_sets() {
        assert_eq!(parse_bins("22").unwrap(), [22]);
        assert_eq!(parse_bins("4..7").unwrap(), [4, 5, 6, 7]);
        assert_eq!(parse_bins("4..=5").unwrap(), [4, 5]);
        assert_eq!(parse_bins("17, 5,17").unwrap(), [5, 17]);
        assert!(parse_bins("0").is_err());
        assert!(parse_bins("9..3").is_err());
        assert!(parse_bins("x").is_err());
    }

    #[test]
    fn lambda_grid_is_log_spaced() {
        let g = lambda_grid(1e-8, 1e-1, 1).unwrap();
        assert_eq!(g.len(), 8);
        for (i, &l) in g.iter().enumerate() {
            let want = 10f64.powi(i as i32 - 8);
            assert!((f64::from(l) - want).abs() / want < 1e-6, "{l} vs {want}");
        }
        assert!(lambda_grid(0.0, 1.0, 3).is_err());
        assert!(lambda_grid(1.0, 0.1, 3).is_err());
    }
}
