//! The search of the open head (DESIGN §1.8): the temperature fitted once on the
//! validation rows by NLL (as the temperature baseline, DESIGN §1.4), then one table per
//! `epsilon` of the grid, scored by the layer itself.
//!
//! A candidate's scores are those of [`DynTable::open_into`] with the `FastMath`
//! backend (the head's default on the device) on a table holding exactly the parameters
//! the candidate would write, so they are bit for bit the written table's.

use super::{order, parallel, Candidate, HeadCandidates, Judge, TuneError, ValRows};
use crate::DynTable;
use mlmap_core::Head;

/// The prior weights of the unknown category `tune` tries by default: 0 (no unknown
/// category) and two per decade from `1e-16` to `1e8`.
pub fn epsilon_grid() -> Vec<f32> {
    let mut grid = vec![0.0f32];
    grid.extend((-32..=16).map(|e| 10f64.powf(f64::from(e) / 2.0) as f32));
    grid
}

/// What [`search_open`] searches.
///
/// # Parameters
///
/// | Name | Purpose |
/// |---|---|
/// | `val` | the rows candidates are scored on |
/// | `table` | a table with the chosen Bayes head; each candidate sets the open head on a copy |
/// | `temperature` | the open head's temperature (fitted by NLL on the validation rows) |
/// | `epsilons` | the unknown category's prior weights to try, each 0 or in `[f32::MIN_POSITIVE, MAX_EPSILON]` |
/// | `judge` | what to minimise, and the guards against softmax |
/// | `detail` | how many of the best candidates get every metric |
#[derive(Debug, Clone, Copy)]
pub struct OpenSearchParams<'a> {
    /// The rows candidates are scored on.
    pub val: ValRows<'a>,
    /// A table with the chosen Bayes head.
    pub table: &'a DynTable,
    /// The temperature every candidate uses.
    pub temperature: f32,
    /// The unknown category's weights to try.
    pub epsilons: &'a [f32],
    /// The objective and the guards.
    pub judge: Judge,
    /// How many of the best candidates get every metric.
    pub detail: usize,
}

/// Scores the open head with `epsilon` on every row. `Err` names parameters the table
/// refuses.
fn score(p: &OpenSearchParams<'_>, epsilon: f32, all: bool) -> Result<Candidate, String> {
    let t = p.temperature;
    let table =
        p.table.clone().with_open(t, epsilon).map_err(|e| {
            format!("open head with temperature {t:e} and epsilon {epsilon:e}: {e}")
        })?;
    let head = table.bayes_head().ok_or("the table has no Bayes head")?;
    let (bins, lambda) = (head.bins(), head.lambda());
    let acc = super::accumulate(&table, Head::Open, &p.val, &p.judge, all);
    Ok(Candidate {
        temperature: Some(t),
        epsilon: Some(epsilon),
        ..p.judge.candidate(acc.as_ref(), bins, lambda)
    })
}

/// Searches the open head's `epsilon` at the given temperature. Candidates are ordered
/// as in [`search`](super::search), then by the smaller `epsilon` (0 first); the best
/// `p.detail` get every metric. The grid is shared among the machine's cores.
///
/// # Errors
///
/// [`TuneError`] for an inconsistent validation set, an empty grid, or parameters a
/// table cannot hold.
pub fn search_open(p: &OpenSearchParams<'_>) -> Result<HeadCandidates, TuneError> {
    let val = &p.val;
    let (k, n) = (val.k, val.labels.len());
    if k != p.table.k() || val.logits.len() != n * k || val.objectness.len() != n {
        return Err(TuneError::BadValidationSet(
            "logits, objectness, labels and classes disagree in size".into(),
        ));
    }
    if n == 0 {
        return Err(TuneError::BadValidationSet("no rows".into()));
    }
    if p.epsilons.is_empty() {
        return Err(TuneError::EmptyGrid);
    }
    let found = parallel(p.epsilons, |&e| score(p, e, false))
        .ok_or_else(|| TuneError::Histogram("a search thread failed".into()))?;
    let mut candidates = found
        .into_iter()
        .collect::<Result<Vec<_>, _>>()
        .map_err(TuneError::Histogram)?;
    candidates.sort_by(order);
    for c in candidates.iter_mut().take(p.detail) {
        *c = score(p, c.epsilon.unwrap_or(0.0), true).map_err(TuneError::Histogram)?;
    }
    Ok(HeadCandidates {
        head: Head::Open,
        candidates,
    })
}
