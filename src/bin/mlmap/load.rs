//! Reading data files into memory for the commands that need every row at once
//! (`eval`, `tune`); `fit` and `apply` stream instead.

use std::path::Path;

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

/// Opens a data source, mapping errors.
pub fn open(path: &Path) -> Result<DataSource> {
    DataSource::open(path).map_err(data_error)
}

/// `PATH:LINE` for a CSV line, `PATH: row index I` for an NPY row (as data errors).
pub fn at(path: &Path, location: Location) -> String {
    match location {
        Location::Line(l) => format!("{}:{l}", path.display()),
        Location::Row(r) => format!("{}: row index {r}", path.display()),
    }
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
    /// Whether the file has labels (a `label` column or `labels.npy`).
    pub has_labels: bool,
    /// Where the first row without a label is, if any.
    pub first_missing_label: Option<Location>,
}

impl Loaded {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// Labels as `Option<class>` (background → None), refusing missing labels.
    pub fn class_labels(&self, path: &Path) -> Result<Vec<Option<usize>>> {
        if !self.has_labels {
            return Err(CliError::input(
                path,
                "has no labels (a `label` column or labels.npy); labelled rows are needed here",
            ));
        }
        if let Some(loc) = self.first_missing_label {
            return Err(CliError::Input(format!(
                "{}: column \"label\": the label is empty; a class name or background \
                 is needed here",
                at(path, loc)
            )));
        }
        Ok(self
            .labels
            .iter()
            .map(|l| match l {
                Label::Class(c) => Some(*c),
                Label::Background | Label::Missing => None,
            })
            .collect())
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
        has_labels: src.has_labels(),
        first_missing_label: None,
    };
    src.for_each_row(|row| -> Result<()> {
        if row.label == Label::Missing && d.first_missing_label.is_none() {
            d.first_missing_label = Some(row.location());
        }
        d.labels.push(row.label);
        d.objectness.push(row.objectness);
        d.logits.extend_from_slice(row.logits);
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
