//! `mlmap.Evaluator`: `evaluate`'s metrics over rows given shard by shard, in memory
//! that does not grow with the rows, through the library's mergeable
//! `metrics::StreamMetrics` (one per method).

use std::path::Path;

use mlmap::host::baselines::{self, Baseline, Rows};
use mlmap::host::dataset::Label;
use mlmap::host::eval::{self, Method};
use mlmap::host::metrics::{self, Binning, MetricsConfig, StreamMetrics};
use mlmap::host::names::Named;
use mlmap::host::DynTable;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PySlice};

use crate::arrays::{self, value_error};
use crate::errors::host_error;
use crate::evaluate::loaded;
use crate::table::PyTable;

/// Rows scored and added at a time: the extra memory of `update` whatever its input.
const PIECE: usize = 1 << 16;

/// The metrics of `mlmap.evaluate` for every method, accumulated shard by shard.
///
/// `Evaluator(table, *, ece_bins=10, ece_binning="design", temperature=None,
/// rank_levels=65536)` starts empty; `update(logits, labels, objectness=None)` adds
/// rows (any number of calls, any sizes; an empty shard adds nothing); `merge(other)`
/// (or `+`, `sum()`) adds another evaluator's rows, exactly for every count and with
/// compensated sums, so shards merge in any order; `report()` gives the dict of
/// `evaluate` on all the rows (`"methods"`, `"rows"`, `"classes"`, `"ece_bins"`,
/// `"ece_binning"`, and `"rank_levels"`). Evaluators pickle (for Dask or
/// multiprocessing) through `to_bytes`.
///
/// The methods are sigmoid, softmax, temperature (with `temperature=T`, e.g. from
/// `evaluate(..., val=...)`'s report), and the table's heads. Memory is bounded by
/// the counts of `auroc` and `ap_<class>`: per method at most `(K + 1) * (rank_levels
/// + 1)` score levels. `ece`, `mce`, `nll`, `brier`, `accuracy` and the `tp_*` / `fp_*`
/// moments equal `evaluate`'s up to the order of floating-point additions; `auroc`
/// and `ap_<class>` count scores within `1 / rank_levels` of each other as tied, and
/// are `evaluate`'s exactly for scores on those levels.
#[pyclass(module = "mlmap", name = "Evaluator")]
pub struct PyEvaluator {
    table: DynTable,
    table_bytes: Vec<u8>,
    temperature: Option<f64>,
    classes: Vec<String>,
    methods: Vec<(Method, StreamMetrics)>,
}

/// The methods an evaluator of `table` reports, in `evaluate`'s order.
fn methods(table: &DynTable, temperature: Option<f64>) -> Vec<Method> {
    Method::ALL
        .into_iter()
        .filter(|m| match m {
            Method::Sigmoid | Method::Softmax | Method::Ml | Method::Map => true,
            Method::Temperature => temperature.is_some(),
            Method::Bayes => table.bayes_head().is_some(),
            Method::Open => table.open_params().is_some(),
            Method::Isotonic | Method::Energy => false,
        })
        .collect()
}

impl PyEvaluator {
    fn build(
        table: &PyTable,
        bins: usize,
        binning: Binning,
        temperature: Option<f64>,
        levels: u32,
    ) -> PyResult<Self> {
        if let Some(t) = temperature {
            if !(t > 0.0 && t.is_finite()) {
                return Err(value_error(format!(
                    "temperature: {t} is not a positive, finite number"
                )));
            }
        }
        let cfg = MetricsConfig { bins, binning };
        let t = &table.table;
        let k = t.k();
        let ms = methods(t, temperature)
            .into_iter()
            .map(|m| StreamMetrics::new(k, &cfg, levels).map(|s| (m, s)))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| value_error(e.to_string()))?;
        Ok(Self {
            table: t.clone(),
            table_bytes: table.bytes.clone(),
            temperature,
            classes: t.class_names().map(str::to_string).collect(),
            methods: ms,
        })
    }

    /// Scores one piece of rows with every method and adds them.
    fn add(&mut self, piece: &mlmap::host::data::Loaded) -> PyResult<()> {
        let k = self.table.k();
        let labels: Vec<Option<usize>> = piece
            .labels
            .iter()
            .map(|l| match l {
                Label::Class(c) => Some(*c),
                _ => None,
            })
            .collect();
        let path = Path::new("logits");
        for (method, acc) in &mut self.methods {
            let scores = match method.head() {
                Some(head) => {
                    eval::head_scores(&self.table, head, piece, path).map_err(|e| host_error(&e))?
                }
                None => {
                    let b = match method {
                        Method::Temperature => {
                            Baseline::Temperature(self.temperature.unwrap_or(1.0))
                        }
                        Method::Softmax => Baseline::Softmax,
                        _ => Baseline::Sigmoid,
                    };
                    let rows = Rows::new(&piece.logits, k, &[], &piece.objectness)
                        .map_err(|e| value_error(e.to_string()))?;
                    baselines::score_rows(b, &rows).map_err(|e| value_error(e.to_string()))?
                }
            };
            for ((s, x), l) in scores
                .chunks_exact(k)
                .zip(piece.logits.chunks_exact(k))
                .zip(&labels)
            {
                acc.add(s, x, *l);
            }
        }
        Ok(())
    }
}

#[pymethods]
impl PyEvaluator {
    #[new]
    #[pyo3(signature = (table, *, ece_bins=arrays::Count::new(10), ece_binning="design",
                        temperature=None, rank_levels=arrays::Count::new(65536)),
        text_signature = "(table, *, ece_bins=10, ece_binning='design', temperature=None, \
                          rank_levels=65536)")]
    fn new(
        table: &Bound<'_, PyTable>,
        ece_bins: arrays::Count,
        ece_binning: &str,
        temperature: Option<f64>,
        rank_levels: arrays::Count,
    ) -> PyResult<Self> {
        let expected = format!("an integer from 1 to {}", metrics::MAX_BINS);
        let bins = ece_bins.get("ece_bins", 1..=metrics::MAX_BINS, &expected)?;
        let binning = Binning::from_name(ece_binning).map_err(|e| value_error(e.to_string()))?;
        let max = metrics::MAX_RANK_LEVELS as usize;
        let levels = rank_levels.get(
            "rank_levels",
            1..=max,
            &format!("an integer from 1 to {max}"),
        )?;
        Self::build(table.get(), bins, binning, temperature, levels as u32)
    }

    /// Adds rows: `logits` `(N, K)` in the table's class order, `labels` `(N,)`
    /// integers (`0 .. K-1` a class, `-1` background), `objectness` `None`, a number or
    /// `(N,)`; checked as `evaluate` checks them. `N = 0` adds nothing.
    #[pyo3(signature = (logits, labels, objectness=None))]
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        logits: &Bound<'py, PyAny>,
        labels: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<()> {
        let np = py.import("numpy")?;
        let x = np.call_method1("asarray", (logits,))?;
        let shape: Vec<usize> = x.getattr("shape")?.extract()?;
        let n = match shape.as_slice() {
            [0, k] if *k == self.classes.len() => return Ok(()),
            [n, _] => *n,
            _ => 0,
        };
        let y = np.call_method1("asarray", (labels,))?;
        let o = match objectness.filter(|o| !o.is_none()) {
            Some(o) if np.call_method1("ndim", (o,))?.extract::<usize>()? > 0 => {
                Some(np.call_method1("asarray", (o,))?)
            }
            other => other.cloned(),
        };
        if n <= PIECE {
            let piece = loaded(&self.classes, &x, Some(&y), o.as_ref(), "")?;
            return py.detach(|| self.add(&piece));
        }
        let ylen: usize = y.len()?;
        if ylen != n {
            return Err(value_error(format!(
                "labels: has {ylen} rows but the logits have {n}"
            )));
        }
        if let Some(o) = o.as_ref().filter(|o| o.hasattr("shape").unwrap_or(false)) {
            let olen: usize = o.len()?;
            if olen != n {
                return Err(value_error(format!(
                    "objectness: has {olen} rows but the logits have {n}"
                )));
            }
        }
        for start in (0..n).step_by(PIECE) {
            let end = (start + PIECE).min(n);
            let s = PySlice::new(py, start as isize, end as isize, 1);
            let part = |a: &Bound<'py, PyAny>| a.get_item(&s);
            let op = match o.as_ref() {
                Some(o) if o.hasattr("shape")? => Some(part(o)?),
                other => other.cloned(),
            };
            let piece = loaded(&self.classes, &part(&x)?, Some(&part(&y)?), op.as_ref(), "")
                .map_err(|e| value_error(format!("rows {start} .. {end}: {e}")))?;
            py.detach(|| self.add(&piece))?;
        }
        Ok(())
    }

    /// The merge of both (a new evaluator; any order and grouping gives the same
    /// counts). Evaluators of other tables or settings raise `ValueError`.
    fn merge(&self, other: &Bound<'_, PyEvaluator>) -> PyResult<Self> {
        let o = other.borrow();
        if o.table_bytes != self.table_bytes || o.temperature != self.temperature {
            return Err(value_error(
                "the evaluators are of different tables or temperatures",
            ));
        }
        let mut methods = self.methods.clone();
        for ((m, a), (n, b)) in methods.iter_mut().zip(&o.methods) {
            if m != n {
                return Err(value_error("the evaluators report different methods"));
            }
            a.merge(b).map_err(|_| {
                value_error("the evaluators have different bins, binning or rank levels")
            })?;
        }
        Ok(Self {
            table: self.table.clone(),
            table_bytes: self.table_bytes.clone(),
            temperature: self.temperature,
            classes: self.classes.clone(),
            methods,
        })
    }

    fn __add__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        match other.cast::<PyEvaluator>() {
            Ok(o) => self.merge(o),
            Err(_) if other.extract::<i64>().is_ok_and(|v| v == 0) => self.merge_nothing(),
            Err(_) => Err(pyo3::exceptions::PyTypeError::new_err(
                "only evaluators add to evaluators",
            )),
        }
    }

    fn __radd__(&self, other: &Bound<'_, PyAny>) -> PyResult<Self> {
        self.__add__(other)
    }

    /// Rows added.
    #[getter]
    fn rows(&self) -> usize {
        self.methods.first().map_or(0, |(_, s)| s.rows())
    }

    /// The metrics of every method on the rows added, as `evaluate`'s dict; no rows
    /// raise `ValueError`.
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let methods = PyDict::new(py);
        let mut cfg = None;
        for (method, acc) in &self.methods {
            let m = acc.report().map_err(|e| value_error(e.to_string()))?;
            let d = PyDict::new(py);
            for (key, v) in m.entries(&self.classes) {
                d.set_item(key, v.filter(|v| v.is_finite()))?;
            }
            methods.set_item(method.name(), d)?;
            cfg = Some(acc.config());
        }
        let out = PyDict::new(py);
        out.set_item("methods", methods)?;
        out.set_item("rows", self.rows())?;
        out.set_item("classes", self.classes.clone())?;
        if let Some((c, levels)) = cfg {
            out.set_item("ece_bins", c.bins)?;
            out.set_item("ece_binning", c.binning.name())?;
            out.set_item("rank_levels", levels)?;
        }
        Ok(out)
    }

    /// The evaluator's state as bytes (the table, the settings, every count and sum).
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        let mut out = Vec::new();
        let mut part = |b: &[u8]| {
            out.extend_from_slice(&(b.len() as u64).to_le_bytes());
            out.extend_from_slice(b);
        };
        part(&self.table_bytes);
        part(&self.temperature.map_or([0u8; 8], f64::to_le_bytes));
        for (m, s) in &self.methods {
            part(m.name().as_bytes());
            part(&s.to_bytes());
        }
        PyBytes::new(py, &out)
    }

    /// Reads `to_bytes`'s output; anything else raises `ValueError`.
    #[staticmethod]
    fn from_bytes(data: &Bound<'_, PyAny>) -> PyResult<Self> {
        let data = arrays::buffer_bytes(data, "data")?;
        let bad =
            || value_error("data: not the bytes of an mlmap.Evaluator (corrupt or truncated)");
        let mut parts = Vec::new();
        let mut rest = data.as_slice();
        while !rest.is_empty() {
            let (len, tail) = rest.split_at_checked(8).ok_or_else(bad)?;
            let len = usize::try_from(u64::from_le_bytes(len.try_into().map_err(|_| bad())?))
                .map_err(|_| bad())?;
            let (p, tail) = tail.split_at_checked(len).ok_or_else(bad)?;
            parts.push(p);
            rest = tail;
        }
        let [table, t, states @ ..] = parts.as_slice() else {
            return Err(bad());
        };
        let table = PyTable::decode(table, "data: ")?;
        let t = f64::from_le_bytes((*t).try_into().map_err(|_| bad())?);
        let temperature = (t != 0.0).then_some(t);
        let ms = methods(&table.table, temperature);
        if states.len() != 2 * ms.len() {
            return Err(bad());
        }
        let mut out = Vec::with_capacity(ms.len());
        for (m, pair) in ms.into_iter().zip(states.chunks_exact(2)) {
            let [name, state] = pair else {
                return Err(bad());
            };
            let s = StreamMetrics::from_bytes(state).ok_or_else(bad)?;
            if *name != m.name().as_bytes() || s.k() != table.table.k() {
                return Err(bad());
            }
            out.push((m, s));
        }
        if out.windows(2).any(|w| match w {
            [(_, a), (_, b)] => a.config() != b.config(),
            _ => false,
        }) {
            return Err(bad());
        }
        Ok(Self {
            classes: table.table.class_names().map(str::to_string).collect(),
            table: table.table.clone(),
            table_bytes: table.bytes.clone(),
            temperature,
            methods: out,
        })
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let from_bytes = slf.get_type().getattr("from_bytes")?;
        Ok((from_bytes, (slf.borrow().to_bytes(slf.py()),)))
    }
}

impl PyEvaluator {
    fn merge_nothing(&self) -> PyResult<Self> {
        Ok(Self {
            table: self.table.clone(),
            table_bytes: self.table_bytes.clone(),
            temperature: self.temperature,
            classes: self.classes.clone(),
            methods: self.methods.clone(),
        })
    }
}
