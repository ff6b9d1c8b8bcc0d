//! The mergeable statistics of the two passes of a fit (`FitStats`, `FitEdges`,
//! `FitCounts`) and `finish`, their table.

use super::*;

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
        let inner = py
            .detach(|| counts_of(&src, edges))
            .map_err(|e| fit_error(&e))?;
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
