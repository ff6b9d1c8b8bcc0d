//! numpy arrays as a [`RowSource`]: the rows of a fit read in place (no copy of a
//! C-ordered array), checked as the data files are (DESIGN §2), and split into row
//! ranges that threads read at the same time.

use std::ops::Range;
use std::path::{Path, PathBuf};

use mlmap::host::dataset::{DataError, DataErrorKind, Label, Location, Row, RowSource};
use mlmap::host::fit::{FitLabel, FitLogit};
use pyo3::prelude::*;

use crate::arrays::{Column, LabelColumn, Labels, Logits, Objectness, Rows};

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
    /// Every row of the arrays, each holding exactly one value per row (and class).
    pub fn new(
        classes: &'a [String],
        logits: &'a Logits<'_>,
        labels: Option<&'a Labels<'_>>,
        objectness: &'a Objectness<'_>,
        prefix: &str,
    ) -> PyResult<Self> {
        let name = |part: &str| {
            PathBuf::from(if prefix.is_empty() {
                part.to_string()
            } else {
                format!("{prefix}.{part}")
            })
        };
        let n = logits.rows;
        let labels_path = name("labels");
        let what = labels_path.display().to_string();
        let rows = logits.rows()?;
        let objectness = objectness.column()?;
        if classes.len() != logits.cols || !objectness.covers(n) {
            return Err(crate::arrays::value_error(format!(
                "{}: the arrays do not have one value per row and class",
                name("logits").display()
            )));
        }
        Ok(Self {
            path: name("logits"),
            labels: labels.map(|l| l.column(n, &what)).transpose()?,
            labels_path,
            objectness_path: name("objectness"),
            classes,
            logits: rows,
            objectness,
            range: 0..n,
        })
    }

    /// The same rows, their logits named `name` in error messages (the `background`
    /// rows of a fit).
    pub fn with_logits_name(self, name: &str) -> Self {
        Self {
            path: PathBuf::from(name),
            ..self
        }
    }

    /// The error of values missing from the arrays: never, as [`ArraySource::new`]
    /// checked their lengths, but reported rather than read as empty.
    fn missing(&self, first: usize) -> DataError {
        DataError::new(
            &self.path,
            DataErrorKind::Io {
                reason: "the arrays hold fewer values than their shapes".to_string(),
            },
        )
        .at(Location::Row(first as u64))
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
            let finite = match self.logits.get(values.clone()) {
                Some(Rows::F32(x)) => x.iter().fold(true, |ok, v| ok & v.is_finite()),
                Some(Rows::F64(x)) => x.iter().fold(true, |ok, v| ok & v.is_finite()),
                None => return Err(self.missing(start).into()),
            };
            if !finite {
                return Err(self.first_error(start..end).into());
            }
            let Some(x) = self.logits.get(values) else {
                return Err(self.missing(start).into());
            };
            macro_rules! dispatch {
                ($($v:ident),*) => {
                    match labels {
                        $(LabelColumn::$v(l) => {
                            let Some(l) = l.get(start..end) else {
                                return Err(self.missing(start).into());
                            };
                            match x {
                                Rows::F32(x) => sink.block(self, start, x, l),
                                Rows::F64(x) => sink.block(self, start, x, l),
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
            match self.logits.get(i * k..(i + 1) * k) {
                Some(Rows::F32(src)) => {
                    for (d, &v) in x.iter_mut().zip(src) {
                        *d = f64::from(v);
                    }
                }
                Some(Rows::F64(src)) => {
                    for (d, &v) in x.iter_mut().zip(src) {
                        *d = v;
                    }
                }
                None => return Err(self.missing(i).into()),
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
