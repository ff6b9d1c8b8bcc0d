//! [`DataError`]: what went wrong in an input file, and where.

use std::fmt;
use std::path::{Path, PathBuf};

use mlmap_core::NameError;

/// Where in a file an error was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Location {
    /// A CSV line, 1-based; the header is line 1.
    Line(u64),
    /// A row of an NPY array, by its 0-based index (numpy's `a[i]`).
    Row(u64),
}

/// What is wrong with an input (the `kind` of a [`DataError`]).
///
/// Every kind but [`DataErrorKind::Io`] is the input's fault (the CLI exits with 2);
/// see [`DataErrorKind::is_bad_input`].
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum DataErrorKind {
    /// The file or directory does not exist.
    NotFound,
    /// The file exists but cannot be opened (permissions, a directory where a file is
    /// expected, ...).
    Unreadable {
        /// The operating system's explanation.
        reason: String,
    },
    /// Reading failed after the file was opened (a device error, not a format error).
    Io {
        /// The operating system's explanation.
        reason: String,
    },
    /// A `.npy` file was given where an NPY input directory is expected.
    NpyFileNotDirectory,
    /// The text is not valid UTF-8.
    NotUtf8,
    /// The file has no header row (it is empty or blank).
    Empty,
    /// A header field is empty.
    EmptyColumnName {
        /// 1-based position of the column in the header.
        index: usize,
    },
    /// A column name appears twice in the header (or a class name twice in `classes.txt`).
    DuplicateColumn,
    /// A class is named `background`, the label of rows without an object.
    ReservedClassName,
    /// A class name is longer than [`NAME_MAX`](mlmap_core::NAME_MAX) bytes.
    ClassNameTooLong {
        /// Length of the name in bytes.
        len: usize,
    },
    /// A class name holds a character that is not printable, or starts or ends with a
    /// space (DESIGN §6.15).
    BadClassName {
        /// The rule it breaks ([`NameError::Char`] or [`NameError::Padded`]).
        error: NameError,
    },
    /// There are fewer than 2 (or more than [`MAX_CLASSES`](super::MAX_CLASSES)) class
    /// columns.
    ClassCount {
        /// Number of class columns found.
        found: usize,
    },
    /// A record has another number of fields than the header.
    FieldCount {
        /// Fields in the header.
        expected: usize,
        /// Fields in the record.
        found: usize,
    },
    /// A field that must hold a number is empty.
    MissingValue,
    /// A field is not a number.
    NotANumber {
        /// The field as written.
        text: String,
    },
    /// A logit is NaN or infinite.
    NotFinite {
        /// The value as written (CSV) or printed (NPY).
        text: String,
    },
    /// A logit is finite but beyond the range of `f32` (above `f32::MAX` in magnitude),
    /// so the layer would see an infinity.
    OutOfF32 {
        /// The value as written (CSV) or printed (NPY).
        text: String,
    },
    /// A CSV file ends inside a quoted field (its closing quote is missing).
    UnterminatedQuote,
    /// A quoted CSV field has text after its closing quote (`"1"2`).
    TextAfterQuote,
    /// A CSV record is longer than [`MAX_RECORD_BYTES`](super::MAX_RECORD_BYTES).
    RecordTooLong {
        /// The limit, in bytes.
        limit: usize,
    },
    /// A second pass over an input that can be read only once (a pipe, a FIFO).
    ReadOnce,
    /// An objectness is NaN or outside `[0, 1]`.
    ObjectnessRange {
        /// The value as written (CSV) or printed (NPY).
        text: String,
    },
    /// A CSV label is neither a class name, `background`, nor empty.
    UnknownLabel {
        /// The label as written.
        text: String,
    },
    /// An NPY label is neither a class index nor `-1`.
    LabelIndex {
        /// The label value.
        value: i128,
        /// Number of classes K (valid indices are `0..K`).
        classes: usize,
    },
    /// The file is not an NPY file, or its header cannot be parsed.
    NpyFormat {
        /// What the NPY reader reported.
        reason: String,
    },
    /// The NPY array has an element type this input cannot hold.
    NpyDtype {
        /// The dtype as numpy writes it (e.g. `<i4`).
        found: String,
        /// What is accepted.
        expected: &'static str,
    },
    /// The NPY array is stored in Fortran (column-major) order.
    NpyFortranOrder,
    /// The NPY array does not have the expected number of dimensions.
    NpyShape {
        /// The shape in the file.
        found: Vec<u64>,
        /// What is accepted.
        expected: &'static str,
    },
    /// The NPY array's size in bytes (its shape times its element size) does not fit in
    /// 64 bits.
    NpyTooLarge {
        /// The shape in the file.
        shape: Vec<u64>,
    },
    /// The NPY file holds more or fewer data bytes than its header announces.
    NpySize {
        /// Data bytes the header announces.
        expected: u64,
        /// Data bytes in the file.
        found: u64,
    },
    /// An NPY array has another number of rows than `logits.npy`.
    RowCount {
        /// Rows of `logits.npy`.
        expected: u64,
        /// Rows of this array.
        found: u64,
    },
    /// Rows held in memory: a field has another number of values than the rows need.
    Length {
        /// The field (`logits`, `objectness`).
        what: &'static str,
        /// Values needed (rows, or rows times classes).
        expected: u64,
        /// Values given.
        found: u64,
    },
    /// `classes.txt` lists another number of names than `logits.npy` has columns.
    ClassListLength {
        /// Columns of `logits.npy`.
        expected: usize,
        /// Names in `classes.txt`.
        found: usize,
    },
}

impl DataErrorKind {
    /// The kind of error of class name `name` (the `i`-th, 0-based) that breaks the
    /// rule `error` of [`check_class_name`](mlmap_core::check_class_name).
    pub fn of_name(i: usize, name: &str, error: NameError) -> Self {
        match error {
            NameError::Empty => Self::EmptyColumnName { index: i + 1 },
            NameError::TooLong => Self::ClassNameTooLong { len: name.len() },
            NameError::Reserved => Self::ReservedClassName,
            NameError::Repeated { .. } => Self::DuplicateColumn,
            NameError::Char { .. } | NameError::Padded => Self::BadClassName { error },
        }
    }

    /// `true` when the input is at fault (exit code 2), `false` for a failure of the
    /// machine while reading a valid file (exit code 1). A missing or unreadable input
    /// file is the caller's fault.
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, Self::Io { .. })
    }
}

impl fmt::Display for DataErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotFound => f.write_str("no such file or directory"),
            Self::Unreadable { reason } => write!(f, "cannot be opened: {reason}"),
            Self::Io { reason } => write!(f, "read failed: {reason}"),
            Self::NpyFileNotDirectory => f.write_str(
                "an NPY input is a directory holding logits.npy (and optionally labels.npy, \
                 objectness.npy, classes.txt), not a single .npy file",
            ),
            Self::NotUtf8 => f.write_str("the text is not valid UTF-8"),
            Self::Empty => f.write_str("the file is empty (no header row)"),
            Self::EmptyColumnName { index } => write!(f, "column {index} has an empty name"),
            Self::DuplicateColumn => f.write_str("the name appears more than once"),
            Self::ReservedClassName => f.write_str(
                "a class cannot be named \"background\" (the label of rows without an object)",
            ),
            Self::ClassNameTooLong { len } => write!(
                f,
                "the class name is {len} bytes long; a table holds at most {} bytes",
                mlmap_core::NAME_MAX
            ),
            Self::BadClassName { error } => write!(f, "not a valid class name: {error}"),
            Self::ClassCount { found } => write!(
                f,
                "found {found} class column(s); between 2 and {} are needed",
                super::MAX_CLASSES
            ),
            Self::FieldCount { expected, found } => {
                write!(
                    f,
                    "expected {expected} fields (as the header), found {found}"
                )
            }
            Self::MissingValue => f.write_str("the field is empty"),
            Self::NotANumber { text } => write!(f, "{text:?} is not a number"),
            Self::NotFinite { text } => write!(f, "{text:?} is not a finite number"),
            Self::OutOfF32 { text } => write!(
                f,
                "{text:?} is out of range: a logit must be finite as a 32-bit float \
                 (magnitude at most {:e})",
                f32::MAX
            ),
            Self::UnterminatedQuote => {
                f.write_str("a quoted field has no closing quote before the end of the file")
            }
            Self::TextAfterQuote => f.write_str(
                "text follows the closing quote of a field; quote the whole field and \
                 double the quotes inside it",
            ),
            Self::RecordTooLong { limit } => write!(
                f,
                "the record is longer than {limit} bytes, the limit of a CSV record"
            ),
            Self::ReadOnce => f.write_str(
                "is not a regular file (a pipe or a FIFO): it can be read only once, and \
                 this needs a second pass; save it to a file first",
            ),
            Self::ObjectnessRange { text } => {
                write!(f, "objectness {text:?} is not a number in [0, 1]")
            }
            Self::UnknownLabel { text } => {
                write!(f, "{text:?} is not a class name, \"background\" or empty")
            }
            Self::LabelIndex { value, classes } => write!(
                f,
                "label {value} is not a class index (0 to {}) or -1 (background)",
                classes.saturating_sub(1)
            ),
            Self::NpyFormat { reason } => write!(f, "not a valid NPY file: {reason}"),
            Self::NpyDtype { found, expected } => {
                write!(f, "dtype {found:?} is not supported; expected {expected}")
            }
            Self::NpyFortranOrder => f.write_str(
                "the array is in Fortran order; save a C-ordered array \
                 (numpy.ascontiguousarray)",
            ),
            Self::NpyShape { found, expected } => {
                write!(f, "shape {found:?} is not {expected}")
            }
            Self::NpyTooLarge { shape } => write!(
                f,
                "shape {shape:?} is too large: its size in bytes does not fit in 64 bits"
            ),
            Self::NpySize { expected, found } => write!(
                f,
                "holds {found} data bytes but its header announces {expected} \
                 (truncated or padded file)"
            ),
            Self::RowCount { expected, found } => {
                write!(f, "has {found} rows but logits.npy has {expected}")
            }
            Self::Length {
                what,
                expected,
                found,
            } => write!(f, "{what} holds {found} values; {expected} are needed"),
            Self::ClassListLength { expected, found } => write!(
                f,
                "lists {found} class names but logits.npy has {expected} columns"
            ),
        }
    }
}

/// An input file that cannot be read, with the file, the position and the column.
///
/// Displays as `PATH:LINE: column "NAME": WHAT` for CSV files
/// (e.g. `examples/data/x.csv:17: column "cyclist": "abc" is not a number`) and as
/// `PATH: row index I: column "NAME": WHAT` for NPY arrays; parts that do not apply are
/// left out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DataError(std::boxed::Box<Inner>);

#[derive(Debug, Clone, PartialEq, Eq)]
struct Inner {
    path: PathBuf,
    location: Option<Location>,
    column: Option<String>,
    kind: DataErrorKind,
}

impl DataError {
    /// An error of `kind` in the file `path`, with no position yet.
    pub fn new(path: impl Into<PathBuf>, kind: DataErrorKind) -> Self {
        Self(std::boxed::Box::new(Inner {
            path: path.into(),
            location: None,
            column: None,
            kind,
        }))
    }

    /// The same error at `location`.
    #[must_use]
    pub fn at(mut self, location: Location) -> Self {
        self.0.location = Some(location);
        self
    }

    /// The same error in the column named `column`.
    #[must_use]
    pub fn in_column(mut self, column: impl Into<String>) -> Self {
        self.0.column = Some(super::echo(&column.into()));
        self
    }

    /// The file (for NPY inputs, the file inside the directory) the error is in.
    pub fn path(&self) -> &Path {
        &self.0.path
    }

    /// Where in the file, when the error concerns one line or row.
    pub fn location(&self) -> Option<Location> {
        self.0.location
    }

    /// The CSV line (1-based, header = 1), when the error concerns one line.
    pub fn line(&self) -> Option<u64> {
        match self.0.location {
            Some(Location::Line(l)) => Some(l),
            _ => None,
        }
    }

    /// The column name, when the error concerns one column.
    pub fn column(&self) -> Option<&str> {
        self.0.column.as_deref()
    }

    /// What is wrong.
    pub fn kind(&self) -> &DataErrorKind {
        &self.0.kind
    }

    /// `true` when the input is at fault (exit code 2), `false` for an I/O failure
    /// (exit code 1). See [`DataErrorKind::is_bad_input`].
    pub fn is_bad_input(&self) -> bool {
        self.0.kind.is_bad_input()
    }

    /// Maps an error of opening `path` to [`DataErrorKind::NotFound`] or
    /// [`DataErrorKind::Unreadable`].
    pub(crate) fn open(path: &Path, e: &std::io::Error) -> Self {
        let kind = if e.kind() == std::io::ErrorKind::NotFound {
            DataErrorKind::NotFound
        } else {
            DataErrorKind::Unreadable {
                reason: e.to_string(),
            }
        };
        Self::new(path, kind)
    }

    /// Maps an error while reading `path` to [`DataErrorKind::Io`].
    pub(crate) fn io(path: &Path, e: &std::io::Error) -> Self {
        Self::new(
            path,
            DataErrorKind::Io {
                reason: e.to_string(),
            },
        )
    }
}

impl fmt::Display for DataError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0.path.display())?;
        match self.0.location {
            Some(Location::Line(l)) => write!(f, ":{l}: ")?,
            Some(Location::Row(r)) => write!(f, ": row index {r}: ")?,
            None => f.write_str(": ")?,
        }
        if let Some(c) = &self.0.column {
            write!(f, "column {c:?}: ")?;
        }
        write!(f, "{}", self.0.kind)
    }
}

impl std::error::Error for DataError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_names_file_line_and_column() {
        let e = DataError::new(
            "examples/data/x.csv",
            DataErrorKind::NotANumber { text: "abc".into() },
        )
        .at(Location::Line(17))
        .in_column("cyclist");
        assert_eq!(
            e.to_string(),
            r#"examples/data/x.csv:17: column "cyclist": "abc" is not a number"#
        );
        assert_eq!(e.line(), Some(17));
        assert_eq!(e.column(), Some("cyclist"));
        assert!(e.is_bad_input());
    }

    #[test]
    fn display_of_npy_rows_and_plain_errors() {
        let e = DataError::new(
            "d/labels.npy",
            DataErrorKind::LabelIndex {
                value: 7,
                classes: 3,
            },
        )
        .at(Location::Row(4));
        assert_eq!(
            e.to_string(),
            "d/labels.npy: row index 4: label 7 is not a class index (0 to 2) or -1 (background)"
        );
        assert_eq!(e.line(), None);
        let e = DataError::new("a.csv", DataErrorKind::Empty);
        assert_eq!(e.to_string(), "a.csv: the file is empty (no header row)");
    }

    #[test]
    fn only_io_failures_are_not_bad_input() {
        assert!(!DataErrorKind::Io { reason: "x".into() }.is_bad_input());
        assert!(DataErrorKind::NotFound.is_bad_input());
        assert!(DataErrorKind::Unreadable { reason: "x".into() }.is_bad_input());
    }
}
