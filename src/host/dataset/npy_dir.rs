//! NPY directory input (DESIGN §2), through the `npyz` crate.
//!
//! Arrays are read element by element from buffered files, so memory does not grow
//! with N. File sizes are checked against the headers when the directory is opened,
//! so a truncated array is reported before any row is produced.

use std::boxed::Box;
use std::fs::File;
use std::io::{self, BufReader, Seek};
use std::path::{Path, PathBuf};
use std::string::{String, ToString};
use std::vec::Vec;

use npyz::{DType, NpyFile, NpyHeader, Order, TypeChar};

use super::{check_class_names, DataError, DataErrorKind, Label, Location, Row};

/// Read buffer of each array.
const BUFFER: usize = 1 << 16;

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

/// A checked array: its file and element type.
#[derive(Debug, Clone)]
struct Array {
    path: PathBuf,
    elem: Elem,
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

type Stream<T> = Box<dyn Iterator<Item = io::Result<T>>>;

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
    if expected != Some(found) {
        return Err(bad(DataErrorKind::NpySize {
            expected: expected.unwrap_or(u64::MAX),
            found,
        }));
    }
    Ok((
        Array {
            path: path.to_path_buf(),
            elem,
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
        return Ok((0..k).map(|i| std::format!("class{i}")).collect());
    }
    let bytes = std::fs::read(&path).map_err(|e| DataError::open(&path, &e))?;
    let text =
        String::from_utf8(bytes).map_err(|_| DataError::new(&path, DataErrorKind::NotUtf8))?;
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

fn float_stream(a: &Array) -> Result<Stream<f64>, DataError> {
    let (header, reader) = open_npy(&a.path)?;
    let npy = NpyFile::with_header(header, reader);
    let dtype_error = |_| {
        DataError::new(
            &a.path,
            DataErrorKind::Io {
                reason: "the array's dtype changed while it was read".into(),
            },
        )
    };
    Ok(match a.elem {
        Elem::F32 => Box::new(
            npy.data::<f32>()
                .map_err(dtype_error)?
                .map(|r| r.map(f64::from)),
        ),
        _ => Box::new(npy.data::<f64>().map_err(dtype_error)?),
    })
}

fn int_stream(a: &Array) -> Result<Stream<i128>, DataError> {
    fn boxed<T>(npy: NpyFile<BufReader<File>>, path: &Path) -> Result<Stream<i128>, DataError>
    where
        T: npyz::Deserialize + Into<i128> + 'static,
    {
        let reader = npy.data::<T>().map_err(|_| {
            DataError::new(
                path,
                DataErrorKind::Io {
                    reason: "the array's dtype changed while it was read".into(),
                },
            )
        })?;
        Ok(Box::new(reader.map(|r| r.map(Into::into))))
    }
    let (header, reader) = open_npy(&a.path)?;
    let npy = NpyFile::with_header(header, reader);
    match a.elem {
        Elem::I8 => boxed::<i8>(npy, &a.path),
        Elem::I16 => boxed::<i16>(npy, &a.path),
        Elem::I32 => boxed::<i32>(npy, &a.path),
        Elem::I64 => boxed::<i64>(npy, &a.path),
        Elem::U8 => boxed::<u8>(npy, &a.path),
        Elem::U16 => boxed::<u16>(npy, &a.path),
        Elem::U32 => boxed::<u32>(npy, &a.path),
        Elem::U64 | Elem::F32 | Elem::F64 => boxed::<u64>(npy, &a.path),
    }
}

/// The next element of `stream`, the element of row `row` of `path`.
fn next<T>(stream: &mut Stream<T>, path: &Path, row: u64) -> Result<T, DataError> {
    match stream.next() {
        Some(Ok(v)) => Ok(v),
        Some(Err(e)) => Err(DataError::io(path, &e).at(Location::Row(row))),
        None => Err(DataError::new(
            path,
            DataErrorKind::Io {
                reason: "the file ended early (it changed after it was opened)".into(),
            },
        )
        .at(Location::Row(row))),
    }
}

impl Schema {
    /// Reads and checks every array header and `classes.txt`; returns the class names
    /// and the schema.
    pub(super) fn open(dir: &Path) -> Result<(Vec<String>, Self), DataError> {
        let logits_path = dir.join("logits.npy");
        let (logits, shape) = check_array(&logits_path, true, 2, "(N, K): N rows of K logits")?;
        let (rows, k) = match shape.as_slice() {
            [n, k] => (*n, usize::try_from(*k).unwrap_or(usize::MAX)),
            _ => (0, 0),
        };
        if !(2..=usize::from(u16::MAX)).contains(&k) {
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
        let mut logits = float_stream(&self.logits)?;
        let mut labels = self.labels.as_ref().map(int_stream).transpose()?;
        let mut objectness = self.objectness.as_ref().map(float_stream).transpose()?;
        let mut buf = std::vec![0.0f64; self.k];
        for index in 0..self.rows {
            let at = |path: &Path, kind| DataError::new(path, kind).at(Location::Row(index));
            for (slot, name) in buf.iter_mut().zip(classes) {
                let v = next(&mut logits, &self.logits.path, index)?;
                if !v.is_finite() {
                    let text = std::format!("{v}");
                    let e = at(&self.logits.path, DataErrorKind::NotFinite { text });
                    return Err(e.in_column(name.as_str()).into());
                }
                *slot = v;
            }
            let label = match (&mut labels, &self.labels) {
                (Some(stream), Some(a)) => match next(stream, &a.path, index)? {
                    -1 => Label::Background,
                    v => match usize::try_from(v) {
                        Ok(c) if c < self.k => Label::Class(c),
                        _ => {
                            let kind = DataErrorKind::LabelIndex {
                                value: v,
                                classes: self.k,
                            };
                            return Err(at(&a.path, kind).into());
                        }
                    },
                },
                _ => Label::Missing,
            };
            let os = match (&mut objectness, &self.objectness) {
                (Some(stream), Some(a)) => {
                    let v = next(stream, &a.path, index)?;
                    if !(0.0..=1.0).contains(&v) {
                        let text = std::format!("{v}");
                        return Err(at(&a.path, DataErrorKind::ObjectnessRange { text }).into());
                    }
                    v
                }
                _ => 1.0,
            };
            f(Row {
                index,
                line: None,
                id: None,
                label,
                objectness: os,
                logits: &buf,
            })?;
        }
        Ok(())
    }
}
