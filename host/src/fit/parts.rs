//! A fit over parts of its rows read at the same time: the fit of the Python package
//! (`mlmap.fit`, `FitStats(...)`, `FitCounts(...)`), which reads numpy arrays by row
//! ranges on a thread pool.
//!
//! The steps are those of [`fit`](super::fit()): pass (a), the [`FitStats`] of every
//! part, merged in part order; their [`FitEdges`]; pass (b), the [`FitCounts`] of every
//! part over those edges, merged; [`finish`]. Every merge is exact, so the table's
//! bytes do not depend on the split: they are those of `fit` over the same rows.
//!
//! The caller brings the parts ([`FitPart`]: rows, and optionally a faster reading by
//! blocks) and says how a pass runs them ([`Runner`]: [`InOrder`], or a thread pool).
//! The first error in part order is the one returned, whichever part fails first in
//! time, so a run on a pool reports what a run in order does.
//!
//! ```
//! use mlmap_host::dataset::{Label, Row};
//! use mlmap_host::fit::parts::{self, InOrder};
//! use mlmap_host::fit::{fit, FitParams};
//!
//! let data = [(0, [2.0, -1.0]), (1, [0.5, 1.5]), (0, [3.0, 0.0]), (1, [-0.5, 2.5])];
//! fn row((c, x): &(usize, [f64; 2])) -> Row<'_> {
//!     let label = Label::Class(*c);
//!     Row { index: 0, line: None, id: None, label, objectness: 1.0, logits: x }
//! }
//! let rows: Vec<Row<'_>> = data.iter().map(row).collect();
//! let classes = ["car".to_string(), "person".to_string()];
//! let params = FitParams::default();
//! // Two parts, read one after the other: the table of one fit over all rows.
//! let (a, b) = rows.split_at(1);
//! let split = [parts::Rows::new(&classes, a), parts::Rows::new(&classes, b)];
//! let table = parts::fit(&split, &params, &InOrder)?;
//! let whole = fit(&parts::Rows::new(&classes, &rows), &params)?;
//! assert_eq!(table.to_vec()?, whole.to_vec()?);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::Path;

use super::{finish, FitCounts, FitEdges, FitError, FitParams, FitStats, TrainingSet};
use crate::dataset::{DataError, Row, RowSource};
use crate::DynTable;

/// Rows per part below which a pass reads a source as one part ([`part_count`]).
pub const MIN_ROWS_PER_PART: usize = 262_144;

/// Parts per thread at most ([`part_count`]): a few, so that threads that finish early
/// take more.
pub const PARTS_PER_THREAD: usize = 4;

/// How many parts a pass over `rows` rows splits them into on `threads` threads: one
/// per [`MIN_ROWS_PER_PART`] rows, at least one and at most [`PARTS_PER_THREAD`] per
/// thread.
pub fn part_count(rows: usize, threads: usize) -> usize {
    (rows / MIN_ROWS_PER_PART).clamp(1, PARTS_PER_THREAD * threads.max(1))
}

/// A part of the rows of a fit: a [`RowSource`], optionally read faster by blocks.
///
/// The block readings are a fast path: a part that gives none (the defaults) is read
/// row by row, with the same result.
pub trait FitPart: RowSource {
    /// Adds every row of the part to `stats` (e.g. by [`FitStats::push_rows`]) and
    /// returns `Ok(true)`; or reads nothing and returns `Ok(false)` (the default).
    ///
    /// # Errors
    ///
    /// The first bad row's error, as [`RowSource::for_each_row`] reports it.
    fn stats_blocks(&self, stats: &mut FitStats) -> Result<bool, FitError> {
        let _ = stats;
        Ok(false)
    }

    /// Adds every row of the part to `counts` (e.g. by [`FitCounts::push_rows`]) and
    /// returns `Ok(true)`; or reads nothing and returns `Ok(false)` (the default).
    ///
    /// # Errors
    ///
    /// The first bad row's error, as [`RowSource::for_each_row`] reports it;
    /// [`FitError::OutsideEdges`] for a row with a value outside the edges.
    fn count_blocks(&self, counts: &mut FitCounts) -> Result<bool, FitError> {
        let _ = counts;
        Ok(false)
    }
}

/// How a pass runs a function over the parts.
pub trait Runner {
    /// `f` of every part, in part order (they may be computed at the same time).
    fn each<P: Sync, T: Send>(&self, parts: &[P], f: &(dyn Fn(&P) -> T + Sync)) -> Vec<T>;
}

/// Runs the parts one after the other, on the calling thread.
#[derive(Debug, Clone, Copy, Default)]
pub struct InOrder;

impl Runner for InOrder {
    fn each<P: Sync, T: Send>(&self, parts: &[P], f: &(dyn Fn(&P) -> T + Sync)) -> Vec<T> {
        parts.iter().map(f).collect()
    }
}

/// Pass (a) of one part: the statistics of its rows.
///
/// # Errors
///
/// The first bad row's error.
pub fn part_stats<P: FitPart + ?Sized>(part: &P, classes: &[String]) -> Result<FitStats, FitError> {
    let mut stats = FitStats::new(classes);
    if !part.stats_blocks(&mut stats)? {
        part.for_each_row(|row| {
            stats.push(&row);
            Ok::<(), FitError>(())
        })?;
    }
    Ok(stats)
}

/// Pass (b) of one part: the bin counts of its rows over `edges`.
///
/// # Errors
///
/// The first bad row's error; [`FitError::OutsideEdges`] for the first row with a value
/// outside the edges.
pub fn part_counts<P: FitPart + ?Sized>(part: &P, edges: &FitEdges) -> Result<FitCounts, FitError> {
    let mut counts = FitCounts::new(edges);
    if !part.count_blocks(&mut counts)? {
        part.for_each_row(|row| {
            if counts.push(&row) {
                Ok(())
            } else {
                Err(FitError::OutsideEdges {
                    path: part.path().to_path_buf(),
                    row: row.index,
                })
            }
        })?;
    }
    Ok(counts)
}

/// Pass (a) over every part, merged: the statistics of all their rows (classes
/// `classes`).
///
/// # Errors
///
/// The first error in part order; a merge error ([`FitStats::merge`]) for parts of
/// other classes.
pub fn stats<P, R>(parts: &[P], classes: &[String], runner: &R) -> Result<FitStats, FitError>
where
    P: FitPart + Sync,
    R: Runner + ?Sized,
{
    let each = runner.each(parts, &|p| part_stats(p, classes));
    let mut total = FitStats::new(classes);
    for s in each.into_iter().collect::<Result<Vec<_>, _>>()? {
        total.merge(&s)?;
    }
    Ok(total)
}

/// Pass (b) over every part, merged: the bin counts of all their rows over `edges`.
///
/// # Errors
///
/// The first error in part order (as [`part_counts`]).
pub fn counts<P, R>(parts: &[P], edges: &FitEdges, runner: &R) -> Result<FitCounts, FitError>
where
    P: FitPart + Sync,
    R: Runner + ?Sized,
{
    let each = runner.each(parts, &|p| part_counts(p, edges));
    let mut total = FitCounts::new(edges);
    for c in each.into_iter().collect::<Result<Vec<_>, _>>()? {
        total.merge(&c)?;
    }
    Ok(total)
}

/// Fits a table from the rows of `parts`, in order (the classes of the first part): the
/// table [`fit`](super::fit()) gives on the same rows read as one source.
///
/// With the objectness feature (DESIGN §1.6), which needs the rows, every part is read
/// once, in order, into a [`TrainingSet`] (on the calling thread).
///
/// # Errors
///
/// [`FitError::Param`] for parameters out of range; the first error in part order of a
/// pass; the errors of [`finish`] (a class without rows, edges a table cannot hold).
pub fn fit<P, R>(parts: &[P], params: &FitParams, runner: &R) -> Result<DynTable, FitError>
where
    P: FitPart + Sync,
    R: Runner + ?Sized,
{
    params.validate()?;
    if params.bayes.is_some_and(|b| b.objectness) {
        return TrainingSet::read(&Chained(parts))?.fit(params);
    }
    let classes = Chained(parts).classes().to_vec();
    let stats = stats(parts, &classes, runner)?;
    let edges = stats.edges(params)?;
    let counts = counts(parts, &edges, runner)?;
    finish(&stats, &counts)
}

/// The rows of several sources, one after the other (e.g. the training rows, then the
/// rows taken as background): one [`RowSource`] for a pass that reads rows in order.
/// Its path and classes are the first source's; each row's error names its own source.
#[derive(Debug, Clone, Copy)]
pub struct Chained<'s, S>(pub &'s [S]);

impl<S: RowSource> RowSource for Chained<'_, S> {
    fn path(&self) -> &Path {
        self.0.first().map_or(Path::new(""), |s| s.path())
    }

    fn classes(&self) -> &[String] {
        self.0.first().map_or(&[], |s| s.classes())
    }

    fn has_labels(&self) -> bool {
        self.0.iter().all(|s| s.has_labels())
    }

    fn for_each_row<E, F>(&self, mut f: F) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>) -> Result<(), E>,
    {
        for s in self.0 {
            s.for_each_row(&mut f)?;
        }
        Ok(())
    }
}

/// Rows held in memory, with their class names: a part read row by row (tests,
/// examples, small data).
#[derive(Debug, Clone, Copy)]
pub struct Rows<'a> {
    classes: &'a [String],
    rows: &'a [Row<'a>],
}

impl<'a> Rows<'a> {
    /// The rows `rows` of classes `classes`.
    pub fn new(classes: &'a [String], rows: &'a [Row<'a>]) -> Self {
        Self { classes, rows }
    }
}

impl RowSource for Rows<'_> {
    fn path(&self) -> &Path {
        Path::new("rows")
    }

    fn classes(&self) -> &[String] {
        self.classes
    }

    fn has_labels(&self) -> bool {
        true
    }

    fn for_each_row<E, F>(&self, mut f: F) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>) -> Result<(), E>,
    {
        for row in self.rows {
            f(*row)?;
        }
        Ok(())
    }
}

impl FitPart for Rows<'_> {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::Label;
    use crate::fit::fit as fit_one;
    use crate::testing::lcg;

    fn rows(n: usize) -> Vec<(Label, [f64; 3])> {
        let mut next = lcg(7);
        (0..n)
            .map(|i| {
                let label = if i % 7 == 0 {
                    Label::Background
                } else {
                    Label::Class(i % 3)
                };
                (
                    label,
                    [next() * 8.0 - 4.0, next() * 6.0 - 3.0, next() * 2.0],
                )
            })
            .collect()
    }

    fn as_rows(data: &[(Label, [f64; 3])]) -> Vec<Row<'_>> {
        data.iter()
            .enumerate()
            .map(|(i, (label, x))| Row {
                index: i as u64,
                line: None,
                id: None,
                label: *label,
                objectness: 0.5,
                logits: x,
            })
            .collect()
    }

    fn classes() -> Vec<String> {
        ["a", "b", "c"].iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn any_split_gives_the_bytes_of_one_fit() {
        let data = rows(500);
        let all = as_rows(&data);
        let classes = classes();
        let params = FitParams::default();
        let whole = fit_one(&Rows::new(&classes, &all), &params).unwrap();
        for cut in [1, 2, 3, 7] {
            let step = all.len().div_ceil(cut);
            let split: Vec<Rows<'_>> = all.chunks(step).map(|c| Rows::new(&classes, c)).collect();
            let table = fit(&split, &params, &InOrder).unwrap();
            assert_eq!(
                table.to_vec().unwrap(),
                whole.to_vec().unwrap(),
                "{cut} parts"
            );
        }
    }

    #[test]
    fn counts_outside_the_edges_name_the_row() {
        let data = rows(50);
        let all = as_rows(&data);
        let classes = classes();
        let (head, tail) = all.split_at(10);
        let stats = stats(&[Rows::new(&classes, head)], &classes, &InOrder).unwrap();
        let edges = stats.edges(&FitParams::default()).unwrap();
        let e = counts(&[Rows::new(&classes, tail)], &edges, &InOrder).unwrap_err();
        assert!(matches!(e, FitError::OutsideEdges { .. }), "{e}");
        assert!(e.to_string().starts_with("rows: row index "), "{e}");
        assert!(e.is_bad_input());
    }

    #[test]
    fn part_count_is_bounded() {
        assert_eq!(part_count(0, 8), 1);
        assert_eq!(part_count(MIN_ROWS_PER_PART * 3, 8), 3);
        assert_eq!(part_count(usize::MAX, 2), 8);
        assert_eq!(part_count(usize::MAX, 0), 4);
    }
}
