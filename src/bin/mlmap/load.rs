//! Reading data files into memory for the commands that need every row at once
//! (`eval`, `tune`); `fit` and `apply` stream instead.

use std::path::Path;

use std::fmt::Display;

use mlmap::host::dataset::{DataError, DataSource, Label, Location};

use crate::error::{CliError, Result};

/// Maps a data error to exit code 2 (bad input) or 1 (I/O failure).
pub fn data_error(e: DataError) -> CliError {
    if e.is_bad_input() {
        CliError::Input(e.to_string())
    } else {
        CliError::Internal(e.to_string())
    }
}

/// Bad input at a position of a file, formatted like the readers' errors.
pub fn at(path: &Path, location: Location, msg: impl Display) -> CliError {
    match location {
        Location::Line(l) => CliError::Input(format!("{}:{l}: {msg}", path.display())),
        Location::Row(r) => CliError::Input(format!("{}: row index {r}: {msg}", path.display())),
    }
}

/// Opens a data source, mapping errors.
pub fn open(path: &Path) -> Result<DataSource> {
    DataSource::open(path).map_err(data_error)
}

/// Every row of a data file.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// Class names, in column order.
    pub classes: Vec<String>,
    /// N labels.
    pub labels: Vec<Label>,
    /// N objectness scores.
    pub objectness: Vec<f64>,
    /// N x K logits, row-major.
    pub logits: Vec<f64>,
    /// Where each row is in its file (CSV line or NPY row index), for errors.
    pub locations: Vec<Location>,
}

impl Loaded {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// Labels as `Option<class>` (background → None), refusing missing labels.
    pub fn class_labels(&self, path: &Path) -> Result<Vec<Option<usize>>> {
        self.labels
            .iter()
            .enumerate()
            .map(|(i, l)| match l {
                Label::Class(c) => Ok(Some(*c)),
                Label::Background => Ok(None),
                Label::Missing => Err(CliError::input(
                    path,
                    format!(
                        "data row {}: a label is needed here (class name or background)",
                        i + 1
                    ),
                )),
            })
            .collect()
    }

    /// Logits in the layer's precision.
    pub fn logits_f32(&self) -> Vec<f32> {
        self.logits.iter().map(|&x| x as f32).collect()
    }

    /// Objectness in the layer's precision.
    pub fn objectness_f32(&self) -> Vec<f32> {
        self.objectness.iter().map(|&x| x as f32).collect()
    }
}

/// Reads every row of `path`.
pub fn load(path: &Path) -> Result<Loaded> {
    let src = open(path)?;
    let mut d = Loaded {
        classes: src.classes().to_vec(),
        labels: Vec::new(),
        objectness: Vec::new(),
        logits: Vec::new(),
        locations: Vec::new(),
    };
    src.for_each_row(|row| -> Result<()> {
        d.labels.push(row.label);
        d.objectness.push(row.objectness);
        d.logits.extend_from_slice(row.logits);
        d.locations.push(row.location());
        Ok(())
    })?;
    if d.labels.is_empty() {
        return Err(CliError::input(path, "holds no data rows"));
    }
    Ok(d)
}

impl From<DataError> for CliError {
    fn from(e: DataError) -> Self {
        data_error(e)
    }
}

/// Refuses data whose classes differ from the table's (names and order).
pub fn check_classes<'a>(
    path: &Path,
    data: &[String],
    table: impl Iterator<Item = &'a str>,
) -> Result<()> {
    let table: Vec<&str> = table.collect();
    if data.len() != table.len() || data.iter().zip(&table).any(|(a, b)| a != b) {
        return Err(CliError::input(
            path,
            format!(
                "its classes [{}] differ from the table's [{}] (same names, same order needed)",
                data.join(", "),
                table.join(", ")
            ),
        ));
    }
    Ok(())
}
