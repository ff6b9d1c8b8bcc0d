//! NPY directory input (DESIGN §2), through the `npyz` crate.
//!
//! The headers are parsed by `npyz`; the data is read in chunks of rows (at most
//! `CHUNK_VALUES` elements per array at once) and decoded here, so memory does not grow
//! with N and the cost per row is a few instructions. File sizes are checked against the
//! headers when the directory is opened, so a truncated array is reported before any row
//! is produced.

use std::fs::File;
use std::io::{self, BufReader, Seek};
use std::path::{Path, PathBuf};

use npyz::{DType, Endianness, NpyHeader, Order, TypeChar};

use super::{check_class_names, DataError, DataErrorKind, Label, Location, Row};

mod read;

use read::{Chunk, Column, Columns, CHUNK_VALUES};

/// Read buffer of each array: it holds the header; the data is read in chunks larger
/// than it, which bypass it.
const BUFFER: usize = 1 << 12;

/// Element types this module reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Elem {
    F32,
    F64,
    I8,
    I16,
    I32,
    I64,
    U8,
    U16,
    U32,
    U64,
}

impl Elem {
    /// Bytes per element.
    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::F32 | Self::I32 | Self::U32 => 4,
            Self::F64 | Self::I64 | Self::U64 => 8,
        }
    }
}

/// A checked array: its file, element type and byte order.
#[derive(Debug, Clone)]
struct Array {
    path: PathBuf,
    elem: Elem,
    big_endian: bool,
}

/// What the directory holds, read from the array headers.
#[derive(Debug, Clone)]
pub(super) struct Schema {
    rows: u64,
    k: usize,
    logits: Array,
    labels: Option<Array>,
    objectness: Option<Array>,
}

const FLOATS: &str = "float32 or float64";
const INTEGERS: &str = "an integer type";

/// Maps an error of the NPY header parser: format errors are the file's fault.
fn header_error(path: &Path, e: &io::Error) -> DataError {
    match e.kind() {
        io::ErrorKind::InvalidData | io::ErrorKind::UnexpectedEof => DataError::new(
            path,
            DataErrorKind::NpyFormat {
                reason: e.to_string(),
            },
        ),
        _ => DataError::io(path, e),
    }
}

/// Opens `path` and parses its NPY header; the reader is left on the first data byte.
fn open_npy(path: &Path) -> Result<(NpyHeader, BufReader<File>), DataError> {
    let file = File::open(path).map_err(|e| DataError::open(path, &e))?;
    let is_file = file
        .metadata()
        .map_err(|e| DataError::io(path, &e))?
        .is_file();
    if !is_file {
        let reason = "not a regular file".to_string();
        return Err(DataError::new(path, DataErrorKind::Unreadable { reason }));
    }
    let mut reader = BufReader::with_capacity(BUFFER, file);
    let header = NpyHeader::from_reader(&mut reader).map_err(|e| header_error(path, &e))?;
    Ok((header, reader))
}

fn elem_of(dtype: &DType, floats: bool) -> Option<Elem> {
    let DType::Plain(ts) = dtype else {
        return None;
    };
    match (ts.type_char(), ts.size_field(), floats) {
        (TypeChar::Float, 4, true) => Some(Elem::F32),
        (TypeChar::Float, 8, true) => Some(Elem::F64),
        (TypeChar::Int, 1, false) => Some(Elem::I8),
        (TypeChar::Int, 2, false) => Some(Elem::I16),
        (TypeChar::Int, 4, false) => Some(Elem::I32),
        (TypeChar::Int, 8, false) => Some(Elem::I64),
        (TypeChar::Uint, 1, false) => Some(Elem::U8),
        (TypeChar::Uint, 2, false) => Some(Elem::U16),
        (TypeChar::Uint, 4, false) => Some(Elem::U32),
        (TypeChar::Uint, 8, false) => Some(Elem::U64),
        _ => None,
    }
}

/// Opens `path`, checks dtype, order, dimensions and file size; returns the array and
/// its shape.
fn check_array(
    path: &Path,
    floats: bool,
    ndim: usize,
    expected_shape: &'static str,
) -> Result<(Array, Vec<u64>), DataError> {
    let bad = |kind| DataError::new(path, kind);
    let (npy, mut reader) = open_npy(path)?;
    let dtype = npy.dtype();
    let elem = elem_of(&dtype, floats).ok_or_else(|| {
        let found = match &dtype {
            DType::Plain(ts) => ts.to_string(),
            other => other.descr(),
        };
        bad(DataErrorKind::NpyDtype {
            found,
            expected: if floats { FLOATS } else { INTEGERS },
        })
    })?;
    if npy.order() == Order::Fortran {
        return Err(bad(DataErrorKind::NpyFortranOrder));
    }
    let shape = npy.shape().to_vec();
    if shape.len() != ndim {
        return Err(bad(DataErrorKind::NpyShape {
            found: shape,
            expected: expected_shape,
        }));
    }
    // Size check: the data after the header must be exactly what the header announces.
    let item = dtype.num_bytes().and_then(|n| u64::try_from(n).ok());
    let expected = shape
        .iter()
        .try_fold(item.unwrap_or(u64::MAX), |acc, &d| acc.checked_mul(d));
    let header_len = reader
        .stream_position()
        .map_err(|e| DataError::io(path, &e))?;
    let file_len = reader
        .get_ref()
        .metadata()
        .map_err(|e| DataError::io(path, &e))?
        .len();
    let found = file_len.saturating_sub(header_len);
    let Some(expected) = expected else {
        return Err(bad(DataErrorKind::NpyTooLarge { shape }));
    };
    if expected != found {
        return Err(bad(DataErrorKind::NpySize { expected, found }));
    }
    let big_endian = match &dtype {
        DType::Plain(ts) => ts.endianness() == Endianness::Big,
        _ => false,
    };
    Ok((
        Array {
            path: path.to_path_buf(),
            elem,
            big_endian,
        },
        shape,
    ))
}

/// Checks an optional per-row array of `rows` elements, if its file exists.
fn optional_column(
    dir: &Path,
    name: &str,
    floats: bool,
    rows: u64,
) -> Result<Option<Array>, DataError> {
    let path = dir.join(name);
    if !path.exists() {
        return Ok(None);
    }
    let (array, shape) = check_array(&path, floats, 1, "(N,): one value per row")?;
    let found = shape.first().copied().unwrap_or(0);
    if found != rows {
        return Err(DataError::new(
            &path,
            DataErrorKind::RowCount {
                expected: rows,
                found,
            },
        ));
    }
    Ok(Some(array))
}

/// The class names from `classes.txt`, or `class0..class{K-1}` without it.
fn class_names(dir: &Path, k: usize) -> Result<Vec<String>, DataError> {
    let path = dir.join("classes.txt");
    if !path.exists() {
        return Ok(super::default_class_names(k));
    }
    let bytes = std::fs::read(&path).map_err(|e| DataError::open(&path, &e))?;
    let text =
        String::from_utf8(bytes).map_err(|_| DataError::new(&path, DataErrorKind::NotUtf8))?;
    // A byte-order mark is not part of the first name (as in CSV files).
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let mut names: Vec<String> = text.lines().map(|l| l.trim().to_string()).collect();
    while names.last().is_some_and(String::is_empty) {
        names.pop();
    }
    if names.len() != k {
        return Err(DataError::new(
            &path,
            DataErrorKind::ClassListLength {
                expected: k,
                found: names.len(),
            },
        ));
    }
    check_class_names(&names, |i, kind| {
        let e = DataError::new(&path, kind);
        match u64::try_from(i) {
            Ok(i) if i < u64::MAX => e.at(Location::Line(i + 1)),
            _ => e,
        }
    })?;
    Ok(names)
}

impl Schema {
    /// Reads and checks every array header and `classes.txt`; returns the class names
    /// and the schema. With `codes`, the logits are quantized: an `int8` or `int16` array instead of a
    /// float one.
    pub(super) fn open_with(dir: &Path, codes: bool) -> Result<(Vec<String>, Self), DataError> {
        let logits_path = dir.join("logits.npy");
        const CODES: &str = "int8 or int16 (quantized logits)";
        let (logits, shape) = check_array(&logits_path, !codes, 2, "(N, K): N rows of K logits")
            .map_err(|e| match e.kind() {
                DataErrorKind::NpyDtype { found, .. } if codes => DataError::new(
                    &logits_path,
                    DataErrorKind::NpyDtype {
                        found: found.clone(),
                        expected: CODES,
                    },
                ),
                _ => e,
            })?;
        if codes && !matches!(logits.elem, Elem::I8 | Elem::I16) {
            return Err(DataError::new(
                &logits_path,
                DataErrorKind::NpyDtype {
                    found: format!("{:?}", logits.elem).to_lowercase(),
                    expected: CODES,
                },
            ));
        }
        let (rows, k) = match shape.as_slice() {
            [n, k] => (*n, usize::try_from(*k).unwrap_or(usize::MAX)),
            _ => (0, 0),
        };
        if !(2..=super::MAX_CLASSES).contains(&k) {
            return Err(DataError::new(
                &logits_path,
                DataErrorKind::ClassCount { found: k },
            ));
        }
        let labels = optional_column(dir, "labels.npy", false, rows)?;
        let objectness = optional_column(dir, "objectness.npy", true, rows)?;
        let names = class_names(dir, k)?;
        Ok((
            names,
            Self {
                rows,
                k,
                logits,
                labels,
                objectness,
            },
        ))
    }

    pub(super) fn rows(&self) -> u64 {
        self.rows
    }

    pub(super) fn has_labels(&self) -> bool {
        self.labels.is_some()
    }

    pub(super) fn has_objectness(&self) -> bool {
        self.objectness.is_some()
    }

    pub(super) fn for_each_row<E, F>(&self, classes: &[String], mut f: F) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>) -> Result<(), E>,
    {
        let k = self.k;
        let mut cols = Columns {
            logits: Column::open(&self.logits)?,
            labels: self.labels.as_ref().map(Column::open).transpose()?,
            objectness: self.objectness.as_ref().map(Column::open).transpose()?,
        };
        let rows_per_chunk = (CHUNK_VALUES / k).max(1);
        let mut chunk = Chunk::default();
        let mut start = 0u64;
        while start < self.rows {
            let n = usize::try_from(self.rows - start)
                .map_or(rows_per_chunk, |left| left.min(rows_per_chunk));
            cols.read(n, k, &mut chunk);
            if chunk.is_valid(n, k, &cols) {
                // Every field is present and valid: no check per row.
                for (i, (index, logits)) in (start..).zip(chunk.xs.chunks_exact(k)).enumerate() {
                    let label = match (&cols.labels, chunk.ls.get(i)) {
                        (Some(_), Some(&v)) => {
                            usize::try_from(v).map_or(Label::Background, Label::Class)
                        }
                        _ => Label::Missing,
                    };
                    let objectness = chunk.objs.get(i).copied().unwrap_or(1.0);
                    f(Row {
                        index,
                        line: None,
                        id: None,
                        label,
                        objectness,
                        logits,
                    })?;
                }
            } else {
                // Field by field, in file order: the rows before the first problem are
                // produced, then the problem is the error.
                for (i, index) in (start..start + n as u64).enumerate() {
                    let (label, objectness) =
                        self.checked_row(classes, &mut cols, &chunk, i, index)?;
                    f(Row {
                        index,
                        line: None,
                        id: None,
                        label,
                        objectness,
                        logits: chunk.xs.get(i * k..(i + 1) * k).unwrap_or(&[]),
                    })?;
                }
            }
            start += n as u64;
        }
        Ok(())
    }

    /// Checks row `i` of `chunk` (row `index` of the arrays) field by field: its logits
    /// in column order, then its label, then its objectness. Returns the label and the
    /// objectness, or the first problem.
    fn checked_row(
        &self,
        classes: &[String],
        cols: &mut Columns<'_>,
        chunk: &Chunk,
        i: usize,
        index: u64,
    ) -> Result<(Label, f64), DataError> {
        let k = self.k;
        let at = |path: &Path, kind| DataError::new(path, kind).at(Location::Row(index));
        for c in 0..k {
            let Some(&v) = chunk.xs.get(i * k + c) else {
                return Err(cols.logits.missing(index));
            };
            if let Err(kind) = super::check_logit(v, || format!("{v}")) {
                let e = at(&self.logits.path, kind);
                return Err(e.in_column(classes.get(c).map_or("", String::as_str)));
            }
        }
        let label = match &mut cols.labels {
            Some(col) => match chunk.ls.get(i) {
                None => return Err(col.missing(index)),
                Some(-1) => Label::Background,
                Some(&v) => match usize::try_from(v) {
                    Ok(class) if class < k => Label::Class(class),
                    _ => {
                        let value = col.exact_int(i).unwrap_or(i128::from(v));
                        let kind = DataErrorKind::LabelIndex { value, classes: k };
                        return Err(at(&col.array.path, kind));
                    }
                },
            },
            None => Label::Missing,
        };
        let objectness = match &mut cols.objectness {
            Some(col) => match chunk.objs.get(i) {
                None => return Err(col.missing(index)),
                Some(&v) if (0.0..=1.0).contains(&v) => v,
                Some(&v) => {
                    let text = format!("{v}");
                    return Err(at(&col.array.path, DataErrorKind::ObjectnessRange { text }));
                }
            },
            None => 1.0,
        };
        Ok((label, objectness))
    }
}
