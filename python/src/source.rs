//! numpy arrays as a [`RowSource`]: the rows of a fit read in place (no copy of a
//! C-ordered array), checked as the data files are (DESIGN §2), and split into row
//! ranges that threads read at the same time.

use std::ops::Range;
use std::path::{Path, PathBuf};

use mlmap::host::dataset::{DataError, DataErrorKind, Label, Location, Row, RowSource};
use mlmap::host::fit::{FitLabel, FitLogit};
use numpy::prelude::*;
use numpy::{PyArray1, PyReadonlyArray1, PyUntypedArray};
use pyo3::prelude::*;

use crate::arrays::{self, value_error, Column, Logits, Objectness, Rows};

/// Labels borrowed from an integer array of any width (or copied when strided).
#[derive(Debug, Clone, Copy)]
pub enum LabelColumn<'a> {
    I64(&'a [i64]),
    I32(&'a [i32]),
    I16(&'a [i16]),
    I8(&'a [i8]),
    U64(&'a [u64]),
    U32(&'a [u32]),
    U16(&'a [u16]),
    U8(&'a [u8]),
}

impl LabelColumn<'_> {
    /// Label `i`, exactly (`None` past the end).
    #[inline]
    fn get(&self, i: usize) -> Option<i128> {
        match self {
            Self::I64(s) => s.get(i).map(|&v| i128::from(v)),
            Self::I32(s) => s.get(i).map(|&v| i128::from(v)),
            Self::I16(s) => s.get(i).map(|&v| i128::from(v)),
            Self::I8(s) => s.get(i).map(|&v| i128::from(v)),
            Self::U64(s) => s.get(i).map(|&v| i128::from(v)),
            Self::U32(s) => s.get(i).map(|&v| i128::from(v)),
            Self::U16(s) => s.get(i).map(|&v| i128::from(v)),
            Self::U8(s) => s.get(i).map(|&v| i128::from(v)),
        }
    }
}

/// A label array held for the duration of a call.
pub enum Labels<'py> {
    I64(PyReadonlyArray1<'py, i64>),
    I32(PyReadonlyArray1<'py, i32>),
    I16(PyReadonlyArray1<'py, i16>),
    I8(PyReadonlyArray1<'py, i8>),
    U64(PyReadonlyArray1<'py, u64>),
    U32(PyReadonlyArray1<'py, u32>),
    U16(PyReadonlyArray1<'py, u16>),
    U8(PyReadonlyArray1<'py, u8>),
    /// A checked copy (a strided or byte-swapped array).
    Owned(Vec<i64>),
}

impl Labels<'_> {
    /// The labels as a column.
    pub fn column(&self) -> LabelColumn<'_> {
        match self {
            Self::I64(a) => LabelColumn::I64(a.as_slice().unwrap_or(&[])),
            Self::I32(a) => LabelColumn::I32(a.as_slice().unwrap_or(&[])),
            Self::I16(a) => LabelColumn::I16(a.as_slice().unwrap_or(&[])),
            Self::I8(a) => LabelColumn::I8(a.as_slice().unwrap_or(&[])),
            Self::U64(a) => LabelColumn::U64(a.as_slice().unwrap_or(&[])),
            Self::U32(a) => LabelColumn::U32(a.as_slice().unwrap_or(&[])),
            Self::U16(a) => LabelColumn::U16(a.as_slice().unwrap_or(&[])),
            Self::U8(a) => LabelColumn::U8(a.as_slice().unwrap_or(&[])),
            Self::Owned(v) => LabelColumn::I64(v),
        }
    }
}

/// Borrows an `(N,)` integer label array in place when it is contiguous and of a native
/// integer type; otherwise copies it (checked).
pub fn labels<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
    n: usize,
    k: usize,
) -> PyResult<Labels<'py>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        if a.ndim() == 1 && a.is_c_contiguous() && a.shape().first() == Some(&n) {
            macro_rules! borrow {
                ($($t:ty => $v:ident),*) => {$(
                    if let Ok(x) = a.cast::<PyArray1<$t>>() {
                        let x = x.try_readonly().map_err(|e| {
                            value_error(format!("{what}: cannot be read: {e}"))
                        })?;
                        return Ok(Labels::$v(x));
                    }
                )*};
            }
            borrow!(i64 => I64, i32 => I32, i16 => I16, i8 => I8,
                    u64 => U64, u32 => U32, u16 => U16, u8 => U8);
        }
    }
    // Any other layout or type: the checked conversion of `arrays::labels`.
    Ok(Labels::Owned(arrays::labels(obj, what, n, k)?))
}

/// Rows of numpy arrays: the logits, optionally labels and objectness, restricted to a
/// range of rows. Errors name the arrays by `prefix` (`logits`, `labels`,
/// `objectness`) and the row by its index in the whole array.
#[derive(Clone)]
pub struct ArraySource<'a> {
    path: PathBuf,
    labels_path: PathBuf,
    objectness_path: PathBuf,
    classes: &'a [String],
    logits: Rows<'a>,
    labels: Option<LabelColumn<'a>>,
    objectness: Column<'a>,
    range: Range<usize>,
}

impl<'a> ArraySource<'a> {
    /// Every row of the arrays.
    pub fn new(
        classes: &'a [String],
        logits: &'a Logits<'_>,
        labels: Option<&'a Labels<'_>>,
        objectness: &'a Objectness<'_>,
        prefix: &str,
    ) -> Self {
        let name = |part: &str| {
            PathBuf::from(if prefix.is_empty() {
                part.to_string()
            } else {
                format!("{prefix}.{part}")
            })
        };
        Self {
            path: name("logits"),
            labels_path: name("labels"),
            objectness_path: name("objectness"),
            classes,
            logits: logits.rows(),
            labels: labels.map(Labels::column),
            objectness: objectness.column(),
            range: 0..logits.rows,
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.range.len()
    }

    /// The same arrays, rows `range` (indices into the whole arrays) only.
    pub fn slice(&self, range: Range<usize>) -> Self {
        Self {
            range,
            ..self.clone()
        }
    }

    /// Splits the rows into `parts` ranges of nearly equal size (at least one).
    pub fn split(&self, parts: usize) -> Vec<Self> {
        let (start, n) = (self.range.start, self.range.len());
        let parts = parts.clamp(1, n.max(1));
        (0..parts)
            .map(|p| self.slice(start + p * n / parts..start + (p + 1) * n / parts))
            .collect()
    }

    fn row_error(&self, path: &Path, i: usize, kind: DataErrorKind) -> DataError {
        DataError::new(path, kind).at(Location::Row(i as u64))
    }
}

/// Rows per block of [`ArraySource::for_each_block`]: the labels and logits of a block
/// stay in the first cache levels between its checks and its use.
pub const BLOCK_ROWS: usize = 16_384;

/// What takes the blocks of [`ArraySource::for_each_block`]: the arrays' own types.
pub trait BlockSink {
    /// Why it stopped.
    type Error: From<DataError>;

    /// Takes rows `first..first + labels.len()` (indices into the whole arrays): the
    /// logits row-major, every one finite.
    fn block<T: FitLogit, L: FitLabel>(
        &mut self,
        src: &ArraySource<'_>,
        first: usize,
        logits: &[T],
        labels: &[L],
    ) -> Result<(), Self::Error>;
}

impl ArraySource<'_> {
    /// The rows in blocks of [`BLOCK_ROWS`], read in place: the fast path of the fit.
    /// Each block's logits are checked finite first; at a bad value the block is read
    /// row by row ([`RowSource::for_each_row`]), which returns the error it finds (so
    /// the messages are the same). The labels are checked by the sink (the library's
    /// `push_rows`), which may also call [`first_error`](Self::first_error). The
    /// objectness is not read: the arrays were checked when they were taken.
    ///
    /// `Ok(false)`, and nothing read, without labels.
    pub fn for_each_block<S: BlockSink>(&self, sink: &mut S) -> Result<bool, S::Error> {
        let Some(labels) = self.labels else {
            return Ok(false);
        };
        let k = self.classes.len();
        let mut start = self.range.start;
        while start < self.range.end {
            let end = self.range.end.min(start + BLOCK_ROWS);
            let values = start * k..end * k;
            let finite = match self.logits {
                Rows::F32(all) => all
                    .get(values)
                    .is_some_and(|x| x.iter().fold(true, |ok, v| ok & v.is_finite())),
                Rows::F64(all) => all
                    .get(values)
                    .is_some_and(|x| x.iter().fold(true, |ok, v| ok & v.is_finite())),
            };
            if !finite {
                return Err(self.first_error(start..end).into());
            }
            macro_rules! dispatch {
                ($($v:ident),*) => {
                    match labels {
                        $(LabelColumn::$v(l) => {
                            let l = l.get(start..end).unwrap_or(&[]);
                            match self.logits {
                                Rows::F32(x) => {
                                    sink.block(self, start, x.get(start * k..end * k).unwrap_or(&[]), l)
                                }
                                Rows::F64(x) => {
                                    sink.block(self, start, x.get(start * k..end * k).unwrap_or(&[]), l)
                                }
                            }
                        })*
                    }
                };
            }
            dispatch!(I64, I32, I16, I8, U64, U32, U16, U8)?;
            start = end;
        }
        Ok(true)
    }

    /// The first error of rows `range` as [`RowSource::for_each_row`] reports it (a
    /// generic one if it finds none: the caller saw one).
    pub fn first_error(&self, range: Range<usize>) -> DataError {
        let first = range.start;
        match self.slice(range).for_each_row(|_| Ok::<(), DataError>(())) {
            Err(e) => e,
            Ok(()) => DataError::new(
                &self.path,
                DataErrorKind::Io {
                    reason: "the arrays changed while they were read".to_string(),
                },
            )
            .at(Location::Row(first as u64)),
        }
    }
}

impl RowSource for ArraySource<'_> {
    fn path(&self) -> &Path {
        &self.path
    }

    fn classes(&self) -> &[String] {
        self.classes
    }

    fn has_labels(&self) -> bool {
        self.labels.is_some()
    }

    fn for_each_row<E, F>(&self, mut f: F) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>) -> Result<(), E>,
    {
        let k = self.classes.len();
        let mut x = vec![0f64; k];
        let classes = i128::try_from(k).unwrap_or(i128::MAX);
        for i in self.range.clone() {
            match self.logits {
                Rows::F32(all) => {
                    let src = all.get(i * k..(i + 1) * k).unwrap_or(&[]);
                    for (d, &v) in x.iter_mut().zip(src) {
                        *d = f64::from(v);
                    }
                }
                Rows::F64(all) => {
                    let src = all.get(i * k..(i + 1) * k).unwrap_or(&[]);
                    x.copy_from_slice(src);
                }
            }
            if let Some(c) = x.iter().position(|v| !v.is_finite()) {
                let text = format!("{}", x.get(c).copied().unwrap_or(f64::NAN));
                let e = self.row_error(&self.path, i, DataErrorKind::NotFinite { text });
                return Err(e
                    .in_column(self.classes.get(c).map_or("", String::as_str))
                    .into());
            }
            let label = match &self.labels {
                None => Label::Missing,
                Some(col) => match col.get(i) {
                    Some(-1) => Label::Background,
                    Some(v) if (0..classes).contains(&v) => {
                        Label::Class(usize::try_from(v).unwrap_or(0))
                    }
                    v => {
                        let kind = DataErrorKind::LabelIndex {
                            value: v.unwrap_or(i128::MIN),
                            classes: k,
                        };
                        return Err(self.row_error(&self.labels_path, i, kind).into());
                    }
                },
            };
            let objectness = self.objectness.get(i);
            if !(0.0..=1.0).contains(&objectness) {
                let text = format!("{objectness}");
                let kind = DataErrorKind::ObjectnessRange { text };
                return Err(self.row_error(&self.objectness_path, i, kind).into());
            }
            f(Row {
                index: i as u64,
                line: None,
                id: None,
                label,
                objectness,
                logits: &x,
            })?;
        }
        Ok(())
    }
}
