//! Reading the arrays of an opened directory: each array's elements chunk by chunk
//! ([`Column`]), and the rows of a pass ([`Columns`] into a [`Chunk`]).

use std::fs::File;
use std::io::{self, BufReader, Read};

use super::{open_npy, Array, Elem};
use crate::dataset::{DataError, DataErrorKind, Location};

/// Values read from each array at once (per array, at most this many elements): bulk
/// reads keep the cost per row at a few instructions and the memory bounded.
pub(super) const CHUNK_VALUES: usize = 1 << 14;

/// The message of an array that ends before the row count of its header.
const ENDED_EARLY: &str = "the file ended early (it changed after it was opened)";

/// Decodes every complete element of `raw` with `from`, appending to `out`.
#[inline(always)]
fn decode<const N: usize, T>(raw: &[u8], out: &mut Vec<T>, from: impl Fn([u8; N]) -> T) {
    let (elements, _) = raw.as_chunks::<N>();
    out.extend(elements.iter().map(|&b| from(b)));
}

/// The elements of one array, read chunk by chunk from the first data byte on.
pub(super) struct Column<'a> {
    pub(super) array: &'a Array,
    reader: BufReader<File>,
    raw: Vec<u8>,
    /// The read error that stopped the last fill short, if any.
    error: Option<io::Error>,
}

impl<'a> Column<'a> {
    pub(super) fn open(array: &'a Array) -> Result<Self, DataError> {
        let (_, reader) = open_npy(&array.path)?;
        Ok(Self {
            array,
            reader,
            raw: Vec::new(),
            error: None,
        })
    }

    /// Reads the bytes of up to `n` more elements; returns the bytes of the complete
    /// ones. Stops short at the end of the file or at a read error (kept for
    /// [`Column::missing`]).
    fn read(&mut self, n: usize) -> &[u8] {
        let size = self.array.elem.size();
        let want = n.saturating_mul(size);
        if self.raw.len() < want {
            self.raw.resize(want, 0);
        }
        let mut filled = 0;
        while filled < want {
            let Some(dst) = self.raw.get_mut(filled..want) else {
                break;
            };
            match self.reader.read(dst) {
                Ok(0) => break,
                Ok(got) => filled += got,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => {
                    self.error = Some(e);
                    break;
                }
            }
        }
        let complete = filled - filled % size;
        self.raw.get(..complete).unwrap_or(&[])
    }

    /// Reads up to `n` more elements of a float array into `out` (replacing its
    /// contents); fewer only at the end of the file or at a read error.
    fn floats(&mut self, n: usize, out: &mut Vec<f64>) {
        out.clear();
        let (elem, big) = (self.array.elem, self.array.big_endian);
        let raw = self.read(n);
        match (elem, big) {
            (Elem::F32, false) => decode(raw, out, |b| f64::from(f32::from_le_bytes(b))),
            (Elem::F32, true) => decode(raw, out, |b| f64::from(f32::from_be_bytes(b))),
            // Quantized logits (`DataSource::open_codes`): exact in f64.
            (Elem::I8, _) => decode(raw, out, |b: [u8; 1]| f64::from(b[0] as i8)),
            (Elem::I16, false) => decode(raw, out, |b| f64::from(i16::from_le_bytes(b))),
            (Elem::I16, true) => decode(raw, out, |b| f64::from(i16::from_be_bytes(b))),
            (_, false) => decode(raw, out, f64::from_le_bytes),
            (_, true) => decode(raw, out, f64::from_be_bytes),
        }
    }

    /// Reads up to `n` more elements of an integer array into `out`, as
    /// [`floats`](Self::floats). `u64` values above `i64::MAX` (never a valid label)
    /// become `i64::MAX`; [`Column::exact_int`] gives their value.
    fn ints(&mut self, n: usize, out: &mut Vec<i64>) {
        out.clear();
        let (elem, big) = (self.array.elem, self.array.big_endian);
        let raw = self.read(n);
        macro_rules! ints {
            ($t:ty) => {
                if big {
                    decode(raw, out, |b| i64::from(<$t>::from_be_bytes(b)))
                } else {
                    decode(raw, out, |b| i64::from(<$t>::from_le_bytes(b)))
                }
            };
        }
        let wide = |v: u64| i64::try_from(v).unwrap_or(i64::MAX);
        match elem {
            Elem::I8 => ints!(i8),
            Elem::I16 => ints!(i16),
            Elem::I32 => ints!(i32),
            Elem::I64 => ints!(i64),
            Elem::U8 => ints!(u8),
            Elem::U16 => ints!(u16),
            Elem::U32 => ints!(u32),
            Elem::U64 | Elem::F32 | Elem::F64 if big => {
                decode(raw, out, |b| wide(u64::from_be_bytes(b)));
            }
            Elem::U64 | Elem::F32 | Elem::F64 => decode(raw, out, |b| wide(u64::from_le_bytes(b))),
        }
    }

    /// Element `i` of the last chunk read by [`Column::ints`], exactly.
    pub(super) fn exact_int(&self, i: usize) -> Option<i128> {
        let size = self.array.elem.size();
        let b = self.raw.get(i * size..(i + 1) * size)?;
        let big = self.array.big_endian;
        macro_rules! int {
            ($t:ty) => {{
                let b = b.as_chunks().0.first().copied()?;
                i128::from(if big {
                    <$t>::from_be_bytes(b)
                } else {
                    <$t>::from_le_bytes(b)
                })
            }};
        }
        Some(match self.array.elem {
            Elem::I8 => int!(i8),
            Elem::I16 => int!(i16),
            Elem::I32 => int!(i32),
            Elem::I64 => int!(i64),
            Elem::U8 => int!(u8),
            Elem::U16 => int!(u16),
            Elem::U32 => int!(u32),
            Elem::U64 | Elem::F32 | Elem::F64 => int!(u64),
        })
    }

    /// The error for an element of row `row` that could not be read.
    pub(super) fn missing(&mut self, row: u64) -> DataError {
        let path = &self.array.path;
        match self.error.take() {
            Some(e) => DataError::io(path, &e),
            None => DataError::new(
                path,
                DataErrorKind::Io {
                    reason: ENDED_EARLY.into(),
                },
            ),
        }
        .at(Location::Row(row))
    }
}

/// The open arrays of a pass.
pub(super) struct Columns<'a> {
    pub(super) logits: Column<'a>,
    pub(super) labels: Option<Column<'a>>,
    pub(super) objectness: Option<Column<'a>>,
}

impl Columns<'_> {
    /// Reads the next `n` rows of every array into `chunk` (fewer where an array ends
    /// early or fails).
    pub(super) fn read(&mut self, n: usize, k: usize, chunk: &mut Chunk) {
        self.logits.floats(n * k, &mut chunk.xs);
        chunk.ls.clear();
        if let Some(c) = &mut self.labels {
            c.ints(n, &mut chunk.ls);
        }
        chunk.objs.clear();
        if let Some(c) = &mut self.objectness {
            c.floats(n, &mut chunk.objs);
        }
    }
}

/// A chunk of rows: logits (row-major), labels and objectness as read.
#[derive(Default)]
pub(super) struct Chunk {
    pub(super) xs: Vec<f64>,
    pub(super) ls: Vec<i64>,
    pub(super) objs: Vec<f64>,
}

impl Chunk {
    /// `true` when all `n` rows are complete and every field is valid (checked a
    /// column at a time, which the compiler vectorises).
    pub(super) fn is_valid(&self, n: usize, k: usize, cols: &Columns<'_>) -> bool {
        let classes = i64::try_from(k).unwrap_or(i64::MAX);
        let complete = self.xs.len() == n * k
            && (cols.labels.is_none() || self.ls.len() == n)
            && (cols.objectness.is_none() || self.objs.len() == n);
        // Branch-free integer accumulators, so that each scan vectorises.
        let bad_logits = self
            .xs
            .iter()
            .fold(0u8, |bad, &v| bad | u8::from(!(v as f32).is_finite()));
        let bad_labels = self.ls.iter().fold(0u8, |bad, &v| {
            bad | u8::from(v < -1) | u8::from(v >= classes)
        });
        let bad_objectness = self.objs.iter().fold(0u8, |bad, &v| {
            bad | u8::from(!(v >= 0.0)) | u8::from(!(v <= 1.0))
        });
        complete && (bad_logits | bad_labels | bad_objectness) == 0
    }
}
