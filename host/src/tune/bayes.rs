//! The search of the Bayes head (DESIGN §1.6): its counts once per bin count, then one
//! table per lambda, scored by the layer itself.
//!
//! A candidate's scores are those of [`DynTable::bayes_into`] with the `FastMath`
//! backend (the head's default on the device) on a table holding exactly the head the
//! candidate would write, so they are bit for bit the written table's.

use super::{order, parallel, Candidate, HeadCandidates, Judge, TuneError, ValRows};
use crate::fit::BayesCounts;
use crate::DynTable;
use mlmap_core::Head;

/// What [`search_bayes`] searches.
///
/// # Parameters
///
/// | Name | Purpose |
/// |---|---|
/// | `val` | the rows candidates are scored on |
/// | `base` | a table of the same classes; each candidate adds its Bayes head to a copy |
/// | `bins` | the bin counts per logit to try |
/// | `lambdas` | the smoothing values to try, each in `(0, 1]` |
/// | `judge` | what to minimise, and the guards against softmax |
/// | `detail` | how many of the best candidates get every metric |
#[derive(Debug, Clone, Copy)]
pub struct BayesSearchParams<'a> {
    /// The rows candidates are scored on.
    pub val: ValRows<'a>,
    /// A table of the same classes.
    pub base: &'a DynTable,
    /// Bin counts to try.
    pub bins: &'a [usize],
    /// Lambdas to try.
    pub lambdas: &'a [f32],
    /// The objective and the guards.
    pub judge: Judge,
    /// How many of the best candidates get every metric.
    pub detail: usize,
}

/// Scores one Bayes head on every row: the objective and the guards' metrics, or every
/// metric with `all`. `Err` names a head the table refuses.
fn score(
    p: &BayesSearchParams<'_>,
    counts: &BayesCounts,
    lambda: f32,
    all: bool,
) -> Result<Candidate, String> {
    let bins = counts.bins();
    let table = p
        .base
        .clone()
        .with_bayes(counts.spec(lambda))
        .map_err(|e| format!("Bayes head with {bins} bins and lambda {lambda:e}: {e}"))?;
    let acc = super::accumulate(&table, Head::Bayes, &p.val, &p.judge, all);
    Ok(p.judge.candidate(acc.as_ref(), bins, lambda))
}

/// Searches the Bayes head: `counts(b)` returns the fitted counts with `b` bins per
/// logit (called once per bin count). Candidates are ordered as in
/// [`search`](super::search); the best `p.detail` get every metric. The bin counts are
/// shared among the machine's cores; `progress(done, total)` is called as bin counts
/// complete.
///
/// # Errors
///
/// [`TuneError`] for an inconsistent validation set, an empty grid, or counts a table
/// cannot hold.
pub fn search_bayes<C>(
    p: &BayesSearchParams<'_>,
    mut counts: C,
    progress: impl Fn(usize, usize) + Sync,
) -> Result<HeadCandidates, TuneError>
where
    C: FnMut(usize) -> Result<BayesCounts, String>,
{
    let val = &p.val;
    let (k, n) = (val.k, val.labels.len());
    if k != p.base.k() || val.logits.len() != n * k || val.objectness.len() != n {
        return Err(TuneError::BadValidationSet(
            "logits, objectness, labels and classes disagree in size".into(),
        ));
    }
    if n == 0 {
        return Err(TuneError::BadValidationSet("no rows".into()));
    }
    if p.lambdas.is_empty() || p.bins.is_empty() {
        return Err(TuneError::EmptyGrid);
    }
    let mut work = Vec::with_capacity(p.bins.len());
    for &b in p.bins {
        work.push(counts(b).map_err(TuneError::Histogram)?);
    }
    let done = std::sync::atomic::AtomicUsize::new(0);
    let sweep = |c: &BayesCounts| -> Result<Vec<Candidate>, String> {
        let found = p
            .lambdas
            .iter()
            .map(|&l| score(p, c, l, false))
            .collect::<Result<Vec<_>, _>>();
        let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        progress(d, work.len());
        found
    };
    let parts = parallel(&work, sweep)
        .ok_or_else(|| TuneError::Histogram("a search thread failed".into()))?;
    let mut candidates = Vec::with_capacity(work.len() * p.lambdas.len());
    for part in parts {
        candidates.extend(part.map_err(TuneError::Histogram)?);
    }
    candidates.sort_by(order);
    for c in candidates.iter_mut().take(p.detail) {
        if let Some(counts) = work.iter().find(|w| w.bins() == c.bins) {
            *c = score(p, counts, c.lambda, true).map_err(TuneError::Histogram)?;
        }
    }
    Ok(HeadCandidates {
        head: Head::Bayes,
        candidates,
    })
}
