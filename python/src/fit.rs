//! Fitting from numpy arrays: `mlmap.fit`, `mlmap.tune`, and the mergeable statistics
//! of the two passes (`FitStats`, `FitEdges`, `FitCounts`, `finish`).
//!
//! `fit` is the library's two passes over row ranges read by the rayon pool at the same
//! time: pass (a) statistics per range, merged; the edges; pass (b) counts per range,
//! merged; the table. The merges are exact, so the table's bytes do not depend on the
//! split: they are those of `mlmap fit` on the same rows. Rows given as `background`
//! are ranges of their own, every row labelled `-1` (`mlmap fit --background FILE`).

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

use mlmap::host::dataset::{DataError, DataErrorKind, RowSource, MAX_CLASSES};
use mlmap::host::fit::{
    self as host_fit, BayesParams, FitCounts, FitEdges, FitError, FitLabel, FitLogit, FitParams,
    FitStats, TrainingSet,
};
use mlmap::host::names::Named;
use mlmap::host::tune::{self as host_tune, BayesGrid, Guards, Objective, TuneParams};
use mlmap::host::DynTable;
use mlmap::{EdgeMode, Head, UpperTail};
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyType};
use rayon::prelude::*;

use crate::arrays::{self, value_error, Count};
use crate::errors::host_error;
use crate::evaluate;
use crate::source::{ArraySource, BlockSink, Chained};
use crate::table::PyTable;

/// Rows per range of a parallel pass: below it, one range.
const MIN_ROWS_PER_PART: usize = 262_144;

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
        None => (0..k).map(|i| format!("class{i}")).collect(),
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

/// Ranges for a parallel pass over `srcs`, in order.
fn parts<'a>(srcs: &[ArraySource<'a>]) -> Vec<ArraySource<'a>> {
    let threads = rayon::current_num_threads().max(1);
    srcs.iter()
        .flat_map(|src| {
            let n = (src.len() / MIN_ROWS_PER_PART).clamp(1, 4 * threads);
            src.split(n)
        })
        .collect()
}

/// The first error in range order (the lowest row), or every value.
fn in_order<T, E>(results: Vec<Result<T, E>>) -> Result<Vec<T>, E> {
    results.into_iter().collect()
}

/// Pass (a) of blocks of rows.
struct StatsSink(FitStats);

impl BlockSink for StatsSink {
    type Error = DataError;

    fn block<T: FitLogit, L: FitLabel>(
        &mut self,
        src: &ArraySource<'_>,
        first: usize,
        logits: &[T],
        labels: &[L],
    ) -> Result<(), DataError> {
        // A bad label: the row-by-row reading names it as the data files do.
        self.0
            .push_rows(logits, labels)
            .map_err(|_| src.first_error(first..first + labels.len()))
    }
}

/// Pass (a) over the rows of `srcs`, in parallel.
fn stats_of(srcs: &[ArraySource<'_>]) -> Result<FitStats, FitError> {
    let classes = Chained(srcs).classes().to_vec();
    let each = parts(srcs)
        .par_iter()
        .map(|p| {
            let mut sink = StatsSink(FitStats::new(&classes));
            if !p.for_each_block(&mut sink)? {
                p.for_each_row(|row| {
                    sink.0.push(&row);
                    Ok::<(), FitError>(())
                })?;
            }
            Ok::<FitStats, FitError>(sink.0)
        })
        .collect();
    let mut total = FitStats::new(&classes);
    for s in in_order(each)? {
        total.merge(&s)?;
    }
    Ok(total)
}

/// Why pass (b) stopped: bad data, or a value outside the edges (in the array named,
/// at the row given).
enum CountError {
    Data(DataError),
    Outside(PathBuf, u64),
}

impl From<DataError> for CountError {
    fn from(e: DataError) -> Self {
        Self::Data(e)
    }
}

/// Pass (b) of blocks of rows.
struct CountsSink(FitCounts);

impl BlockSink for CountsSink {
    type Error = CountError;

    fn block<T: FitLogit, L: FitLabel>(
        &mut self,
        src: &ArraySource<'_>,
        first: usize,
        logits: &[T],
        labels: &[L],
    ) -> Result<(), CountError> {
        match self.0.push_rows(logits, labels) {
            Ok(None) => Ok(()),
            Ok(Some(i)) => Err(CountError::Outside(
                src.path().to_path_buf(),
                (first + i) as u64,
            )),
            Err(_) => Err(CountError::Data(
                src.first_error(first..first + labels.len()),
            )),
        }
    }
}

/// Pass (b) over the rows of `srcs`, in parallel.
fn counts_of(srcs: &[ArraySource<'_>], edges: &FitEdges) -> PyResult<FitCounts> {
    let each = parts(srcs)
        .par_iter()
        .map(|p| {
            let mut sink = CountsSink(FitCounts::new(edges));
            if !p.for_each_block(&mut sink)? {
                p.for_each_row(|row| {
                    if sink.0.push(&row) {
                        Ok(())
                    } else {
                        Err(CountError::Outside(p.path().to_path_buf(), row.index))
                    }
                })?;
            }
            Ok::<FitCounts, CountError>(sink.0)
        })
        .collect();
    let mut total = FitCounts::new(edges);
    for c in in_order(each).map_err(|e| match e {
        CountError::Data(e) => value_error(e.to_string()),
        CountError::Outside(path, i) => value_error(format!(
            "{}: row index {i}: a training value lies outside the edges; pass (b) needs \
             the edges of statistics that include these rows",
            path.display()
        )),
    })? {
        total.merge(&c).map_err(|e| fit_error(&e))?;
    }
    Ok(total)
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
    let table = py.detach(|| -> PyResult<DynTable> {
        // The objectness feature needs the rows (DESIGN §1.6): the in-memory fit.
        if p.bayes.is_some_and(|b| b.objectness) {
            let train = TrainingSet::read(&Chained(&src)).map_err(|e| fit_error(&e))?;
            return train.fit(&p).map_err(|e| fit_error(&e));
        }
        let stats = stats_of(&src).map_err(|e| fit_error(&e))?;
        let edges = stats.edges(&p).map_err(|e| fit_error(&e))?;
        let counts = counts_of(&src, &edges)?;
        host_fit::finish(&stats, &counts).map_err(|e| fit_error(&e))
    })?;
    PyTable::new(table)
}

/// Adds `other` to `acc` (`0`, the start of `sum()`, is the empty statistics).
macro_rules! mergeable {
    ($py_ty:ident, $inner:ty, $what:literal) => {
        #[pymethods]
        impl $py_ty {
            /// The merge of both (exact: any order and grouping gives the same result).
            fn merge(&self, other: &Bound<'_, $py_ty>) -> PyResult<Self> {
                let mut out = self.inner.clone();
                out.merge(&other.get().inner).map_err(|e| fit_error(&e))?;
                Ok(Self { inner: out })
            }

            fn __add__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
                match other.cast::<$py_ty>() {
                    Ok(o) => self.merge(o),
                    Err(_) if is_zero(other) => Ok(Self {
                        inner: self.inner.clone(),
                    }),
                    Err(_) => Err(PyTypeError::new_err(concat!(
                        "only ", $what, " add to ", $what
                    ))),
                }
            }

            fn __radd__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
                self.__add__(other)
            }

            /// The versioned bytes (they cross process and machine boundaries).
            fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
                PyBytes::new(py, &self.inner.to_bytes())
            }

            /// Reads `to_bytes`'s output; a corrupt, truncated or newer input raises
            /// `ValueError`.
            #[staticmethod]
            fn from_bytes(data: &Bound<'_, PyAny>) -> PyResult<Self> {
                let data = arrays::buffer_bytes(data, "data")?;
                let inner = <$inner>::from_bytes(&data).map_err(|e| fit_error(&e))?;
                Ok(Self { inner })
            }

            fn __reduce__<'py>(
                slf: &Bound<'py, Self>,
            ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
                let from_bytes = slf.get_type().getattr("from_bytes")?;
                Ok((from_bytes, (slf.get().to_bytes(slf.py()),)))
            }

            fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
                other
                    .cast::<$py_ty>()
                    .is_ok_and(|o| o.get().inner.to_bytes() == self.inner.to_bytes())
            }

            fn __hash__(&self) -> u64 {
                let mut h = DefaultHasher::new();
                self.inner.to_bytes().hash(&mut h);
                h.finish()
            }
        }
    };
}

fn is_zero(obj: &Bound<'_, PyAny>) -> bool {
    obj.extract::<i64>().is_ok_and(|v| v == 0)
}

/// Pass (a) of a fit over some rows: per class the exact count, extremes and sums of
/// its training values, and the Bayes head's extremes and category rows. Shards'
/// statistics merge exactly (`merge`, `+`, `sum()`), pickle through versioned bytes,
/// and give the `edges` of pass (b).
#[pyclass(module = "mlmap", frozen, name = "FitStats")]
pub struct PyFitStats {
    inner: FitStats,
}

mergeable!(PyFitStats, FitStats, "FitStats");

#[pymethods]
impl PyFitStats {
    /// The statistics of the rows of `logits`/`labels` and of the rows `background`
    /// takes as background (as `mlmap.fit` takes them; `mlmap stats --background`).
    #[new]
    #[pyo3(signature = (logits, labels, objectness=None, *, classes=None, background=None))]
    fn py_new<'py>(
        py: Python<'py>,
        logits: &Bound<'py, PyAny>,
        labels: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
        classes: Option<Vec<String>>,
        background: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Self> {
        let held = Held::new(logits, labels, objectness, classes, background)?;
        let src = held.sources()?;
        let inner = py.detach(|| stats_of(&src)).map_err(|e| fit_error(&e))?;
        Ok(Self { inner })
    }

    /// The statistics of no rows (the neutral element of `merge`).
    #[classmethod]
    fn empty(_cls: &Bound<'_, PyType>, classes: Vec<String>) -> PyResult<Self> {
        let k = classes.len();
        let classes = class_names(Some(classes), k)?;
        Ok(Self {
            inner: FitStats::new(&classes),
        })
    }

    /// Class names.
    #[getter]
    fn classes(&self) -> Vec<String> {
        self.inner.classes().to_vec()
    }

    /// Rows seen (labelled or not, background rows included).
    #[getter]
    fn rows(&self) -> u64 {
        self.inner.rows()
    }

    /// Training values per class (rows labelled with it).
    #[getter]
    fn class_rows(&self) -> Vec<u64> {
        self.inner.moments().iter().map(|m| m.count()).collect()
    }

    /// The edges of every histogram for a fit with these settings (the keywords of
    /// `mlmap.fit`): what pass (b) counts against.
    #[pyo3(signature = (*, bins_ml=Count::new(22), lambda_ml=None, bins_map=Count::new(17),
                        lambda_map=None, edges="linspace", tail="zero", bayes=BayesArg::DEFAULT),
        text_signature = "($self, *, bins_ml=22, lambda_ml=None, bins_map=17, \
                          lambda_map=None, edges='linspace', tail='zero', bayes=True)")]
    #[allow(clippy::too_many_arguments)]
    fn edges(
        &self,
        bins_ml: Count,
        lambda_ml: Option<f64>,
        bins_map: Count,
        lambda_map: Option<f64>,
        edges: &str,
        tail: &str,
        bayes: BayesArg,
    ) -> PyResult<PyFitEdges> {
        let p = params(bins_ml, lambda_ml, bins_map, lambda_map, edges, tail, bayes)?;
        let inner = self.inner.edges(&p).map_err(|e| fit_error(&e))?;
        Ok(PyFitEdges { inner })
    }

    /// The table of these statistics and the merged counts of pass (b).
    fn finish(&self, counts: &Bound<'_, PyFitCounts>) -> PyResult<PyTable> {
        finish(self, counts)
    }

    fn __repr__(&self) -> String {
        format!(
            "FitStats(classes={:?}, rows={}, class_rows={:?})",
            self.inner.classes(),
            self.inner.rows(),
            self.class_rows()
        )
    }
}

/// The edges of every histogram (ML and MAP per class, Bayes per logit) and the fit
/// settings: what pass (b) counts against. From `FitStats.edges(...)`; pickles.
#[pyclass(module = "mlmap", frozen, name = "FitEdges")]
pub struct PyFitEdges {
    inner: FitEdges,
}

#[pymethods]
impl PyFitEdges {
    /// Class names.
    #[getter]
    fn classes(&self) -> Vec<String> {
        self.inner.classes().to_vec()
    }

    /// The versioned bytes.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.inner.to_bytes())
    }

    /// Reads `to_bytes`'s output.
    #[staticmethod]
    fn from_bytes(data: &Bound<'_, PyAny>) -> PyResult<Self> {
        let data = arrays::buffer_bytes(data, "data")?;
        let inner = FitEdges::from_bytes(&data).map_err(|e| fit_error(&e))?;
        Ok(Self { inner })
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let from_bytes = slf.get_type().getattr("from_bytes")?;
        Ok((from_bytes, (slf.get().to_bytes(slf.py()),)))
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyFitEdges>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }
}

/// Pass (b) of a fit over some rows: the bin counts of every head over given edges.
/// Shards' counts merge by addition (`merge`, `+`, `sum()`) and pickle.
#[pyclass(module = "mlmap", frozen, name = "FitCounts")]
pub struct PyFitCounts {
    inner: FitCounts,
}

mergeable!(PyFitCounts, FitCounts, "FitCounts");

#[pymethods]
impl PyFitCounts {
    /// The counts over `edges` of the rows of `logits`/`labels` and of the rows
    /// `background` takes as background (the same rows as their `FitStats`).
    #[new]
    #[pyo3(signature = (edges, logits, labels, objectness=None, *, background=None))]
    fn py_new<'py>(
        py: Python<'py>,
        edges: &Bound<'py, PyFitEdges>,
        logits: &Bound<'py, PyAny>,
        labels: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
        background: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Self> {
        let edges = &edges.get().inner;
        let classes = Some(edges.classes().to_vec());
        let held = Held::new(logits, labels, objectness, classes, background)?;
        let src = held.sources()?;
        let inner = py.detach(|| counts_of(&src, edges))?;
        Ok(Self { inner })
    }

    /// No counts over `edges` (the neutral element of `merge`).
    #[classmethod]
    fn empty(_cls: &Bound<'_, PyType>, edges: &Bound<'_, PyFitEdges>) -> Self {
        Self {
            inner: FitCounts::new(&edges.get().inner),
        }
    }

    /// Rows counted.
    #[getter]
    fn rows(&self) -> u64 {
        self.inner.rows()
    }

    fn __repr__(&self) -> String {
        format!(
            "FitCounts(classes={:?}, rows={})",
            self.inner.edges().classes(),
            self.inner.rows()
        )
    }
}

/// The table of merged statistics (pass (a)) and merged counts (pass (b)) of the same
/// rows: the bytes `mlmap.fit` writes on all of them at once.
#[pyfunction]
pub fn finish(stats: &PyFitStats, counts: &Bound<'_, PyFitCounts>) -> PyResult<PyTable> {
    let table = host_fit::finish(&stats.inner, &counts.get().inner).map_err(|e| fit_error(&e))?;
    PyTable::new(table)
}

/// Searches bins and lambdas of every head on validation data, as `mlmap tune` does;
/// returns `(table, report)`, the report a dict as `mlmap tune --format json` (without
/// the table's path). With the Bayes head, the open head's temperature is fitted by NLL
/// on the labelled validation rows and its `epsilon` searched on the grid of `mlmap
/// tune`; the report's `"open"` candidates and its `validation.methods.open` carry
/// both. `background` takes more training rows as background, as in `mlmap.fit`.
/// `maps=True` (the default) fits a recalibration map per head (DESIGN §1.9), kept
/// where it lowers the cross-fitted ECE within the guards; the report's `"maps"` gives
/// each head's verdict (`kept`, `cv_ece_without`, `cv_ece_with`, `within_guards`, `adds_no_loss`,
/// `knots`), as `mlmap tune --format json`. `maps=False` is `mlmap tune --no-maps`;
/// `objectness_feature=True` is `mlmap tune --objectness-feature` (DESIGN §1.6).
#[pyfunction]
#[pyo3(signature = (logits, labels, val, objectness=None, *, ood=None, background=None,
                    classes=None,
                    objective="ece", bins_ml=None, bins_map=None, bins_bayes=None,
                    bayes=true, lambda_min=1e-8, lambda_max=1.0,
                    lambdas_per_decade=Count::new(3),
                    lambda_bayes_min=None, lambda_bayes_max=None, max_accuracy_loss=0.005,
                    max_map_loss=0.01, edges="linspace", tail="zero", top=Count::new(5),
                    maps=true, objectness_feature=false),
    text_signature = "(logits, labels, val, objectness=None, *, ood=None, background=None, \
                      classes=None, \
                      objective='ece', bins_ml=None, bins_map=None, bins_bayes=None, \
                      bayes=True, lambda_min=1e-8, lambda_max=1.0, lambdas_per_decade=3, \
                      lambda_bayes_min=None, lambda_bayes_max=None, \
                      max_accuracy_loss=0.005, max_map_loss=0.01, edges='linspace', \
                      tail='zero', top=5, maps=True, objectness_feature=False)")]
#[allow(clippy::too_many_arguments)]
pub fn tune<'py>(
    py: Python<'py>,
    logits: &Bound<'py, PyAny>,
    labels: &Bound<'py, PyAny>,
    val: &Bound<'py, PyAny>,
    objectness: Option<&Bound<'py, PyAny>>,
    ood: Option<&Bound<'py, PyAny>>,
    background: Option<&Bound<'py, PyAny>>,
    classes: Option<Vec<String>>,
    objective: &str,
    bins_ml: Option<Vec<Count>>,
    bins_map: Option<Vec<Count>>,
    bins_bayes: Option<Vec<Count>>,
    bayes: bool,
    lambda_min: f64,
    lambda_max: f64,
    lambdas_per_decade: Count,
    lambda_bayes_min: Option<f64>,
    lambda_bayes_max: Option<f64>,
    max_accuracy_loss: f64,
    max_map_loss: f64,
    edges: &str,
    tail: &str,
    top: Count,
    maps: bool,
    objectness_feature: bool,
) -> PyResult<(PyTable, Bound<'py, PyDict>)> {
    let grid = |b: Option<Vec<Count>>, what: &str| -> PyResult<Vec<usize>> {
        let Some(b) = b else {
            return Ok((4..=40).collect());
        };
        let refuse = |got: &str| {
            value_error(format!(
                "{what}: bin counts must be in 1..=65535, at least one{got}"
            ))
        };
        if b.is_empty() {
            return Err(refuse(""));
        }
        b.iter()
            .map(|n| {
                n.value()
                    .filter(|v| (1..=MAX_BINS).contains(v))
                    .ok_or_else(|| refuse(&format!(" (got {})", n.text())))
            })
            .collect()
    };
    let lambdas_per_decade = lambdas_per_decade.get(
        "lambdas_per_decade",
        1..=MAX_LAMBDAS_PER_DECADE,
        "an integer from 1 to 1000",
    )?;
    let top = top.get("top", 0..=usize::MAX, "an integer >= 0")?;
    let lambdas = host_tune::lambda_grid(lambda_min, lambda_max, lambdas_per_decade)
        .map_err(|e| value_error(format!("lambda_min/lambda_max: {e}")))?;
    let bayes_grid = if bayes {
        let lambdas = host_tune::bayes_lambda_grid(
            lambda_bayes_min.unwrap_or(lambda_min),
            lambda_bayes_max.unwrap_or(lambda_max),
            lambdas_per_decade,
        )
        .map_err(|e| value_error(format!("lambda_bayes_min/lambda_bayes_max: {e}")))?;
        Some(BayesGrid {
            bins: grid(bins_bayes, "bins_bayes")?,
            lambdas,
            objectness: objectness_feature,
        })
    } else {
        None
    };
    let guards = Guards {
        max_accuracy_loss,
        max_map_loss,
    };
    guards.validate().map_err(|e| {
        value_error(
            e.replace("--max-accuracy-loss", "max_accuracy_loss")
                .replace("--max-map-loss", "max_map_loss"),
        )
    })?;
    let params = TuneParams {
        bins: vec![
            (Head::Ml, grid(bins_ml, "bins_ml")?),
            (Head::Map, grid(bins_map, "bins_map")?),
        ],
        lambdas,
        bayes: bayes_grid,
        epsilons: host_tune::epsilon_grid(),
        objective: Objective::from_name(objective).map_err(|e| value_error(e.to_string()))?,
        guards,
        edges: EdgeMode::from_name(edges).map_err(|e| value_error(e.to_string()))?,
        tail: UpperTail::from_name(tail).map_err(|e| value_error(e.to_string()))?,
        detail: top,
        maps,
    };
    params.check_size().map_err(value_error)?;
    let held = Held::new(logits, labels, objectness, classes, background)?;
    let src = held.sources()?;
    let names = held.classes.clone();
    let val = evaluate::data_set(&names, val, "val")?;
    let ood = ood
        .filter(|o| !o.is_none())
        .map(|o| evaluate::data_set(&names, o, "ood"))
        .transpose()?;
    let (val_path, ood_path) = (Path::new("val"), Path::new("ood"));
    let tuned = py.detach(|| -> PyResult<_> {
        let train = TrainingSet::read(&Chained(&src)).map_err(|e| fit_error(&e))?;
        host_tune::tune(
            &train,
            &val,
            val_path,
            ood.as_ref().map(|o| (o, ood_path)),
            &params,
            |_, _| {},
        )
        .map_err(|e| host_error(&e))
    })?;
    let report = tune_report(py, &tuned, &params, top)?;
    Ok((PyTable::new(tuned.table)?, report))
}

/// The keys of the comparison of `tune`, as the CLI's JSON report names them.
const COMPARED: [&str; 6] = ["ece", "nll", "brier", "accuracy", "mean_ap", "auroc"];

fn compared(m: &mlmap::host::metrics::Metrics, key: &str) -> Option<f64> {
    match key {
        "ece" => Some(m.ece),
        "nll" => m.nll,
        "brier" => Some(m.brier),
        "accuracy" => m.accuracy,
        "mean_ap" => m.mean_ap(),
        "auroc" => m.auroc,
        "ood_mean" => m.ood.map(|o| o.ood_mean),
        "ood_auroc" => m.ood.and_then(|o| o.auroc),
        "ood_fpr95" => m.ood.and_then(|o| o.fpr95),
        _ => None,
    }
    .filter(|v| v.is_finite())
}

/// The energy score's value of `key` in the comparison: its ranking metrics only.
fn energy_compared(r: &mlmap::host::eval::Ranking, key: &str) -> Option<f64> {
    match key {
        "auroc" => r.auroc,
        "ood_auroc" => r.ood_auroc,
        "ood_fpr95" => r.ood_fpr95,
        _ => None,
    }
    .filter(|v| v.is_finite())
}

/// `tune`'s report as a dict with the keys of `mlmap tune --format json`.
fn tune_report<'py>(
    py: Python<'py>,
    tuned: &host_tune::Tuned,
    params: &TuneParams,
    top: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("objective", params.objective.name())?;
    let counts = PyDict::new(py);
    for h in &tuned.result.heads {
        counts.set_item(h.head.name(), params.candidates(h.head))?;
    }
    out.set_item("candidates", counts)?;
    for h in &tuned.result.heads {
        let list = pyo3::types::PyList::empty(py);
        for (i, c) in h.candidates.iter().take(top).enumerate() {
            let d = PyDict::new(py);
            d.set_item("bins", c.bins)?;
            d.set_item("lambda", c.lambda)?;
            d.set_item("objective", Some(c.objective).filter(|v| v.is_finite()))?;
            d.set_item("ece", c.ece)?;
            d.set_item("nll", c.nll)?;
            d.set_item("brier", c.brier)?;
            d.set_item("accuracy", c.accuracy)?;
            d.set_item("mean_ap", c.mean_ap)?;
            d.set_item("within_guards", c.eligible())?;
            if let (Some(t), Some(e)) = (c.temperature, c.epsilon) {
                d.set_item("temperature", t)?;
                d.set_item("epsilon", e)?;
            }
            d.set_item("rank", i + 1)?;
            list.append(d)?;
        }
        out.set_item(h.head.name(), list)?;
    }
    let c = &tuned.comparison;
    let methods = PyDict::new(py);
    let mut keys = COMPARED.to_vec();
    if c.ood_rows.is_some() {
        keys.extend(["ood_mean", "ood_auroc", "ood_fpr95"]);
    }
    for m in &c.methods {
        let d = PyDict::new(py);
        for &key in &keys {
            d.set_item(key, compared(&m.metrics, key))?;
        }
        if let Some(ch) = &m.chosen {
            d.set_item("bins", ch.bins)?;
            d.set_item("lambda", ch.lambda)?;
            if let (Some(t), Some(e)) = (ch.temperature, ch.epsilon) {
                d.set_item("temperature", t)?;
                d.set_item("epsilon", e)?;
            }
            d.set_item("within_guards", m.excess == 0.0)?;
        }
        methods.set_item(m.method.name(), d)?;
    }
    let energy = PyDict::new(py);
    for &key in &keys {
        energy.set_item(key, energy_compared(&c.energy, key))?;
    }
    methods.set_item(mlmap::host::eval::Method::Energy.name(), energy)?;
    let v = PyDict::new(py);
    v.set_item("rows", c.rows)?;
    v.set_item("ood_rows", c.ood_rows)?;
    v.set_item("temperature", c.temperature)?;
    v.set_item("max_accuracy_loss", params.guards.max_accuracy_loss)?;
    v.set_item("max_map_loss", params.guards.max_map_loss)?;
    v.set_item("methods", methods)?;
    v.set_item("best", c.best.map(|m| m.name()))?;
    out.set_item("validation", v)?;
    if params.maps {
        let maps = PyDict::new(py);
        for m in &tuned.maps {
            let d = PyDict::new(py);
            d.set_item("kept", m.kept)?;
            d.set_item(
                "cv_ece_without",
                Some(m.ece_without).filter(|v| v.is_finite()),
            )?;
            d.set_item("cv_ece_with", Some(m.ece_with).filter(|v| v.is_finite()))?;
            d.set_item("within_guards", m.excess == 0.0)?;
            d.set_item("adds_no_loss", m.excess <= m.excess_without)?;
            // Lists `[x, y]`, as the JSON report has them.
            let knots: Vec<[f32; 2]> = m.knots.iter().map(|k| [k.x, k.y]).collect();
            d.set_item("knots", knots)?;
            maps.set_item(m.head.name(), d)?;
        }
        out.set_item("maps", maps)?;
    }
    Ok(out)
}
