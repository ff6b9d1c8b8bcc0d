//! Fitting from numpy arrays: `mlmap.fit`, `mlmap.tune`, and the mergeable statistics
//! of the two passes (`FitStats`, `FitEdges`, `FitCounts`, `finish`).
//!
//! `fit` is the host's fit over parts (`mlmap::host::fit::parts`): the two passes over
//! row ranges of the arrays, read by the rayon pool at the same time, merged exactly, so
//! the table's bytes do not depend on the split: they are those of `mlmap fit` on the
//! same rows. This module converts the arguments and results, gives the host the ranges
//! (with their reading by blocks) and the pool, and releases the GIL. Rows given as
//! `background` are ranges of their own, every row labelled `-1` (`mlmap fit
//! --background FILE`).

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::path::Path;

use mlmap::host::dataset::{DataError, DataErrorKind, RowSource, MAX_CLASSES};
use mlmap::host::fit::parts::{self as host_parts, Chained, FitPart, Runner};
use mlmap::host::fit::{
    self as host_fit, BayesParams, FitCounts, FitEdges, FitError, FitLabel, FitLogit, FitParams,
    FitStats, TrainingSet,
};
use mlmap::host::names::Named;
use mlmap::host::tune::{self as host_tune, BayesGrid, Guards, Objective, TuneParams};
use mlmap::{EdgeMode, Head, UpperTail};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyType};
use rayon::prelude::*;

use crate::arrays::{self, value_error, Count};
use crate::errors::host_error;
use crate::evaluate;
use crate::source::{ArraySource, BlockSink};
use crate::table::PyTable;

mod mergeable;
mod search;

pub use mergeable::{finish, PyFitCounts, PyFitEdges, PyFitStats};
pub use search::tune;

/// A fitting error as a Python exception, with the CLI's message (parameters named by
/// their keyword instead of their flag).
pub fn fit_error(e: &FitError) -> PyErr {
    let msg = match e {
        FitError::Param {
            name,
            value,
            expected,
        } => format!("{name} {value} is out of range: expected {expected}"),
        _ => mlmap::host::fit_message(Path::new("logits"), e),
    };
    if e.is_bad_input() {
        PyValueError::new_err(msg)
    } else {
        PyRuntimeError::new_err(msg)
    }
}

/// The fit settings from keywords; `bayes` is `True` (the default head), `False` or
/// `None` (no Bayes head), or a dict with `bins` and/or `lambda`.
#[allow(clippy::too_many_arguments)]
fn params(
    bins_ml: Count,
    lambda_ml: Option<f64>,
    bins_map: Count,
    lambda_map: Option<f64>,
    edges: &str,
    tail: &str,
    bayes: BayesArg,
) -> PyResult<FitParams> {
    let d = FitParams::default();
    let p = FitParams {
        bins_ml: bins(&bins_ml, "bins_ml")?,
        lambda_ml: lambda_ml.map_or(d.lambda_ml, |v| v as f32),
        bins_map: bins(&bins_map, "bins_map")?,
        lambda_map: lambda_map.map_or(d.lambda_map, |v| v as f32),
        edges: EdgeMode::from_name(edges).map_err(|e| value_error(e.to_string()))?,
        upper_tail: UpperTail::from_name(tail).map_err(|e| value_error(e.to_string()))?,
        bayes: bayes.0,
    };
    p.validate().map_err(|e| fit_error(&e))?;
    Ok(p)
}

/// A bin count: `1..=65535`, else the message of a fit parameter out of range.
fn bins(count: &Count, name: &str) -> PyResult<usize> {
    count.get(name, 1..=MAX_BINS, "an integer from 1 to 65535")
}

/// The largest bin count of a histogram (the table stores it as `u16`).
const MAX_BINS: usize = u16::MAX as usize;

/// The most lambdas per decade `tune` takes: far more than a search needs, and few
/// enough that the grid is always small next to the data.
const MAX_LAMBDAS_PER_DECADE: usize = 1000;

/// The `bayes` keyword: `True` (the default head), `False` or `None` (no Bayes head),
/// or a dict with `bins` and/or `lambda`.
#[derive(Debug, Clone, Copy)]
pub struct BayesArg(Option<BayesParams>);

impl BayesArg {
    /// The default: a Bayes head with its default settings.
    const DEFAULT: Self = Self(Some(BayesParams {
        bins: 22,
        lambda: 1e-3,
        objectness: false,
    }));
}

impl<'a, 'py> FromPyObject<'a, 'py> for BayesArg {
    type Error = PyErr;

    fn extract(b: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if b.is_none() {
            return Ok(Self(None));
        }
        if let Ok(flag) = b.cast::<PyBool>() {
            return Ok(Self(flag.is_true().then(BayesParams::default)));
        }
        let d = b.cast::<PyDict>().map_err(|_| {
            PyTypeError::new_err(
                "bayes: expected True, False, None or a dict {\"bins\": .., \"lambda\": .., \
                 \"objectness\": ..}",
            )
        })?;
        let mut p = BayesParams::default();
        for (key, value) in d.iter() {
            match key.extract::<String>()?.as_str() {
                "bins" => p.bins = bins(&value.extract::<Count>()?, "bins_bayes")?,
                "lambda" => p.lambda = value.extract::<f64>()? as f32,
                "objectness" => {
                    p.objectness = value
                        .cast::<PyBool>()
                        .map_err(|_| {
                            PyTypeError::new_err("bayes: \"objectness\" must be True or False")
                        })?
                        .is_true();
                }
                other => {
                    return Err(value_error(format!(
                        "bayes: unknown key {other:?}; expected \"bins\", \"lambda\" and \
                         \"objectness\""
                    )))
                }
            }
        }
        Ok(Self(Some(p)))
    }
}

/// Class names: the given ones (checked as a data file's header is), or `class0` ..
/// `class{K-1}` as for an NPY directory without `classes.txt`.
fn class_names(classes: Option<Vec<String>>, k: usize) -> PyResult<Vec<String>> {
    let names = match classes {
        Some(names) => names,
        // More columns than a table holds: refused before any name is made.
        None if k > MAX_CLASSES => {
            let e = DataError::new("classes", DataErrorKind::ClassCount { found: k });
            return Err(value_error(e.to_string()));
        }
        None => mlmap::host::dataset::default_class_names(k),
    };
    if names.len() != k {
        return Err(value_error(format!(
            "classes: {} names given but the logits have {k} columns",
            names.len()
        )));
    }
    check_class_names(&names)?;
    Ok(names)
}

/// The rules of a data file's class names (DESIGN §2, §6.15), with its messages.
fn check_class_names(names: &[String]) -> PyResult<()> {
    mlmap::host::dataset::check_class_names(names, |i, kind| {
        let e = DataError::new("classes", kind);
        match names.get(i).filter(|n| !n.is_empty()) {
            Some(n) => e.in_column(n.as_str()),
            None => e,
        }
    })
    .map(|_| ())
    .map_err(|e| value_error(e.to_string()))
}

/// The rows of the `background` keyword: logits only, every row taken as background
/// (label `-1`) whatever it is, as `mlmap fit --background FILE` takes a file's rows.
struct Background<'py> {
    logits: arrays::Logits<'py>,
    labels: arrays::Labels<'py>,
    objectness: arrays::Objectness<'py>,
}

impl<'py> Background<'py> {
    /// `None` (no rows) or an `(N_b, K)` float array of any layout (DESIGN §6.20).
    fn new(obj: Option<&Bound<'py, PyAny>>, k: usize) -> PyResult<Option<Self>> {
        let Some(obj) = obj.filter(|o| !o.is_none()) else {
            return Ok(None);
        };
        let x = arrays::logits(obj, "background")?;
        if x.cols != k {
            return Err(value_error(format!(
                "background: has {} columns but the logits have {k}",
                x.cols
            )));
        }
        Ok(Some(Self {
            labels: arrays::Labels::Owned(vec![-1; x.rows]),
            logits: x,
            // The objectness does not enter a fit.
            objectness: arrays::Objectness::Const(1.0),
        }))
    }
}

/// The arrays of a fit, checked and held for one call.
struct Held<'py> {
    classes: Vec<String>,
    logits: arrays::Logits<'py>,
    labels: arrays::Labels<'py>,
    objectness: arrays::Objectness<'py>,
    background: Option<Background<'py>>,
}

impl<'py> Held<'py> {
    fn new(
        logits: &Bound<'py, PyAny>,
        labels: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
        classes: Option<Vec<String>>,
        background: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Self> {
        let x = arrays::logits(logits, "logits")?;
        let classes = class_names(classes, x.cols)?;
        let labels = arrays::label_array(labels, "labels", x.rows)?;
        let objectness = arrays::objectness(objectness, "objectness", x.rows)?;
        let background = Background::new(background, x.cols)?;
        Ok(Self {
            classes,
            logits: x,
            labels,
            objectness,
            background,
        })
    }

    /// The training rows, then the rows taken as background (if any).
    fn sources(&self) -> PyResult<Vec<ArraySource<'_>>> {
        let mut out = vec![ArraySource::new(
            &self.classes,
            &self.logits,
            Some(&self.labels),
            &self.objectness,
            "",
        )?];
        if let Some(b) = &self.background {
            let src =
                ArraySource::new(&self.classes, &b.logits, Some(&b.labels), &b.objectness, "")?;
            out.push(src.with_logits_name("background"));
        }
        Ok(out)
    }
}

/// Ranges for a parallel pass over `srcs`, in order (as many per source as the host's
/// `part_count` gives for the pool's threads).
fn parts<'a>(srcs: &[ArraySource<'a>]) -> Vec<ArraySource<'a>> {
    let threads = rayon::current_num_threads();
    srcs.iter()
        .flat_map(|src| src.split(host_parts::part_count(src.len(), threads)))
        .collect()
}

/// The rayon pool, running the parts of a pass at the same time.
struct Pool;

impl Runner for Pool {
    fn each<P: Sync, T: Send>(&self, parts: &[P], f: &(dyn Fn(&P) -> T + Sync)) -> Vec<T> {
        parts.par_iter().map(f).collect()
    }
}

/// A range of the arrays, read by blocks in place.
impl FitPart for ArraySource<'_> {
    fn stats_blocks(&self, stats: &mut FitStats) -> Result<bool, FitError> {
        self.for_each_block(&mut StatsSink(stats))
    }

    fn count_blocks(&self, counts: &mut FitCounts) -> Result<bool, FitError> {
        self.for_each_block(&mut CountsSink(counts))
    }
}

/// Pass (a) of blocks of rows.
struct StatsSink<'s>(&'s mut FitStats);

impl BlockSink for StatsSink<'_> {
    type Error = FitError;

    fn block<T: FitLogit, L: FitLabel>(
        &mut self,
        src: &ArraySource<'_>,
        first: usize,
        logits: &[T],
        labels: &[L],
    ) -> Result<(), FitError> {
        // A bad label: the row-by-row reading names it as the data files do.
        self.0
            .push_rows(logits, labels)
            .map_err(|_| src.first_error(first..first + labels.len()).into())
    }
}

/// Pass (b) of blocks of rows.
struct CountsSink<'s>(&'s mut FitCounts);

impl BlockSink for CountsSink<'_> {
    type Error = FitError;

    fn block<T: FitLogit, L: FitLabel>(
        &mut self,
        src: &ArraySource<'_>,
        first: usize,
        logits: &[T],
        labels: &[L],
    ) -> Result<(), FitError> {
        match self.0.push_rows(logits, labels) {
            Ok(None) => Ok(()),
            Ok(Some(i)) => Err(FitError::OutsideEdges {
                path: src.path().to_path_buf(),
                row: (first + i) as u64,
            }),
            Err(_) => Err(src.first_error(first..first + labels.len()).into()),
        }
    }
}

/// Pass (a) over the rows of `srcs`, in parallel.
fn stats_of(srcs: &[ArraySource<'_>]) -> Result<FitStats, FitError> {
    let classes = Chained(srcs).classes().to_vec();
    host_parts::stats(&parts(srcs), &classes, &Pool)
}

/// Pass (b) over the rows of `srcs`, in parallel.
fn counts_of(srcs: &[ArraySource<'_>], edges: &FitEdges) -> Result<FitCounts, FitError> {
    host_parts::counts(&parts(srcs), edges, &Pool)
}

/// Fits a table from numpy arrays, as `mlmap fit` does from a file (the same bytes on
/// the same rows).
///
/// `logits` is `(N, K)` float32 or float64 in any order; `labels` `(N,)` integers,
/// `0..K-1` a class and `-1` background (used by the Bayes head; the paper's heads skip
/// those rows); `objectness` is checked but does not enter the fit. `background` is an
/// `(N_b, K)` float array of more rows taken as background whatever they are (logged
/// false positives, objects of classes the detector must not report), as `mlmap fit
/// --background FILE` takes a file's rows: they teach the Bayes head's `background`
/// category, and so the open head, what is not a known object. `classes` names the
/// columns (default `class0` ..). `bayes=True` fits the Bayes head with its defaults
/// and the untuned open head (`T = 1`, `epsilon = 0`), `bayes={"bins": 22, "lambda":
/// 1e-3}` with others, `None` or `False` leaves both out.
#[pyfunction]
#[pyo3(signature = (logits, labels, objectness=None, *, background=None, classes=None,
                    bins_ml=Count::new(22), lambda_ml=None, bins_map=Count::new(17),
                    lambda_map=None, edges="linspace", tail="zero", bayes=BayesArg::DEFAULT),
    text_signature = "(logits, labels, objectness=None, *, background=None, classes=None, \
                      bins_ml=22, lambda_ml=None, bins_map=17, lambda_map=None, \
                      edges='linspace', tail='zero', bayes=True)")]
#[allow(clippy::too_many_arguments)]
pub fn fit<'py>(
    py: Python<'py>,
    logits: &Bound<'py, PyAny>,
    labels: &Bound<'py, PyAny>,
    objectness: Option<&Bound<'py, PyAny>>,
    background: Option<&Bound<'py, PyAny>>,
    classes: Option<Vec<String>>,
    bins_ml: Count,
    lambda_ml: Option<f64>,
    bins_map: Count,
    lambda_map: Option<f64>,
    edges: &str,
    tail: &str,
    bayes: BayesArg,
) -> PyResult<PyTable> {
    let p = params(bins_ml, lambda_ml, bins_map, lambda_map, edges, tail, bayes)?;
    let held = Held::new(logits, labels, objectness, classes, background)?;
    let src = held.sources()?;
    let table = py
        .detach(|| host_parts::fit(&parts(&src), &p, &Pool))
        .map_err(|e| fit_error(&e))?;
    PyTable::new(table)
}
