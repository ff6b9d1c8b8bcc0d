//! Reading the data files of DESIGN §2: a CSV file or an NPY directory, streamed.
//!
//! [`DataSource::open`] reads only the header (CSV) or the array headers (NPY) and
//! checks them; [`DataSource::for_each_row`] then streams the rows through a closure,
//! with memory that does not grow with the row count. It can be called again for a
//! second pass (fitting needs two); every pass reopens the files.
//!
//! # CSV
//!
//! A header row; a column `label` (a class name, `background`, or empty when unknown);
//! optionally `objectness` (default 1.0 when the column is absent) and `id` (carried as
//! text); every other column is the logit of the class it names, in order. Fields are
//! trimmed of surrounding whitespace; lines end with LF or CRLF; blank lines are
//! skipped. A field that starts with a quote ends with one (quotes inside are
//! doubled); a record is at most [`MAX_RECORD_BYTES`] long. A file that is not a
//! regular file (a pipe) is read once: its rows go to the first pass.
//!
//! # NPY directory
//!
//! `logits.npy` (N x K, float32 or float64, C order); optionally `labels.npy` (N
//! integers of any integer dtype, `-1` = background), `objectness.npy` (N floats) and
//! `classes.txt` (K names, one a line; default `class0` .. `class{K-1}`).
//!
//! # What is refused
//!
//! Everything DESIGN §2 calls malformed, as a [`DataError`] naming the file, the line
//! (CSV) or row index (NPY) and the column: missing or extra fields, text in a number,
//! a label that is not a class, a NaN or infinite logit (or one beyond the range of
//! `f32`), an objectness that is NaN or
//! outside `[0, 1]`, an empty field where a number is needed, fewer than 2 classes or
//! more than [`MAX_CLASSES`], a quoted field without its closing quote, text after a
//! closing quote, a record longer than [`MAX_RECORD_BYTES`],
//! repeated column names, a class named `background` or longer than
//! [`NAME_MAX`](mlmap_core::NAME_MAX) bytes, empty, missing or unreadable files, and NPY
//! arrays whose dtype, order, shape or size do not fit.

mod csv_file;
mod error;
mod npy_dir;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub use error::{DataError, DataErrorKind, Location};

/// The longest CSV record, in bytes (a line, or the lines of a record whose quoted
/// fields hold line breaks): a longer one is refused while it is read, so memory stays
/// bounded whatever the file (DESIGN §2).
pub const MAX_RECORD_BYTES: usize = 1 << 20;

/// The most classes an input may have (DESIGN §2): the columns of a CSV file or of
/// `logits.npy`.
pub const MAX_CLASSES: usize = 4096;

/// How many characters of a field an error message repeats.
const ECHO_CHARS: usize = 48;

/// `text` for an error message, its non-printable characters escaped: whole when short,
/// else its first characters and its length (a field can be up to [`MAX_RECORD_BYTES`] long).
pub(crate) fn echo(text: &str) -> String {
    // Shown through `visible`: no control character reaches the terminal raw.
    match text.char_indices().nth(ECHO_CHARS) {
        None => crate::escape::visible(text).into_owned(),
        Some((end, _)) => format!(
            "{}... ({} bytes)",
            crate::escape::visible(text.get(..end).unwrap_or_default()),
            text.len()
        ),
    }
}

/// Checks a logit read as `f64`: finite, and finite in the layer's `f32` too
/// (DESIGN §6.16). `text` gives the value as written, for the error.
pub(crate) fn check_logit(v: f64, text: impl FnOnce() -> String) -> Result<f64, DataErrorKind> {
    if !v.is_finite() {
        Err(DataErrorKind::NotFinite { text: text() })
    } else if !(v as f32).is_finite() {
        Err(DataErrorKind::OutOfF32 { text: text() })
    } else {
        Ok(v)
    }
}

/// The label of a row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Label {
    /// A true object of the class with this index.
    Class(usize),
    /// No object (a false positive of the detector).
    Background,
    /// Unknown: no label column, or an empty label.
    Missing,
}

/// One row of a data source, borrowed for the duration of the callback.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row<'a> {
    /// 0-based index of the data row (the header is not counted).
    pub index: u64,
    /// The 1-based line the record starts on, for CSV files (the header is line 1).
    pub line: Option<u64>,
    /// The `id` field, when the CSV file has that column.
    pub id: Option<&'a str>,
    /// The label.
    pub label: Label,
    /// The objectness, in `[0, 1]` (1.0 when the source has none).
    pub objectness: f64,
    /// The K class logits, all finite, in class order.
    pub logits: &'a [f64],
}

impl Row<'_> {
    /// Where the row is, for error messages: its CSV line or NPY row index.
    pub fn location(&self) -> Location {
        match self.line {
            Some(l) => Location::Line(l),
            None => Location::Row(self.index),
        }
    }
}

/// Rows to fit or score from: a data file ([`DataSource`]) or rows held in memory
/// ([`Loaded`](crate::data::Loaded)).
///
/// The fit ([`fit`](crate::fit::fit()), [`class_moments`](crate::fit::class_moments),
/// [`TrainingSet::read`](crate::fit::TrainingSet::read)) works on any source.
pub trait RowSource {
    /// What error messages name: the file, or `rows` for rows held in memory.
    fn path(&self) -> &Path;

    /// The class names, in column order.
    fn classes(&self) -> &[String];

    /// `true` when the rows carry labels.
    fn has_labels(&self) -> bool;

    /// Streams every row, in order, through `f`; stops at the first error, of the data
    /// or of `f`. Can be called again (a fit makes two passes).
    ///
    /// # Errors
    ///
    /// The first [`DataError`] of a row (converted into `E`), or the first error `f`
    /// returns.
    fn for_each_row<E, F>(&self, f: F) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>) -> Result<(), E>;
}

impl RowSource for DataSource {
    fn path(&self) -> &Path {
        DataSource::path(self)
    }

    fn classes(&self) -> &[String] {
        DataSource::classes(self)
    }

    fn has_labels(&self) -> bool {
        DataSource::has_labels(self)
    }

    fn for_each_row<E, F>(&self, f: F) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>) -> Result<(), E>,
    {
        DataSource::for_each_row(self, f)
    }
}

/// A checked data file (CSV) or directory (NPY), ready to be streamed.
#[derive(Debug, Clone)]
pub struct DataSource {
    path: PathBuf,
    classes: Vec<String>,
    format: Format,
}

#[derive(Debug, Clone)]
enum Format {
    Csv(csv_file::Schema),
    Npy(npy_dir::Schema),
}

impl DataSource {
    /// Opens `path`: an NPY directory if it is a directory, a CSV file otherwise. Only
    /// headers are read.
    ///
    /// # Errors
    ///
    /// A [`DataError`] when the path does not exist or cannot be read, or when a header
    /// breaks a rule of DESIGN §2 (see the [module docs](self)).
    pub fn open(path: &Path) -> Result<Self, DataError> {
        Self::open_with(path, false, None)
    }

    /// As [`DataSource::open`], with `column` declared not a class: a CSV column of
    /// that name is neither a logit nor a class, and
    /// [`for_each_row_with_column`](Self::for_each_row_with_column) gives its text
    /// (`eval --group-by`, DESIGN §4). An NPY directory has no such column.
    ///
    /// # Errors
    ///
    /// As [`DataSource::open`].
    pub fn open_with_column(path: &Path, column: &str) -> Result<Self, DataError> {
        Self::open_with(path, false, Some(column))
    }

    /// As [`DataSource::open`], for quantized logits (`mlmap apply --quantized`): an
    /// NPY directory's `logits.npy` must be `int8` or `int16` (a CSV file's logits are
    /// read as numbers, whose integrality the caller checks). Rows give the codes as
    /// exact `f64` values.
    ///
    /// # Errors
    ///
    /// As [`DataSource::open`].
    pub fn open_codes(path: &Path) -> Result<Self, DataError> {
        Self::open_with(path, true, None)
    }

    fn open_with(path: &Path, codes: bool, column: Option<&str>) -> Result<Self, DataError> {
        let (classes, format) = if path.is_dir() {
            let (classes, schema) = npy_dir::Schema::open_with(path, codes)?;
            (classes, Format::Npy(schema))
        } else if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("npy"))
        {
            return Err(DataError::new(path, DataErrorKind::NpyFileNotDirectory));
        } else {
            let (classes, schema) = csv_file::Schema::open(path, column)?;
            (classes, Format::Csv(schema))
        };
        Ok(Self {
            path: path.to_path_buf(),
            classes,
            format,
        })
    }

    /// The path given to [`DataSource::open`].
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The class names, in column order (K of them, K >= 2).
    pub fn classes(&self) -> &[String] {
        &self.classes
    }

    /// `true` when the rows carry labels (a CSV `label` column or `labels.npy`).
    pub fn has_labels(&self) -> bool {
        match &self.format {
            Format::Csv(s) => s.has_labels(),
            Format::Npy(s) => s.has_labels(),
        }
    }

    /// `true` when the rows carry an `id` (CSV files with an `id` column).
    pub fn has_ids(&self) -> bool {
        match &self.format {
            Format::Csv(s) => s.has_ids(),
            Format::Npy(_) => false,
        }
    }

    /// `true` when the file has the column declared by
    /// [`DataSource::open_with_column`].
    pub fn has_column(&self) -> bool {
        match &self.format {
            Format::Csv(s) => s.has_extra(),
            Format::Npy(_) => false,
        }
    }

    /// `true` when the rows carry an objectness (otherwise every row has 1.0).
    pub fn has_objectness(&self) -> bool {
        match &self.format {
            Format::Csv(s) => s.has_objectness(),
            Format::Npy(s) => s.has_objectness(),
        }
    }

    /// `true` when [`DataSource::for_each_row`] can be called more than once: the input
    /// is a regular file or an NPY directory. A pipe, a FIFO or a device is read once
    /// (DESIGN §2); a second pass fails with [`DataErrorKind::ReadOnce`].
    pub fn rereadable(&self) -> bool {
        match &self.format {
            Format::Csv(s) => s.rereadable(),
            Format::Npy(_) => true,
        }
    }

    /// The number of rows when it is known without reading them (NPY directories).
    pub fn row_count_hint(&self) -> Option<u64> {
        match &self.format {
            Format::Csv(_) => None,
            Format::Npy(s) => Some(s.rows()),
        }
    }

    /// Streams every row, in order, through `f`; stops at the first error, of the data
    /// or of `f`.
    ///
    /// Memory use does not depend on the number of rows. Each call reads the input
    /// again from the start; an input that can be read only once (see
    /// [`DataSource::rereadable`]) gives its rows to the first call.
    ///
    /// # Errors
    ///
    /// The first [`DataError`] of a row (converted into `E`), or the first error `f`
    /// returns.
    pub fn for_each_row<E, F>(&self, f: F) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>) -> Result<(), E>,
    {
        match &self.format {
            Format::Csv(s) => s.for_each_row(&self.path, &self.classes, f),
            Format::Npy(s) => s.for_each_row(&self.classes, f),
        }
    }
}

impl DataSource {
    /// As [`DataSource::for_each_row`], with the text of the column declared by
    /// [`DataSource::open_with_column`] (trimmed; `None` when the file does not have
    /// it).
    ///
    /// # Errors
    ///
    /// As [`DataSource::for_each_row`].
    pub fn for_each_row_with_column<E, F>(&self, mut f: F) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>, Option<&str>) -> Result<(), E>,
    {
        match &self.format {
            Format::Csv(s) => s.for_each_row_with_column(&self.path, &self.classes, f),
            Format::Npy(s) => s.for_each_row(&self.classes, |row| f(row, None)),
        }
    }
}

/// The names of `k` columns that have none of their own: `class0` .. `class{k-1}` (an NPY
/// directory without `classes.txt`, numpy arrays without `classes`).
pub fn default_class_names(k: usize) -> Vec<String> {
    (0..k).map(|i| format!("class{i}")).collect()
}

/// Checks a list of class names against the rule of DESIGN §2 and §6.15: between 2 and
/// 65535 names, each passing [`check_class_name`](mlmap_core::check_class_name), none twice.
/// `error` builds the error for name `i` (`usize::MAX` when no single name is at
/// fault). Returns the name-to-index map.
///
/// # Errors
///
/// The error `error` builds for the first name at fault, of the kind
/// [`DataErrorKind::of_name`] gives.
pub fn check_class_names<E>(
    names: &[String],
    error: impl Fn(usize, DataErrorKind) -> E,
) -> Result<HashMap<String, usize>, E> {
    if names.len() < 2 || names.len() > MAX_CLASSES {
        return Err(error(
            usize::MAX,
            DataErrorKind::ClassCount { found: names.len() },
        ));
    }
    let mut index: HashMap<String, usize> = HashMap::with_capacity(names.len());
    for (i, name) in names.iter().enumerate() {
        mlmap_core::check_class_name(name)
            .map_err(|e| error(i, DataErrorKind::of_name(i, name, e)))?;
        if let Some(&first) = index.get(name) {
            let first = u16::try_from(first).unwrap_or(u16::MAX);
            let repeated = mlmap_core::NameError::Repeated { first };
            return Err(error(i, DataErrorKind::of_name(i, name, repeated)));
        }
        index.insert(name.clone(), i);
    }
    Ok(index)
}
