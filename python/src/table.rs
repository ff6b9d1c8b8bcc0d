//! `mlmap.Table`: a validated table of any shape, its bytes, its settings, and scoring
//! numpy arrays through the layer's own `f32` code.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::path::PathBuf;

use mlmap::host::names::Named;
use mlmap::host::{DynQTable, DynTable};
use mlmap::{Head, InferError, QTableError};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};

use crate::arrays::{self, value_error};
use crate::errors::{io_error, table_error};
use crate::score::{self, RowError};

/// A fitted mlmap table (any number of classes and bins), immutable.
///
/// Build one with `mlmap.fit`, `mlmap.tune`, `Table.load(path)` or
/// `Table.from_bytes(data)`. Every way in checks the checksum and every table
/// invariant, and a bad table raises `mlmap.TableError` (a `ValueError`) with the
/// layer's message.
///
/// Scoring (`ml`, `map`, `bayes`, `open`, `scores`) runs the device's `f32` code on
/// every row, so the scores are bit for bit those of the firmware and of `mlmap apply`.
///
/// A file with a quantized section (DESIGN §6.19, `mlmap quantize`) keeps it: the
/// section is checked (its CRC and the table it names), described by `quantized`, and
/// written back unchanged by `to_bytes`, `save` and pickling.
#[pyclass(module = "mlmap", frozen, name = "Table")]
pub struct PyTable {
    pub(crate) table: DynTable,
    /// The file's bytes: the canonical encoding (DESIGN §6.10; equal tables have equal
    /// bytes), then the quantized section the table was read with, if any; a file with a
    /// conformal section is kept whole.
    pub(crate) bytes: Vec<u8>,
    /// The quantized section's code width, length in bytes, and whether it holds the
    /// Bayes head.
    quantized: Option<(u8, usize, bool)>,
}

impl PyTable {
    /// Wraps a table, encoding it once.
    pub(crate) fn new(table: DynTable) -> PyResult<Self> {
        let bytes = table
            .to_vec()
            .map_err(|e| table_error(format!("cannot encode the table: {e}")))?;
        Ok(Self {
            table,
            bytes,
            quantized: None,
        })
    }

    /// Decodes the bytes of a table file, keeping a valid quantized section and
    /// refusing an invalid one; `context` prefixes the messages (a file's path).
    pub(crate) fn decode(bytes: &[u8], context: &str) -> PyResult<Self> {
        let error = |msg: String| table_error(format!("{context}{msg}"));
        let table = DynTable::from_bytes(bytes).map_err(|e| error(e.to_string()))?;
        let mut t = Self::new(table)?;
        match DynQTable::from_bytes(bytes) {
            Ok(q) => {
                t.quantized = Some((q.bits(), q.section_len(), q.has_bayes()));
                t.bytes = bytes.to_vec();
            }
            Err(QTableError::NotQuantized) => {}
            Err(e) => return Err(error(format!("quantized section: {e}"))),
        }
        // A conformal section (DESIGN §8) is checked and kept, with the file's other
        // sections.
        if mlmap::section_of(bytes, mlmap::CONFORMAL_MAGIC).is_some() {
            mlmap::ConformalSpec::from_bytes(bytes, &t.table.view())
                .map_err(|e| error(format!("conformal section: {e}")))?;
            t.bytes = bytes.to_vec();
        }
        Ok(t)
    }

    fn head_names(&self) -> Vec<&'static str> {
        let mut heads = vec![Head::Ml.name(), Head::Map.name()];
        if self.table.bayes_head().is_some() {
            heads.push(Head::Bayes.name());
        }
        if self.table.open_params().is_some() {
            heads.push(Head::Open.name());
        }
        heads
    }

    /// Scores `logits` with `head`, releasing the GIL while the layer runs.
    fn score_array<'py>(
        &self,
        py: Python<'py>,
        head: Head,
        logits: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let x = arrays::logits(logits, "logits")?;
        let k = self.table.k();
        if x.cols != k {
            return Err(value_error(format!(
                "logits: has {} columns; the table has {k} classes ({})",
                x.cols,
                self.table.class_names().collect::<Vec<_>>().join(", ")
            )));
        }
        let n = x.rows;
        let os = arrays::objectness(objectness, "objectness", n)?;
        let (rows, col, table) = (x.rows()?, os.column()?, &self.table);
        let scored = py.detach(|| score::score(table, head, rows, col, n));
        let out = scored.map_err(|RowError { row, error }| match error {
            InferError::NoBayesHead | InferError::NoOpenHead => value_error(error.to_string()),
            InferError::Objectness => value_error(format!("objectness: row index {row}: {error}")),
            _ => value_error(format!("logits: row index {row}: {error}")),
        })?;
        PyArray1::from_vec(py, out).reshape([n, k])
    }
}

/// `(edges, frequencies)` of a histogram.
type EdgesAndFrequencies<'py> = (Bound<'py, PyArray1<f32>>, Bound<'py, PyArray1<f32>>);

/// A head by its name in reports (`ml`, `map`, `bayes`, `open`).
pub fn parse_head(name: &str) -> PyResult<Head> {
    Head::from_name(name).map_err(|e| value_error(e.to_string()))
}

#[pymethods]
impl PyTable {
    /// Decodes a table from the bytes of a `.mlmap` file: `bytes`, `bytearray`, a
    /// `memoryview` or any C-contiguous buffer of single bytes (a numpy `uint8` array).
    /// A quantized section after the table is checked and kept.
    ///
    /// Raises `mlmap.TableError` (a `ValueError`) with the layer's message when the
    /// bytes are not a valid table (or carry an invalid quantized section), and
    /// `TypeError` for an object that is not such a buffer.
    #[staticmethod]
    fn from_bytes(data: &Bound<'_, PyAny>) -> PyResult<Self> {
        let bytes = arrays::buffer_bytes(data, "data")?;
        Self::decode(&bytes, "")
    }

    /// The file's bytes (the `.mlmap` file format, docs/FORMAT.md): the table, then
    /// its quantized section when it was read with one.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.bytes)
    }

    /// Reads and validates a `.mlmap` file (keeping a quantized section); errors name
    /// the file, as `mlmap` does.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let bytes = std::fs::read(&path).map_err(|e| io_error(&path, &e))?;
        Self::decode(&bytes, &format!("{}: ", path.display()))
    }

    /// Writes the table to `path`, with its quantized section if it has one (through
    /// a temporary file renamed into place, so a failed write never leaves a
    /// half-written table).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        crate::errors::write_atomic(&path, &self.bytes)
    }

    /// Class names, in column order.
    #[getter]
    fn classes(&self) -> Vec<String> {
        self.table.class_names().map(str::to_string).collect()
    }

    /// Number of classes K.
    #[getter]
    fn k(&self) -> usize {
        self.table.k()
    }

    /// The heads the table holds, in the order of `mlmap.HEADS`: `("ml", "map")`,
    /// `("ml", "map", "bayes")` or `("ml", "map", "bayes", "open")` (the open head is
    /// built on the Bayes head; format version 3).
    #[getter]
    fn heads<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        PyTuple::new(py, self.head_names())
    }

    /// Bins of the ML histograms.
    #[getter]
    fn bins_ml(&self) -> usize {
        self.table.bins_ml()
    }

    /// Bins of the MAP histograms.
    #[getter]
    fn bins_map(&self) -> usize {
        self.table.bins_map()
    }

    /// Bins per logit of the Bayes head; `None` without that head.
    #[getter]
    fn bins_bayes(&self) -> Option<usize> {
        self.table.bayes_head().map(|b| b.bins())
    }

    /// Smoothing lambda of the ML head (the `f32` the table stores).
    #[getter]
    fn lambda_ml(&self) -> f32 {
        self.table.settings().lambda_ml
    }

    /// Smoothing lambda of the MAP head.
    #[getter]
    fn lambda_map(&self) -> f32 {
        self.table.settings().lambda_map
    }

    /// Smoothing lambda of the Bayes head; `None` without that head.
    #[getter]
    fn lambda_bayes(&self) -> Option<f32> {
        self.table.bayes_head().map(|b| b.lambda())
    }

    /// The open head's parameters (DESIGN §1.8), the `f32` values the table stores:
    /// `{"temperature": T, "epsilon": epsilon}`; `None` without that head (a version-1
    /// or version-2 table). `mlmap fit` writes `T = 1` and `epsilon = 0`; `mlmap tune`
    /// fits them on validation data.
    #[getter]
    fn open_params<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(o) = self.table.open_params() else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("temperature", o.temperature())?;
        d.set_item("epsilon", o.epsilon())?;
        Ok(Some(d))
    }

    /// How the fit placed the bin edges: `"linspace"` or `"matlab"`.
    #[getter]
    fn edges(&self) -> &'static str {
        self.table.settings().edge_mode.name()
    }

    /// The likelihood above the last edge: `"zero"` or `"clamp"`.
    #[getter]
    fn upper_tail(&self) -> &'static str {
        self.table.settings().upper_tail.name()
    }

    /// Training rows per class (the fit's provenance).
    #[getter]
    fn training_rows(&self) -> Vec<u64> {
        self.table.rows().to_vec()
    }

    /// The Bayes head's categories: the classes, then `"background"` when it learnt
    /// one; `None` without that head.
    #[getter]
    fn categories(&self) -> Option<Vec<String>> {
        let b = self.table.bayes_head()?;
        let mut c = self.classes();
        if b.has_background() {
            c.push("background".into());
        }
        Some(c)
    }

    /// The Gaussian priors of the MAP head: `(mean, variance)` per class.
    #[getter]
    fn priors(&self) -> Vec<(f32, f32)> {
        self.table
            .priors()
            .iter()
            .map(|g| (g.mean(), g.variance()))
            .collect()
    }

    /// Size of the file in bytes (`len(to_bytes())`): the encoded table, and its
    /// quantized section if it has one.
    #[getter]
    fn size(&self) -> usize {
        self.bytes.len()
    }

    /// The quantized section the table was read with (DESIGN §6.19): `None`, or
    /// `{"bits": 8 or 16, "size": bytes, "heads": ("ml", "map"[, "bayes"])}`. Scoring
    /// always runs the float table; the section is kept so that the file round-trips.
    #[getter]
    fn quantized<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some((bits, size, bayes)) = self.quantized else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("bits", bits)?;
        d.set_item("size", size)?;
        let mut heads = vec![Head::Ml.name(), Head::Map.name()];
        if bayes {
            heads.push(Head::Bayes.name());
        }
        d.set_item("heads", PyTuple::new(py, heads)?)?;
        Ok(Some(d))
    }

    /// The recalibration map of `head` (`"ml"`, `"map"`, `"bayes"` or `"open"`,
    /// DESIGN §1.9) as its knots, a list of `(x, y)` (`f32` values, `x` from 0 to 1),
    /// or `None` when the table holds no map for that head. Every scoring method
    /// applies it: the head's top score `t` becomes `g(t)`, the other scores keep
    /// their ratios to it.
    fn recal_map(&self, head: &str) -> PyResult<Option<Vec<(f32, f32)>>> {
        let head = parse_head(head)?;
        Ok(self
            .table
            .recal_map(head)
            .map(|g| g.knots().iter().map(|k| (k.x, k.y)).collect()))
    }

    /// The same table without its recalibration maps: every head's own scores (the
    /// ones `mlmap.tune` fits the maps to). A quantized section is not kept.
    fn without_maps(&self) -> PyResult<Self> {
        Self::new(self.table.clone().without_maps())
    }

    /// The histogram of `head` (`"ml"` or `"map"`) for class `cls` (an index or a
    /// name): `(edges, frequencies)`, `B + 1` edges as the layer computes them (`f32`)
    /// and `B` frequencies. The Bayes and open heads have no per-class histogram: they
    /// raise `ValueError`.
    fn histogram<'py>(
        &self,
        py: Python<'py>,
        head: &str,
        cls: &Bound<'py, PyAny>,
    ) -> PyResult<EdgesAndFrequencies<'py>> {
        let hists = match parse_head(head)? {
            Head::Ml => self.table.ml_histograms(),
            Head::Map => self.table.map_histograms(),
            Head::Bayes => {
                return Err(value_error(
                    "the Bayes head has one histogram per logit and category; \
                     histogram() takes \"ml\" or \"map\"",
                ))
            }
            Head::Open => {
                return Err(value_error(
                    "the open head has no histogram of its own (it uses the Bayes head's, \
                     one per logit and category); histogram() takes \"ml\" or \"map\"",
                ))
            }
        };
        let i = self.class_index(cls)?;
        let h = hists
            .get(i)
            .ok_or_else(|| value_error(format!("no class {i}")))?;
        let edges: Vec<f32> = (0..=h.bins()).map(|b| h.edge(b)).collect();
        Ok((
            PyArray1::from_vec(py, edges),
            PyArray1::from_vec(py, h.frequencies().to_vec()),
        ))
    }

    /// ML scores of every row: `logits` is `(N, K)` float32 or float64 (any order),
    /// `objectness` `None` (1.0), a number or an `(N,)` array in `[0, 1]`. Returns
    /// `(N, K)` float32, each row summing to its objectness (before the head's
    /// recalibration map, if the table holds one: see `recal_map`).
    #[pyo3(signature = (logits, objectness=None))]
    fn ml<'py>(
        &self,
        py: Python<'py>,
        logits: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        self.score_array(py, Head::Ml, logits, objectness)
    }

    /// MAP scores of every row (as `ml`).
    #[pyo3(signature = (logits, objectness=None))]
    fn map<'py>(
        &self,
        py: Python<'py>,
        logits: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        self.score_array(py, Head::Map, logits, objectness)
    }

    /// Bayes scores of every row (as `ml`; with a background category a row sums to
    /// at most its objectness). Raises `ValueError` for a table without that head.
    #[pyo3(signature = (logits, objectness=None))]
    fn bayes<'py>(
        &self,
        py: Python<'py>,
        logits: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        self.score_array(py, Head::Bayes, logits, objectness)
    }

    /// Open-head scores of every row (DESIGN §1.8, as `ml`): `OS * q * softmax(z / T)`,
    /// the detector's softmax at the table's temperature times the probability `q`
    /// that the detection is of a known class, so a row sums to at most its
    /// objectness and the classes rank as the logits do. Raises `ValueError` for a
    /// table without that head (a version-1 or version-2 table).
    #[pyo3(signature = (logits, objectness=None))]
    fn open<'py>(
        &self,
        py: Python<'py>,
        logits: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        self.score_array(py, Head::Open, logits, objectness)
    }

    /// The scores of `head` (`"ml"`, `"map"`, `"bayes"` or `"open"`), as `ml`.
    #[pyo3(signature = (head, logits, objectness=None))]
    fn scores<'py>(
        &self,
        py: Python<'py>,
        head: &str,
        logits: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        self.score_array(py, parse_head(head)?, logits, objectness)
    }

    fn __repr__(&self) -> String {
        let classes: Vec<String> = self.table.class_names().map(|c| format!("'{c}'")).collect();
        let bins = match self.table.bayes_head() {
            Some(b) => format!(
                "ml={}, map={}, bayes={}",
                self.table.bins_ml(),
                self.table.bins_map(),
                b.bins()
            ),
            None => format!("ml={}, map={}", self.table.bins_ml(), self.table.bins_map()),
        };
        let open = match self.table.open_params() {
            Some(o) => format!(
                ", open=(temperature={:?}, epsilon={:?})",
                o.temperature(),
                o.epsilon()
            ),
            None => String::new(),
        };
        let quantized = match self.quantized {
            Some((bits, ..)) => format!(", quantized=int{bits}"),
            None => String::new(),
        };
        format!(
            "Table(classes=[{}], bins=({bins}){open}, edges={:?}, size={}{quantized})",
            classes.join(", "),
            self.edges(),
            self.bytes.len()
        )
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyTable>()
            .is_ok_and(|o| o.get().bytes == self.bytes)
    }

    fn __hash__(&self) -> u64 {
        let mut h = DefaultHasher::new();
        self.bytes.hash(&mut h);
        h.finish()
    }

    /// Pickles through the table's bytes.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let py = slf.py();
        let from_bytes = slf.get_type().getattr("from_bytes")?;
        Ok((from_bytes, (PyBytes::new(py, &slf.get().bytes),)))
    }
}

impl PyTable {
    /// A class given as an index or a name.
    fn class_index(&self, cls: &Bound<'_, PyAny>) -> PyResult<usize> {
        let k = self.table.k();
        if let Ok(name) = cls.extract::<String>() {
            return self
                .table
                .class_names()
                .position(|c| c == name)
                .ok_or_else(|| value_error(format!("{name:?} is not a class of the table")));
        }
        let i: arrays::Count = cls.extract()?;
        i.value()
            .filter(|&i| i < k)
            .ok_or_else(|| value_error(format!("class index {} is not in 0..{k}", i.text())))
    }
}
