//! Helpers more than one command uses: reading and writing tables and fit statistics,
//! writing plots.

use std::fs;
use std::path::Path;

use mlmap::host::eval::Evaluation;
use mlmap::host::fit::FitFile;
use mlmap::host::names::Named;
use mlmap::host::{plots, DynTable};

use crate::error::{CliError, Result};
use crate::output;

/// Reads and validates a table file, with errors naming it.
pub fn read_table(path: &Path) -> Result<(DynTable, Vec<u8>)> {
    let bytes = fs::read(path).map_err(|e| CliError::input(path, e))?;
    let table = DynTable::from_bytes(&bytes).map_err(|e| CliError::input(path, e))?;
    Ok((table, bytes))
}

/// Encodes and writes a table atomically; returns its size.
pub fn write_table(path: &Path, table: &DynTable) -> Result<usize> {
    let bytes = table
        .to_vec()
        .map_err(|e| CliError::internal(path, format!("cannot encode the table: {e}")))?;
    output::write_bytes_atomic(path, &bytes)?;
    Ok(bytes.len())
}

/// Writes every plot of an evaluation into `dir`; returns how many files were written.
pub fn write_plots(ev: &Evaluation, dir: &Path, table: &DynTable) -> Result<usize> {
    fs::create_dir_all(dir).map_err(|e| CliError::input(dir, format!("cannot create: {e}")))?;
    let methods: Vec<(&str, &[f64])> = ev
        .methods
        .iter()
        .map(|r| (r.method.name(), r.test.as_slice()))
        .collect();
    let set = plots::Scored {
        class_names: &ev.class_names,
        methods: &methods,
        labels: &ev.labels,
        logits: &ev.logits,
    };
    let written = plots::plot_all(dir, &set, &ev.config, Some(table)).map_err(|e| match &e {
        plots::PlotError::Io { source, .. } if output::location_refused(source) => {
            CliError::Input(e.to_string())
        }
        _ => CliError::Internal(e.to_string()),
    })?;
    Ok(written.len())
}

/// Reads a file written by `stats` or `merge` (pass-(a) statistics or pass-(b) counts),
/// with errors naming it.
pub fn read_fit_file(path: &Path) -> Result<FitFile> {
    let bytes = fs::read(path).map_err(|e| CliError::input(path, e))?;
    FitFile::from_bytes(&bytes).map_err(|e| CliError::input(path, e))
}

/// Writes serialized statistics or counts atomically, and prints what was written.
pub fn write_fit_file(path: &Path, file: &FitFile) -> Result<()> {
    let (bytes, what) = match file {
        FitFile::Stats(s) => (
            s.to_bytes(),
            format!(
                "pass-(a) statistics of {} rows; training rows per class: {}",
                s.rows(),
                s.moments()
                    .iter()
                    .map(|m| format!("{} {}", m.name(), m.count()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ),
        FitFile::Counts(c) => (
            c.to_bytes(),
            format!("pass-(b) bin counts of {} rows", c.rows()),
        ),
    };
    output::write_bytes_atomic(path, &bytes)?;
    output::print(&format!(
        "wrote {} ({} bytes): {what}\n",
        path.display(),
        bytes.len()
    ))
}

/// One class's threshold as `inspect` and `conformal` print it.
pub fn threshold_line(name: &str, n: u32, t: f32, alpha: f32) -> String {
    let r = mlmap::threshold_rank(n, alpha);
    if r == 0 {
        format!(
            "  {name}: -inf (every set holds it: {n} calibration rows, floor((n + 1) alpha) = 0; \
             at least {} rows give a threshold)",
            ((1.0 / f64::from(alpha)).ceil() as u64).saturating_sub(1)
        )
    } else {
        format!("  {name}: {t} (rank {r} of {n} calibration rows)")
    }
}
