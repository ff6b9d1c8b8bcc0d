//! Every row of a data file in memory, for the pipelines that need them all at once
//! ([`eval`](super::eval), [`tune`](super::tune)); fitting and scoring stream instead.

use std::path::Path;

use super::dataset::{echo, DataError, DataErrorKind, DataSource, Label, Location, Row, RowSource};
use super::error::HostError;

/// Opens a data source (CSV file or NPY directory).
///
/// # Errors
///
/// [`HostError`] naming the file: bad input for a malformed file, internal for I/O.
pub fn open(path: &Path) -> Result<DataSource, HostError> {
    Ok(DataSource::open(path)?)
}

/// Opens a data source for a command that reads it more than once (`fit` makes two
/// passes): an input that can be read only once (a pipe, a FIFO: DESIGN §2) is refused
/// before anything is read from it.
///
/// # Errors
///
/// As [`open`]; [`DataErrorKind::ReadOnce`] for a file that is not a regular file or a
/// directory.
pub fn open_twice(path: &Path) -> Result<DataSource, HostError> {
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
        return Err(DataError::new(path, DataErrorKind::ReadOnce).into());
    }
    open(path)
}

/// Opens a data source of quantized logits (an NPY directory's logits `int8` or
/// `int16`); see [`DataSource::open_codes`].
///
/// # Errors
///
/// As [`open`].
pub fn open_codes(path: &Path) -> Result<DataSource, HostError> {
    Ok(DataSource::open_codes(path)?)
}

/// `PATH:LINE` for a CSV line, `PATH: row index I` for an NPY row (as data errors).
pub fn at(path: &Path, location: Location) -> String {
    match location {
        Location::Line(l) => format!("{}:{l}", path.display()),
        Location::Row(r) => format!("{}: row index {r}", path.display()),
    }
}

/// Every row of a data file, or rows built in memory (e.g. from arrays).
///
/// As a [`RowSource`] it can be fitted from ([`fit`](crate::fit::fit()),
/// [`TrainingSet::read`](crate::fit::TrainingSet::read), [`FitStats`](crate::fit::FitStats)).
/// Its messages name the rows `rows`, by row index (or by the `locations` recorded when
/// read from a file). Rows built in memory are checked as they are streamed: the
/// lengths of the fields must agree, logits must be finite, objectness in `[0, 1]`,
/// labels class indices.
///
/// ```
/// use mlmap_host::data::Loaded;
/// use mlmap_host::dataset::Label;
/// use mlmap_host::fit::{fit, FitParams};
///
/// let rows = Loaded {
///     classes: vec!["car".into(), "person".into()],
///     labels: vec![Label::Class(0), Label::Class(1), Label::Class(0), Label::Class(1)],
///     objectness: vec![1.0; 4],
///     logits: vec![2.0, -1.0, 3.0, 1.5, 1.0, 0.0, -0.5, 2.5],
///     locations: Vec::new(),
///     has_labels: true,
///     first_missing_label: None,
/// };
/// let table = fit(&rows, &FitParams::default())?;
/// assert_eq!(table.rows(), &[2, 2]);
/// # Ok::<(), mlmap_host::fit::FitError>(())
/// ```
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
    /// Where each row is in the file.
    pub locations: Vec<Location>,
    /// Whether the file has labels (a `label` column or `labels.npy`).
    pub has_labels: bool,
    /// Where the first row without a label is, if any.
    pub first_missing_label: Option<Location>,
}

impl Loaded {
    /// Reads every row of `path`.
    ///
    /// # Errors
    ///
    /// [`HostError`] naming the file (and line): a malformed file, or no rows.
    pub fn read(path: &Path) -> Result<Self, HostError> {
        Self::read_from(&open(path)?, path, "").map(|(d, _)| d)
    }

    /// Reads every row of `path` with `column` declared not a class (DESIGN §4,
    /// `eval --group-by`), and the column's text of every row: `None` when the file
    /// does not have the column and `required` is false.
    ///
    /// # Errors
    ///
    /// As [`read`](Self::read); also, naming the file, when `required` and the file has
    /// no such column (an NPY directory has none), and naming the line when a row's
    /// value is empty.
    pub fn read_with_column(
        path: &Path,
        column: &str,
        required: bool,
    ) -> Result<(Self, Option<Vec<String>>), HostError> {
        let src = DataSource::open_with_column(path, column)?;
        if !src.has_column() {
            if !required {
                return Self::read_from(&src, path, column).map(|(d, _)| (d, None));
            }
            let why = if path.is_dir() {
                "is an NPY directory, which has no column to group by: give a CSV file"
            } else {
                "has no such column"
            };
            return Err(HostError::Input(format!(
                "{}: column {:?} (--group-by): {why}",
                path.display(),
                echo(column)
            )));
        }
        let (d, values) = Self::read_from(&src, path, column)?;
        Ok((d, Some(values)))
    }

    /// Every row of `src` (read from `path`), with the text of its declared column
    /// `column` (empty without one).
    fn read_from(
        src: &DataSource,
        path: &Path,
        column: &str,
    ) -> Result<(Self, Vec<String>), HostError> {
        let mut d = Self {
            classes: src.classes().to_vec(),
            labels: Vec::new(),
            objectness: Vec::new(),
            logits: Vec::new(),
            locations: Vec::new(),
            has_labels: src.has_labels(),
            first_missing_label: None,
        };
        let mut values = Vec::new();
        src.for_each_row_with_column(|row, value| -> Result<(), HostError> {
            if let Some(v) = value {
                if v.is_empty() {
                    return Err(HostError::Input(format!(
                        "{}: column {:?}: the group value is empty; every row needs one",
                        at(path, row.location()),
                        echo(column)
                    )));
                }
                values.push(v.to_string());
            }
            if row.label == Label::Missing && d.first_missing_label.is_none() {
                d.first_missing_label = Some(row.location());
            }
            d.labels.push(row.label);
            d.objectness.push(row.objectness);
            d.logits.extend_from_slice(row.logits);
            d.locations.push(row.location());
            Ok(())
        })?;
        if d.labels.is_empty() {
            return Err(HostError::input(path, "holds no data rows"));
        }
        Ok((d, values))
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// Whether there are no rows ([`Loaded::read`] refuses such files).
    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    /// Labels as `Option<class>` (background → `None`), refusing missing labels.
    ///
    /// # Errors
    ///
    /// [`HostError::Input`] naming `path` (and the line) when the file has no labels
    /// or a row's label is empty.
    pub fn class_labels(&self, path: &Path) -> Result<Vec<Option<usize>>, HostError> {
        if !self.has_labels {
            return Err(HostError::input(
                path,
                "has no labels (a `label` column or labels.npy); labelled rows are needed here",
            ));
        }
        if let Some(loc) = self.first_missing_label {
            return Err(HostError::Input(format!(
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

/// What in-memory rows are named in messages.
const ROWS: &str = "rows";

impl RowSource for Loaded {
    fn path(&self) -> &Path {
        Path::new(ROWS)
    }

    fn classes(&self) -> &[String] {
        &self.classes
    }

    fn has_labels(&self) -> bool {
        self.has_labels
    }

    fn for_each_row<E, F>(&self, mut f: F) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>) -> Result<(), E>,
    {
        let k = self.classes.len();
        let n = self.labels.len();
        let length = |what, found: usize, expected: usize| {
            DataError::new(
                ROWS,
                DataErrorKind::Length {
                    what,
                    expected: expected as u64,
                    found: found as u64,
                },
            )
        };
        if k == 0 {
            return Err(DataError::new(ROWS, DataErrorKind::ClassCount { found: 0 }).into());
        }
        if self.logits.len() != n.saturating_mul(k) {
            let expected = n.saturating_mul(k);
            return Err(length("logits (rows x classes)", self.logits.len(), expected).into());
        }
        if self.objectness.len() != n {
            return Err(length("objectness (one per row)", self.objectness.len(), n).into());
        }
        let rows = self
            .labels
            .iter()
            .zip(&self.objectness)
            .zip(self.logits.chunks_exact(k));
        for (i, ((&label, &objectness), logits)) in rows.enumerate() {
            let location = self
                .locations
                .get(i)
                .copied()
                .unwrap_or(Location::Row(i as u64));
            let bad = |kind| DataError::new(ROWS, kind).at(location);
            if let Label::Class(c) = label {
                if c >= k {
                    let kind = DataErrorKind::LabelIndex {
                        value: c as i128,
                        classes: k,
                    };
                    return Err(bad(kind).in_column("label").into());
                }
            }
            for (j, &x) in logits.iter().enumerate() {
                if let Err(kind) = super::dataset::check_logit(x, || x.to_string()) {
                    let column = self.classes.get(j).cloned().unwrap_or_default();
                    return Err(bad(kind).in_column(column).into());
                }
            }
            if !(0.0..=1.0).contains(&objectness) {
                let kind = DataErrorKind::ObjectnessRange {
                    text: objectness.to_string(),
                };
                return Err(bad(kind).in_column("objectness").into());
            }
            let (index, line) = match location {
                Location::Line(l) => (i as u64, Some(l)),
                Location::Row(r) => (r, None),
            };
            f(Row {
                index,
                line,
                id: None,
                label,
                objectness,
                logits,
            })?;
        }
        Ok(())
    }
}

/// Refuses data whose classes differ from the table's (names and order).
///
/// # Errors
///
/// [`HostError::Input`] naming `path` and both class lists (the first few names of a
/// long list, and how many more it has).
pub fn check_classes<'a>(
    path: &Path,
    data: &[String],
    table: impl Iterator<Item = &'a str>,
) -> Result<(), HostError> {
    let table: Vec<&str> = table.collect();
    if data.len() == table.len() && data.iter().zip(&table).all(|(a, b)| a == b) {
        return Ok(());
    }
    let list = |names: &mut dyn Iterator<Item = &str>, n: usize| {
        let shown: Vec<String> = names.take(SHOWN_CLASSES).map(echo).collect();
        let more = n.saturating_sub(SHOWN_CLASSES);
        if more == 0 {
            shown.join(", ")
        } else {
            format!("{}, ... and {more} more", shown.join(", "))
        }
    };
    Err(HostError::input(
        path,
        format!(
            "its classes [{}] differ from the table's [{}] (same names, same order needed)",
            list(&mut data.iter().map(String::as_str), data.len()),
            list(&mut table.iter().copied(), table.len()),
        ),
    ))
}

/// How many class names a message about two class lists shows of each.
const SHOWN_CLASSES: usize = 8;

/// Training rows followed by rows taken as `background` whatever their label: the rows of
/// `fit --background FILE` (DESIGN §1.8, "Learning unknown from data"), e.g. logged false
/// positives or objects of classes the detector must not report. They enter only the
/// Bayes head's `background` category (and so the open head's `q`); the ML and MAP heads
/// never see background rows.
#[derive(Debug)]
pub struct WithBackground<'s, S> {
    train: &'s S,
    background: &'s [DataSource],
}

impl<'s, S: RowSource> WithBackground<'s, S> {
    /// `train` followed by every row of each of `background`, in order.
    ///
    /// # Errors
    ///
    /// [`HostError::Input`] naming the background file whose classes differ from the
    /// training data's (names and order).
    pub fn new(train: &'s S, background: &'s [DataSource]) -> Result<Self, HostError> {
        for b in background {
            check_classes(
                b.path(),
                b.classes(),
                train.classes().iter().map(String::as_str),
            )?;
        }
        Ok(Self { train, background })
    }
}

impl<S: RowSource> RowSource for WithBackground<'_, S> {
    fn path(&self) -> &Path {
        self.train.path()
    }

    fn classes(&self) -> &[String] {
        self.train.classes()
    }

    fn has_labels(&self) -> bool {
        self.train.has_labels()
    }

    fn for_each_row<E, F>(&self, mut f: F) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>) -> Result<(), E>,
    {
        self.train.for_each_row(&mut f)?;
        for b in self.background {
            b.for_each_row(|row| {
                f(Row {
                    label: Label::Background,
                    ..row
                })
            })?;
        }
        Ok(())
    }
}

/// Opens the `--background` files of a command that reads them more than once (as
/// [`open_twice`]).
///
/// # Errors
///
/// As [`open_twice`], for the first file that cannot be opened.
pub fn open_background(paths: &[std::path::PathBuf]) -> Result<Vec<DataSource>, HostError> {
    paths.iter().map(|p| open_twice(p)).collect()
}
