//! Hyper-parameter search for the three heads (`mlmap tune`).
//!
//! The ML head depends only on `(B_ML, lambda_ML)`, the MAP head only on
//! `(B_MAP, lambda_MAP)` and the Bayes head only on `(B_Bayes, lambda_Bayes)`, so each
//! head is searched on its own grid. The expensive parts
//! are done once: the Gaussian prior of every validation logit once for the whole
//! search, the likelihoods once per bin count (one histogram lookup per class and row).
//! Each lambda candidate is then one pass of additions and the layer's own
//! normalisation ([`scores_from_evidence`]), so a candidate's scores are bit for bit
//! the scores the layer will produce with the written table. The objective is
//! accumulated on the fly by the metrics module's [`Accumulator`], without storing
//! scores. A Bayes candidate is scored by the layer itself, from a table holding that
//! candidate's head ([`search_bayes`]); so is an open-head candidate, once the Bayes head
//! is chosen: the temperature is fitted by NLL, then `epsilon` searched
//! ([`search_open`]).
//!
//! Every candidate also gets its top-1 accuracy and mAP, and [`Guards`] keep a
//! candidate that loses more of either than allowed against softmax
//! ([`Reference`]) behind every candidate that does not.
//!
//! [`search`] works on rows and histograms; [`tune`] runs the whole job on a training
//! set and a validation file and builds the table of the best candidates; [`report`]
//! is its result as data, which `mlmap tune --format json` and `mlmap.tune` render.

mod bayes;
mod grid;
mod open;
mod pipeline;
mod recal;
mod report;

use std::{format, vec};

pub use self::bayes::{search_bayes, BayesSearchParams};
pub use self::grid::{bayes_lambda_grid, lambda_grid, parse_bins, MAX_CANDIDATES};
pub use self::open::{epsilon_grid, search_open, OpenSearchParams};
pub use self::pipeline::{tune, BayesGrid, Compared, Comparison, TuneParams, Tuned};
pub use self::recal::{choose_maps, fit_map, MapChoice, MAP_GROUPS, MIN_SHARE};
pub use self::report::{
    compared_keys, compared_value, energy_value, report, ReportValue, COMPARED,
};
use crate::metrics::{Accumulator, Metrics, MetricsConfig, Parts};
use crate::names::{Name, Named};
use mlmap_core::{scores_from_evidence, Gaussian, Head, Histogram, MapBackend, UpperTail};

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
            ranking: false,
        }
    }

    /// The objective's value in `m` (`None` when undefined).
    pub fn of(self, m: &Metrics) -> Option<f64> {
        match self {
            Self::Ece => Some(m.ece),
            Self::Nll => m.nll,
            Self::Brier => Some(m.brier),
        }
    }
}

/// How much top-1 accuracy and mAP a candidate may lose against softmax on the
/// validation rows and still be chosen.
///
/// # Parameters
///
/// | Name | Default | Purpose |
/// |---|---|---|
/// | `max_accuracy_loss` | 0.005 (half a point) | largest allowed drop of `accuracy` |
/// | `max_map_loss` | 0.01 (one point) | largest allowed drop of mAP, the mean of `ap_<class>` |
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Guards {
    /// Largest allowed drop of top-1 accuracy.
    pub max_accuracy_loss: f64,
    /// Largest allowed drop of mAP.
    pub max_map_loss: f64,
}

impl Default for Guards {
    fn default() -> Self {
        Self {
            max_accuracy_loss: 0.005,
            max_map_loss: 0.01,
        }
    }
}

/// What the [`Guards`] compare against: softmax's accuracy and mAP on the rows the
/// candidates are scored on.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Reference {
    /// Softmax's top-1 accuracy; `None` when undefined (no guard on accuracy).
    pub accuracy: Option<f64>,
    /// Softmax's mAP; `None` when undefined (no guard on mAP).
    pub mean_ap: Option<f64>,
}

impl Guards {
    /// Checks that both losses are finite and not negative.
    ///
    /// # Errors
    ///
    /// A message naming the flag at fault.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("--max-accuracy-loss", self.max_accuracy_loss),
            ("--max-map-loss", self.max_map_loss),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{name} must be a number >= 0, not {v}"));
            }
        }
        Ok(())
    }

    /// How much more than allowed `accuracy` and `mean_ap` lose against `reference`
    /// (the larger of the two excesses): 0 within the guards, `+inf` for a metric that
    /// is undefined where the reference's is not.
    ///
    /// # Examples
    ///
    /// ```
    /// use mlmap_host::tune::{Guards, Reference};
    ///
    /// let g = Guards::default();
    /// let softmax = Reference { accuracy: Some(0.95), mean_ap: Some(0.80) };
    /// assert_eq!(g.excess(Some(0.946), Some(0.85), &softmax), 0.0);
    /// assert!((g.excess(Some(0.94), Some(0.80), &softmax) - 0.005).abs() < 1e-12);
    /// assert!((g.excess(Some(0.95), Some(0.77), &softmax) - 0.02).abs() < 1e-12);
    /// ```
    pub fn excess(
        &self,
        accuracy: Option<f64>,
        mean_ap: Option<f64>,
        reference: &Reference,
    ) -> f64 {
        // A loss equal to the allowance up to rounding is within it.
        let over = |got: Option<f64>, want: Option<f64>, allowed: f64| match (got, want) {
            (_, None) => 0.0,
            (None, Some(_)) => f64::INFINITY,
            (Some(g), Some(w)) if w - g <= allowed + 1e-12 => 0.0,
            (Some(g), Some(w)) => w - g - allowed,
        };
        over(accuracy, reference.accuracy, self.max_accuracy_loss).max(over(
            mean_ap,
            reference.mean_ap,
            self.max_map_loss,
        ))
    }
}

crate::names::display_and_parse!(Objective);

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
    /// Bin count (for the open head: its Bayes head's).
    pub bins: usize,
    /// Smoothing lambda (as stored in the table, `f32`; for the open head: its Bayes
    /// head's).
    pub lambda: f32,
    /// The open head's temperature; `None` for the other heads.
    pub temperature: Option<f32>,
    /// The open head's `epsilon`; `None` for the other heads.
    pub epsilon: Option<f32>,
    /// The objective's value (lower is better; a missing NLL counts as +inf).
    pub objective: f64,
    /// How much more accuracy or mAP than [`Guards`] allow the candidate loses against
    /// softmax ([`Guards::excess`]): 0 for an eligible candidate.
    pub excess: f64,
    /// Expected calibration error (10 bins, DESIGN default binning); computed for the
    /// best candidates only (see [`search`]).
    pub ece: Option<f64>,
    /// Mean NLL of the labelled rows; for the best candidates only.
    pub nll: Option<f64>,
    /// Mean Brier score; for the best candidates only.
    pub brier: Option<f64>,
    /// Top-1 accuracy of the labelled rows (DESIGN §1.5); every candidate.
    pub accuracy: Option<f64>,
    /// mAP, the mean of `ap_<class>` (DESIGN §1.5); every candidate.
    pub mean_ap: Option<f64>,
}

impl Candidate {
    /// Whether the candidate is within the guards.
    pub fn eligible(&self) -> bool {
        self.excess == 0.0
    }
}

/// What every candidate of a search is judged by: the objective and the guards.
#[derive(Debug, Clone, Copy)]
pub struct Judge {
    /// What to minimise.
    pub objective: Objective,
    /// The allowed losses.
    pub guards: Guards,
    /// Softmax's accuracy and mAP on the same rows.
    pub reference: Reference,
}

impl Judge {
    /// The metrics a candidate's accumulator keeps: the objective's, the accuracy and
    /// mAP of the guards, and with `all` every metric.
    fn parts(&self, all: bool) -> Parts {
        if all {
            return Parts::ALL;
        }
        Parts {
            calibration: true,
            ranking: true,
            ..self.objective.parts()
        }
    }

    /// An empty accumulator for one candidate.
    fn accumulator(&self, all: bool) -> Option<Accumulator> {
        let cfg = MetricsConfig {
            bins: ECE_BINS,
            ..MetricsConfig::default()
        };
        Accumulator::new(&cfg, self.parts(all)).ok()
    }

    /// The candidate `(bins, lambda)` whose rows went into `acc` (`None`: none could).
    fn candidate(&self, acc: Option<&Accumulator>, bins: usize, lambda: f32) -> Candidate {
        let Some(acc) = acc else {
            return Candidate {
                bins,
                lambda,
                temperature: None,
                epsilon: None,
                objective: f64::INFINITY,
                excess: f64::INFINITY,
                ece: None,
                nll: None,
                brier: None,
                accuracy: None,
                mean_ap: None,
            };
        };
        let (ece, nll, brier) = (acc.ece(), acc.nll(), acc.brier());
        let value = match self.objective {
            Objective::Ece => ece,
            Objective::Nll => nll,
            Objective::Brier => brier,
        };
        let (accuracy, mean_ap) = (acc.accuracy(), acc.mean_ap());
        Candidate {
            bins,
            lambda,
            temperature: None,
            epsilon: None,
            objective: value.unwrap_or(f64::INFINITY),
            excess: self.guards.excess(accuracy, mean_ap, &self.reference),
            ece,
            nll,
            brier,
            accuracy,
            mean_ap,
        }
    }
}

/// Scores every validation row with `head` of `table` (the device's default backend, as
/// `TableView::score_into`) into a new accumulator of `judge` (every metric with `all`);
/// `None` when no accumulator can be made. Rows the layer refuses are left out.
fn accumulate(
    table: &crate::DynTable,
    head: Head,
    val: &ValRows<'_>,
    judge: &Judge,
    all: bool,
) -> Option<Accumulator> {
    let k = val.k;
    let cats = table.bayes_head().map_or(k, |b| b.categories()).max(k);
    let (mut scores, mut scratch) = (vec![0.0f32; k], vec![0.0f32; cats]);
    let view = table.view();
    let mut acc = judge.accumulator(all)?;
    let rows = val
        .logits
        .chunks_exact(k)
        .zip(val.objectness)
        .zip(val.labels);
    for ((x, &os), &label) in rows {
        if view
            .score_into(head, x, os, &mut scores, &mut scratch)
            .is_ok()
        {
            acc.add(&scores, x, label);
        }
    }
    Some(acc)
}

/// The order of candidates: eligible first, then the smaller excess, the objective,
/// fewer bins, the smaller lambda and the smaller `epsilon`.
fn order(a: &Candidate, b: &Candidate) -> std::cmp::Ordering {
    let eps = |c: &Candidate| c.epsilon.unwrap_or(0.0);
    a.excess
        .total_cmp(&b.excess)
        .then(a.objective.total_cmp(&b.objective))
        .then(a.bins.cmp(&b.bins))
        .then(a.lambda.total_cmp(&b.lambda))
        .then(eps(a).total_cmp(&eps(b)))
}

/// Runs `f` on every item of `work`, the items shared among the machine's cores;
/// `None` when a thread failed.
fn parallel<T: Sync, R: Send>(work: &[T], f: impl Fn(&T) -> R + Sync) -> Option<Vec<R>> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .clamp(1, work.len().max(1));
    let chunk = work.len().div_ceil(threads).max(1);
    let f = &f;
    let parts: Vec<Option<Vec<R>>> = std::thread::scope(|s| {
        let handles: Vec<_> = work
            .chunks(chunk)
            .map(|part| s.spawn(move || part.iter().map(f).collect::<Vec<R>>()))
            .collect();
        handles.into_iter().map(|h| h.join().ok()).collect()
    });
    let mut out = Vec::with_capacity(work.len());
    for p in parts {
        out.extend(p?);
    }
    Some(out)
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
                Head::Map | Head::Bayes | Head::Open => 0.0,
            };
        }
    }
}

/// Scores one lambda over every row given the evidence: the objective and the guards'
/// metrics, or every metric with `all`.
fn score(
    val: &ValRows<'_>,
    evidence: &[f32],
    bins: usize,
    lambda: f32,
    judge: &Judge,
    all: bool,
) -> Candidate {
    let k = val.k;
    let mut scores = vec![0.0f32; k];
    let mut scratch = vec![0.0f32; k];
    let mut acc = judge.accumulator(all);
    if let Some(acc) = &mut acc {
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
    }
    judge.candidate(acc.as_ref(), bins, lambda)
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
/// | `judge` | what to minimise, and the guards against softmax |
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
    /// The objective and the guards.
    pub judge: Judge,
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
/// distinct bin count). Every candidate gets its objective, accuracy, mAP and excess
/// over the guards, and candidates are ordered as the guards and the objective say
/// (eligible first); the best `p.detail` of each head also get every metric of
/// [`Candidate`]. The bin counts are shared among the
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
    // The prior of every validation logit, once, with the MAP head's backend.
    let pdf: Vec<f32> = val
        .logits
        .chunks_exact(k)
        .flat_map(|row| {
            row.iter()
                .zip(p.priors)
                .map(|(&x, g)| g.pdf::<MapBackend>(x))
        })
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
                        out.push(score(val, &evidence, *b, l, &p.judge, false));
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
                *c = score(val, &evidence, c.bins, c.lambda, &p.judge, true);
            }
        }
    }
    Ok(TuneResult { heads })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn guards_order_candidates() {
        let g = Guards::default();
        let r = Reference {
            accuracy: Some(0.9),
            mean_ap: None,
        };
        // No reference mAP: no guard on it; an undefined accuracy loses everything.
        assert_eq!(g.excess(Some(0.895), None, &r), 0.0);
        assert_eq!(g.excess(None, Some(0.5), &r), f64::INFINITY);
        assert!((g.excess(Some(0.85), None, &r) - 0.045).abs() < 1e-12);
        assert!(Guards {
            max_accuracy_loss: -1.0,
            ..g
        }
        .validate()
        .is_err());
        let c = |excess: f64, objective: f64| Candidate {
            bins: 4,
            lambda: 1.0,
            temperature: None,
            epsilon: None,
            objective,
            excess,
            ece: None,
            nll: None,
            brier: None,
            accuracy: None,
            mean_ap: None,
        };
        let mut v = [c(0.01, 0.1), c(0.0, 0.3), c(0.002, 0.5), c(0.0, 0.2)];
        v.sort_by(order);
        let got: Vec<(f64, f64)> = v.iter().map(|c| (c.excess, c.objective)).collect();
        assert_eq!(got, [(0.0, 0.2), (0.0, 0.3), (0.002, 0.5), (0.01, 0.1)]);
    }

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
        // The Bayes head's lambda is at most 1.
        assert_eq!(bayes_lambda_grid(0.1, 1.0, 1).unwrap(), [0.1f32, 1.0]);
        assert!(bayes_lambda_grid(0.1, 2.0, 1).is_err());
        assert!(lambda_grid(0.1, 2.0, 1).is_ok());
    }
}
