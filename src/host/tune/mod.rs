//! Hyper-parameter search for both heads (`mlmap tune`).
//!
//! The ML head depends only on `(B_ML, lambda_ML)` and the MAP head only on
//! `(B_MAP, lambda_MAP)`, so each head is searched on its own grid. The expensive parts
//! are done once: the Gaussian prior of every validation logit once for the whole
//! search, the likelihoods once per bin count (one histogram lookup per class and row).
//! Each lambda candidate is then one pass of additions and the layer's own
//! normalisation ([`scores_from_evidence`]), so a candidate's scores are bit for bit
//! the scores the layer will produce with the written table. The objective is
//! accumulated on the fly by the metrics module's [`Accumulator`], without storing
//! scores.
//!
//! [`search`] works on rows and histograms; [`tune`] runs the whole job on a training
//! set and a validation file and builds the table of the best candidates.

mod pipeline;

use std::prelude::rust_2021::*;
use std::{format, vec};

pub use self::pipeline::{tune, TuneParams, Tuned};
use crate::host::metrics::{Accumulator, MetricsConfig, Parts};
use crate::host::names::{Name, Named};
use crate::{scores_from_evidence, Gaussian, Head, Histogram, Libm, UpperTail};

/// What the search minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Objective {
    /// Expected calibration error, 10 bins `((m-1)/M, m/M]` (DESIGN §1.5 default).
    Ece,
    /// Mean negative log-likelihood of the labelled rows.
    Nll,
    /// Mean Brier score over all rows.
    Brier,
}

impl Named for Objective {
    const WHAT: &'static str = "objective";
    const NAMES: &'static [Name<Self>] = &[
        Name::new(
            Self::Ece,
            "ece",
            "Expected calibration error (10 bins, DESIGN §1.5)",
        ),
        Name::new(
            Self::Nll,
            "nll",
            "Negative log-likelihood of the labelled rows",
        ),
        Name::new(Self::Brier, "brier", "Brier score over all rows"),
    ];
}

impl Objective {
    /// The metrics an [`Accumulator`] needs to compute this objective alone.
    fn parts(self) -> Parts {
        Parts {
            calibration: self == Self::Ece,
            nll: self == Self::Nll,
            brier: self == Self::Brier,
        }
    }
}

crate::host::names::display_and_parse!(Objective);

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
    /// Top-1 accuracy of the labelled rows (DESIGN §1.5); for the best candidates only.
    pub accuracy: Option<f64>,
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

/// ECE bins of the tuning objective (DESIGN §1.5 default).
const ECE_BINS: usize = 10;

/// Per-row evidence of one head for one set of histograms: `L` (ML) or `L * P` (MAP,
/// `P` only where `L > 0`, as the layer computes it).
fn evidence_into(
    val: &ValRows<'_>,
    hists: &[Histogram<Vec<f32>>],
    pdf: &[f32],
    tail: UpperTail,
    head: Head,
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
                Head::Ml => l,
                Head::Map if l > 0.0 => l * p,
                Head::Map | Head::Bayes => 0.0,
            };
        }
    }
}

/// Scores one lambda over every row given the evidence: the objective alone, or all
/// metrics (`ece`, `nll`, `brier`, `accuracy`) with `all`.
fn score(
    val: &ValRows<'_>,
    evidence: &[f32],
    bins: usize,
    lambda: f32,
    objective: Objective,
    all: bool,
) -> Candidate {
    let k = val.k;
    let mut scores = vec![0.0f32; k];
    let mut scratch = vec![0.0f32; k];
    let cfg = MetricsConfig {
        bins: ECE_BINS,
        ..MetricsConfig::default()
    };
    let parts = if all { Parts::ALL } else { objective.parts() };
    let Ok(mut acc) = Accumulator::new(&cfg, parts) else {
        return Candidate {
            bins,
            lambda,
            objective: f64::INFINITY,
            ece: None,
            nll: None,
            brier: None,
            accuracy: None,
        };
    };
    let rows = evidence
        .chunks_exact(k)
        .zip(val.logits.chunks_exact(k))
        .zip(val.objectness)
        .zip(val.labels);
    for (((e, x), &os), &label) in rows {
        if scores_from_evidence(e, lambda, os, &mut scores, &mut scratch).is_ok() {
            acc.add(&scores, x, label);
        }
    }
    let (ece, nll, brier) = (acc.ece(), acc.nll(), acc.brier());
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
        accuracy: acc.accuracy(),
    }
}

/// The candidates of one head, best first.
#[derive(Debug, Clone, PartialEq)]
pub struct HeadCandidates {
    /// The head.
    pub head: Head,
    /// Every candidate, best first.
    pub candidates: Vec<Candidate>,
}

/// The search's result: every candidate of each head searched, best first.
#[derive(Debug, Clone, PartialEq)]
pub struct TuneResult {
    /// One entry per head, in the order of [`SearchParams::bins`].
    pub heads: Vec<HeadCandidates>,
}

impl TuneResult {
    /// The candidates of `head`, best first (empty when it was not searched).
    pub fn candidates(&self, head: Head) -> &[Candidate] {
        self.heads
            .iter()
            .find(|h| h.head == head)
            .map_or(&[], |h| h.candidates.as_slice())
    }
}

/// What [`search`] searches.
///
/// # Parameters
///
/// | Name | Purpose |
/// |---|---|
/// | `val` | the validation rows candidates are scored on |
/// | `priors` | the `K` fitted Gaussians (used by the MAP head) |
/// | `tail` | the likelihood above the last edge |
/// | `bins` | the bin counts to try, per head (each head is searched on its own) |
/// | `lambdas` | the smoothing values to try (every head) |
/// | `objective` | what to minimise |
/// | `detail` | how many of the best candidates per head get every metric |
#[derive(Debug, Clone, Copy)]
pub struct SearchParams<'a> {
    /// Validation rows.
    pub val: ValRows<'a>,
    /// The `K` fitted priors.
    pub priors: &'a [Gaussian],
    /// Likelihood above the last edge.
    pub tail: UpperTail,
    /// Bin counts to try, per head.
    pub bins: &'a [(Head, Vec<usize>)],
    /// Lambdas to try.
    pub lambdas: &'a [f32],
    /// What to minimise.
    pub objective: Objective,
    /// How many of the best candidates per head get every metric.
    pub detail: usize,
}

impl SearchParams<'_> {
    /// Every distinct bin count of every head, ascending.
    pub fn distinct_bins(&self) -> Vec<usize> {
        let mut all: Vec<usize> = self.bins.iter().flat_map(|(_, b)| b).copied().collect();
        all.sort_unstable();
        all.dedup();
        all
    }
}

/// Searches every head of `p.bins`.
///
/// `histograms(b)` returns the K fitted histograms with `b` bins (called once per
/// distinct bin count). Every candidate gets its objective; the best `p.detail` of
/// each head also get every metric of [`Candidate`]. The bin counts are shared among the
/// machine's cores. `progress(done, total)` is called as bin counts complete.
///
/// # Errors
///
/// [`TuneError`] for an inconsistent validation set, an empty grid, or a failing
/// `histograms`.
pub fn search<H>(
    p: &SearchParams<'_>,
    mut histograms: H,
    progress: impl Fn(usize, usize) + Sync,
) -> Result<TuneResult, TuneError>
where
    H: FnMut(usize) -> Result<Vec<Histogram<Vec<f32>>>, String>,
{
    let val = &p.val;
    let k = val.k;
    let n = val.labels.len();
    if k < 2 || p.priors.len() != k || val.logits.len() != n * k || val.objectness.len() != n {
        return Err(TuneError::BadValidationSet(
            "logits, objectness, labels and priors disagree in size".into(),
        ));
    }
    if n == 0 {
        return Err(TuneError::BadValidationSet("no rows".into()));
    }
    if p.lambdas.is_empty() || p.bins.iter().all(|(_, b)| b.is_empty()) {
        return Err(TuneError::EmptyGrid);
    }
    // The prior of every validation logit, once.
    let pdf: Vec<f32> = val
        .logits
        .chunks_exact(k)
        .flat_map(|row| row.iter().zip(p.priors).map(|(&x, g)| g.pdf::<Libm>(x)))
        .collect();
    let all = p.distinct_bins();
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
        let mut found: Vec<Vec<Candidate>> = vec![Vec::new(); p.bins.len()];
        for (b, hists) in part {
            for ((head, set), out) in p.bins.iter().zip(&mut found) {
                if set.contains(b) {
                    evidence_into(val, hists, &pdf, p.tail, *head, &mut evidence);
                    for &l in p.lambdas {
                        out.push(score(val, &evidence, *b, l, p.objective, false));
                    }
                }
            }
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(d, all.len());
        }
        found
    };
    let chunk = work.len().div_ceil(threads);
    let parts: Vec<Vec<Vec<Candidate>>> = std::thread::scope(|s| {
        let handles: Vec<_> = work
            .chunks(chunk)
            .map(|part| s.spawn(move || sweep(part)))
            .collect();
        handles.into_iter().filter_map(|h| h.join().ok()).collect()
    });
    let mut heads: Vec<HeadCandidates> = p
        .bins
        .iter()
        .map(|(head, _)| HeadCandidates {
            head: *head,
            candidates: Vec::new(),
        })
        .collect();
    for part in parts {
        for (h, found) in heads.iter_mut().zip(part) {
            h.candidates.extend(found);
        }
    }
    // Stable order: objective, then fewer bins, then smaller lambda.
    let order = |a: &Candidate, b: &Candidate| {
        a.objective
            .total_cmp(&b.objective)
            .then(a.bins.cmp(&b.bins))
            .then(a.lambda.total_cmp(&b.lambda))
    };
    let mut evidence = vec![0.0f32; n * k];
    for (h, (_, set)) in heads.iter_mut().zip(p.bins) {
        if h.candidates.len() != set.len() * p.lambdas.len() {
            return Err(TuneError::Histogram("a search thread failed".into()));
        }
        h.candidates.sort_by(order);
        // Every metric for the best candidates.
        for c in h.candidates.iter_mut().take(p.detail) {
            if let Some((_, hists)) = work.iter().find(|(b, _)| *b == c.bins) {
                evidence_into(val, hists, &pdf, p.tail, h.head, &mut evidence);
                *c = score(val, &evidence, c.bins, c.lambda, p.objective, true);
            }
        }
    }
    Ok(TuneResult { heads })
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
