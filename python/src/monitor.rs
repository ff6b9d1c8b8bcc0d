//! `mlmap.Monitor` and `mlmap.monitor_fit`: the drift monitor of DESIGN §7 from Python,
//! through the layer's own `MonitorSpec` (the same windows as the device and `mlmap
//! monitor`).

use std::path::PathBuf;

use mlmap::host::monitor::{fit_thresholds, has_monitor, with_monitor, DynMonitor};
use mlmap::host::DynTable;
use mlmap::{MonitorParams, MonitorSpec, Thresholds, WindowSummary};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{self, value_error, Rows};
use crate::errors::{io_error, table_error};

/// A drift monitor (docs/DESIGN.md §7) over a table file's monitor section.
///
/// `Monitor.load(path)` or `Monitor.from_bytes(data)` read a table file written by
/// `mlmap monitor fit` (or `mlmap.monitor_fit`): its window and alarm thresholds come
/// from the section. A table without a section needs `window=` and never alarms.
/// `push` feeds detections in order and returns one dict per completed window: `window`,
/// `rows`, `alarm`, `psi_max`, `psi_logit`, `oos_rate`, `q_mean` (None without the open
/// head), `psi` (per class) and `alarms` (per metric).
#[pyclass(module = "mlmap", name = "Monitor")]
pub struct PyMonitor {
    table: DynTable,
    /// The table file with its monitor section.
    bytes: Vec<u8>,
    state: DynMonitor,
    fitted: bool,
}

fn spec<'a>(bytes: &'a [u8], table: &'a DynTable) -> PyResult<MonitorSpec<'a>> {
    MonitorSpec::from_bytes(bytes, &table.view())
        .map_err(|e| table_error(format!("monitor section: {e}")))
}

impl PyMonitor {
    fn build(data: &[u8], window: Option<u32>) -> PyResult<Self> {
        let table = DynTable::from_bytes(data).map_err(|e| table_error(e.to_string()))?;
        let fitted = has_monitor(data);
        let bytes = if fitted {
            let s = spec(data, &table)?;
            if let Some(w) = window.filter(|&w| w != s.params().window) {
                return Err(value_error(format!(
                    "window: the monitor section's thresholds are for windows of {} \
                     detections, not {w}",
                    s.params().window
                )));
            }
            data.to_vec()
        } else {
            let w = window.ok_or_else(|| {
                value_error("window: the table has no monitor section; give window=")
            })?;
            let params = MonitorParams {
                window: w,
                alpha: 0.0,
                thresholds: Thresholds::NONE,
            };
            with_monitor(data, &table, &params).map_err(|e| value_error(e.to_string()))?
        };
        let state = DynMonitor::new(&spec(&bytes, &table)?);
        Ok(Self {
            table,
            bytes,
            state,
            fitted,
        })
    }
}

fn window_dict<'py>(
    py: Python<'py>,
    s: &WindowSummary,
    psi: &[f32],
    names: &[String],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("window", s.window)?;
    d.set_item("rows", s.rows)?;
    d.set_item("alarm", s.alarms.any())?;
    d.set_item("psi_max", s.psi_max)?;
    d.set_item("psi_logit", names.get(usize::from(s.psi_logit)))?;
    d.set_item("oos_rate", s.oos_rate)?;
    d.set_item("q_mean", s.q_mean)?;
    let per = PyDict::new(py);
    for (n, p) in names.iter().zip(psi) {
        per.set_item(n, p)?;
    }
    d.set_item("psi", per)?;
    let a = PyDict::new(py);
    a.set_item("psi", s.alarms.psi)?;
    a.set_item("oos", s.alarms.oos)?;
    a.set_item("q", s.alarms.q)?;
    d.set_item("alarms", a)?;
    Ok(d)
}

#[pymethods]
impl PyMonitor {
    /// A monitor from a table file's bytes (`bytes`, `bytearray` or `memoryview`).
    #[staticmethod]
    #[pyo3(signature = (data, window=None))]
    fn from_bytes(data: &Bound<'_, PyAny>, window: Option<u32>) -> PyResult<Self> {
        let v: Vec<u8> = data.extract()?;
        Self::build(&v, window)
    }

    /// A monitor from a table file.
    #[staticmethod]
    #[pyo3(signature = (path, window=None))]
    fn load(path: PathBuf, window: Option<u32>) -> PyResult<Self> {
        let data = std::fs::read(&path).map_err(|e| io_error(&path, &e))?;
        Self::build(&data, window).map_err(|e| table_error(format!("{}: {e}", path.display())))
    }

    /// Detections per window.
    #[getter]
    fn window(&self) -> PyResult<u32> {
        Ok(spec(&self.bytes, &self.table)?.params().window)
    }

    /// The false-alarm rate the thresholds were fitted for (0.0 without thresholds).
    #[getter]
    fn alpha(&self) -> PyResult<f32> {
        Ok(spec(&self.bytes, &self.table)?.params().alpha)
    }

    /// The thresholds: `{"psi": ..., "oos": ..., "q": ...}` (infinite: never alarms).
    #[getter]
    fn thresholds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = spec(&self.bytes, &self.table)?.params().thresholds;
        let d = PyDict::new(py);
        d.set_item("psi", t.psi)?;
        d.set_item("oos", t.oos)?;
        d.set_item("q", t.q)?;
        Ok(d)
    }

    /// Whether the table file has fitted thresholds (a monitor section).
    #[getter]
    fn fitted(&self) -> bool {
        self.fitted
    }

    /// Pushes detections in order: `logits` `(N, K)` (or `(K,)` for one), objectness
    /// `None`, a number or `(N,)`; returns the windows they complete, as dicts.
    #[pyo3(signature = (logits, objectness=None))]
    fn push<'py>(
        &mut self,
        py: Python<'py>,
        logits: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let np = py.import("numpy")?;
        let x2 = np.call_method1("atleast_2d", (logits,))?;
        let x = arrays::logits(&x2, "logits")?;
        let k = self.table.k();
        if x.cols != k {
            return Err(value_error(format!(
                "logits: has {} columns; the table has {k} classes",
                x.cols
            )));
        }
        let n = x.rows;
        let os = arrays::objectness(objectness, "objectness", n)?;
        let (rows, col) = (x.rows()?, os.column()?);
        let names: Vec<String> = self.table.class_names().map(String::from).collect();
        let spec = spec(&self.bytes, &self.table)?;
        let mut out = Vec::new();
        let mut row = vec![0.0f32; k];
        for i in 0..n {
            let r = rows
                .get(i * k..(i + 1) * k)
                .ok_or_else(|| value_error("logits"))?;
            match r {
                Rows::F32(s) => row.copy_from_slice(s),
                Rows::F64(s) => {
                    for (d, &v) in row.iter_mut().zip(s) {
                        *d = v as f32;
                    }
                }
            }
            let done = self
                .state
                .push(&spec, &row, col.get_f32(i))
                .map_err(|e| value_error(format!("logits: row index {i}: {e}")))?;
            if let Some((s, psi)) = done {
                out.push(window_dict(py, &s, &psi, &names)?);
            }
        }
        Ok(out)
    }

    /// Ends the current window (the end of a log): its dict, or None when empty. A
    /// window of fewer than `window` detections raises no alarm.
    fn finish<'py>(&mut self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let names: Vec<String> = self.table.class_names().map(String::from).collect();
        let spec = spec(&self.bytes, &self.table)?;
        match self.state.finish(&spec) {
            Some((s, psi)) => Ok(Some(window_dict(py, &s, &psi, &names)?)),
            None => Ok(None),
        }
    }

    /// The table file with its monitor section (what `Monitor.from_bytes` reads).
    fn to_bytes(&self) -> Vec<u8> {
        self.bytes.clone()
    }
}

/// Fits the monitor's thresholds (docs/DESIGN.md §7) on in-distribution rows and returns
/// the table file's bytes with its monitor section: what `mlmap monitor fit` writes for
/// the same rows, window, false-alarm rate, number of windows and seed.
#[pyfunction]
#[pyo3(signature = (table, logits, objectness=None, *, window, false_alarm, windows=2000, seed=0))]
#[allow(clippy::too_many_arguments)]
pub fn monitor_fit(
    table: &Bound<'_, PyAny>,
    logits: &Bound<'_, PyAny>,
    objectness: Option<&Bound<'_, PyAny>>,
    window: u32,
    false_alarm: f64,
    windows: usize,
    seed: u64,
) -> PyResult<Vec<u8>> {
    let data: Vec<u8> = table.call_method0("to_bytes")?.extract()?;
    let t = DynTable::from_bytes(&data).map_err(|e| table_error(e.to_string()))?;
    if !(1..=1 << 24).contains(&window) {
        return Err(arrays::out_of_range(
            "window",
            &window.to_string(),
            "1 to 16777216",
        ));
    }
    if !(false_alarm > 0.0 && false_alarm <= 0.5) {
        return Err(arrays::out_of_range(
            "false_alarm",
            &false_alarm.to_string(),
            "(0, 0.5]",
        ));
    }
    if !(100..=1_000_000).contains(&windows) {
        return Err(arrays::out_of_range(
            "windows",
            &windows.to_string(),
            "100 to 1000000",
        ));
    }
    let draft = MonitorParams {
        window,
        alpha: 0.0,
        thresholds: Thresholds::NONE,
    };
    let file = with_monitor(&data, &t, &draft).map_err(|e| value_error(e.to_string()))?;
    let s = spec(&file, &t)?;
    let x = arrays::logits(logits, "logits")?;
    if x.cols != t.k() {
        return Err(value_error(format!(
            "logits: has {} columns; the table has {} classes",
            x.cols,
            t.k()
        )));
    }
    let n = x.rows;
    let os = arrays::objectness(objectness, "objectness", n)?;
    let (rows, col) = (x.rows()?, os.column()?);
    let xs: Vec<f32> = match rows {
        Rows::F32(v) => v.to_vec(),
        Rows::F64(v) => v.iter().map(|&a| a as f32).collect(),
    };
    let oss: Vec<f32> = (0..n).map(|i| col.get_f32(i)).collect();
    let fitted = fit_thresholds(&s, &xs, &oss, false_alarm, windows, seed)
        .map_err(|(i, e)| value_error(format!("logits: row index {i}: {e}")))?;
    let params = MonitorParams {
        window,
        alpha: false_alarm as f32,
        thresholds: fitted.thresholds,
    };
    with_monitor(&data, &t, &params).map_err(|e| value_error(e.to_string()))
}
