//! `Table<K, B_ML, B_MAP>`: a validated, fixed-size table and the layer's entry points.

use crate::error::{BatchError, DecodeError, EncodeError, Head, InferError, TableError};
use crate::gaussian::Gaussian;
use crate::histogram::Histogram;
use crate::layer::{self, Scores};
use crate::math::{Backend, Libm};
use crate::name::ClassName;
use crate::wire::{self, ClassSpec, ClassWire, Settings};

/// A fitted ML/MAP table for `K` classes, `B_ML` bins in the ML head's histograms and
/// `B_MAP` bins in the MAP head's.
///
/// Every `Table` satisfies the table invariants of DESIGN §1.3 (5): it can only be
/// obtained from [`Table::from_bytes`], [`Table::from_parts`] or the build-time
/// constant, all of which validate. Its size is fixed at compile time; it never
/// allocates.
///
/// # Examples
///
/// ```
/// use mlmap::{ClassSpec, EdgeMode, Settings, Table, UpperTail};
///
/// let class = |name, mean| ClassSpec {
///     name,
///     rows: 100,
///     mean,
///     variance: 1.0,
///     ml_range: (mean - 2.0, mean + 2.0),
///     ml_freqs: [0.25; 4],
///     map_range: (mean - 2.0, mean + 2.0),
///     map_freqs: [0.5; 2],
/// };
/// let settings = Settings {
///     lambda_ml: 0.0055,
///     lambda_map: 0.00012,
///     edge_mode: EdgeMode::Linspace,
///     upper_tail: UpperTail::Zero,
/// };
/// let table: Table<2, 4, 2> = Table::from_parts(settings, [class("car", 3.0), class("cyclist", 1.0)])?;
///
/// let scores = table.ml(&[3.5, -9.0], 0.9)?;
/// assert_eq!(scores.argmax(), 0);
/// assert!((scores.0.iter().sum::<f32>() - 0.9).abs() < 1e-6);
///
/// // Never seen in training, in any class: "I don't know", OS / K each.
/// assert_eq!(table.map(&[50.0, -50.0], 0.9)?.0, [0.45, 0.45]);
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Table<const K: usize, const B_ML: usize, const B_MAP: usize> {
    pub(crate) names: [ClassName; K],
    pub(crate) rows: [u64; K],
    pub(crate) priors: [Gaussian; K],
    pub(crate) ml: [Histogram<[f32; B_ML]>; K],
    pub(crate) map: [Histogram<[f32; B_MAP]>; K],
    pub(crate) settings: Settings,
}

impl<const K: usize, const B_ML: usize, const B_MAP: usize> Table<K, B_ML, B_MAP> {
    /// Largest number of bytes [`Table::to_slice`] writes for this shape; size a static
    /// buffer with it.
    pub const MAX_ENCODED_LEN: usize = wire::max_encoded_len(K, B_ML, B_MAP);

    const SHAPE_OK: () = assert!(
        K >= 2
            && K <= u16::MAX as usize
            && B_ML >= 1
            && B_ML <= u16::MAX as usize
            && B_MAP >= 1
            && B_MAP <= u16::MAX as usize,
        "a Table needs 2..=65535 classes and 1..=65535 bins per head"
    );

    /// `(K, B_ML, B_MAP)` as stored in a table header.
    const SHAPE: (u16, u16, u16) = (K as u16, B_ML as u16, B_MAP as u16);

    /// Builds a table from fitted statistics, checking every invariant.
    ///
    /// # Errors
    ///
    /// The first broken invariant, as a [`TableError`].
    ///
    /// # Panics
    ///
    /// Never (a bad shape is a compile-time error).
    pub fn from_parts(
        settings: Settings,
        classes: [ClassSpec<'_, [f32; B_ML], [f32; B_MAP]>; K],
    ) -> Result<Self, TableError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::SHAPE_OK;
        settings.validate()?;
        let mut table = Self::placeholder(settings);
        for (i, spec) in classes.into_iter().enumerate() {
            table.set_class(i, spec.validate(i, B_ML, B_MAP)?);
        }
        wire::check_unique_names(&table.names)?;
        Ok(table)
    }

    /// Decodes and validates a table written by `mlmap fit` or [`Table::to_slice`].
    ///
    /// Checks, in order: the magic, the CRC-32, the format version, the shape against
    /// `K`, `B_ML`, `B_MAP`, the body's syntax, and every table invariant. Allocates
    /// nothing; the bytes are not borrowed past the call.
    ///
    /// # Examples
    ///
    /// ```
    /// // The table shipped with the crate (the default of the build-time embedding).
    /// let bytes = include_bytes!("../tables/default.mlmap");
    /// let table = mlmap::Table::<3, 22, 17>::from_bytes(bytes)?;
    /// assert_eq!(table.class_name(0), Some("car"));
    /// # Ok::<(), mlmap::DecodeError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// * [`DecodeError::NotATable`]: no `MLMP` magic.
    /// * [`DecodeError::Truncated`]: too short to hold a table.
    /// * [`DecodeError::Corrupted`]: CRC-32 mismatch.
    /// * [`DecodeError::UnsupportedVersion`]: another format version.
    /// * [`DecodeError::ShapeMismatch`]: another `K` or bin count.
    /// * [`DecodeError::Malformed`]: the body does not parse, bytes are left over, or a
    ///   length is not written in its shortest form (so that every table has exactly one
    ///   encoding, the one [`Table::to_slice`] writes).
    /// * [`DecodeError::Invalid`]: an invariant does not hold.
    ///
    /// # Panics
    ///
    /// Never, whatever the bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, DecodeError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::SHAPE_OK;
        let (header, body) = wire::open(bytes)?;
        if header.shape() != Self::SHAPE {
            return Err(DecodeError::ShapeMismatch {
                expected: Self::SHAPE,
                found: header.shape(),
            });
        }
        type Freqs<const B: usize> = heapless::Vec<f32, B>;
        type Classes<'a, const K: usize, const M: usize, const P: usize> =
            heapless::Vec<ClassWire<'a, Freqs<M>, Freqs<P>>, K>;
        let (settings, classes) = wire::parse_body::<Classes<'_, K, B_ML, B_MAP>>(body)?;
        if classes.len() != K {
            return Err(DecodeError::Malformed);
        }
        let mut table = Self::placeholder(settings);
        for (i, c) in classes.into_iter().enumerate() {
            let c = c.into_spec();
            let class = u16::try_from(i).unwrap_or(u16::MAX);
            let bins = |head| TableError::BinCount { head, class };
            let spec = ClassSpec {
                name: c.name,
                rows: c.rows,
                mean: c.mean,
                variance: c.variance,
                ml_range: c.ml_range,
                ml_freqs: to_array(&c.ml_freqs).ok_or(bins(Head::Ml))?,
                map_range: c.map_range,
                map_freqs: to_array(&c.map_freqs).ok_or(bins(Head::Map))?,
            };
            table.set_class(i, spec.validate(i, B_ML, B_MAP)?);
        }
        wire::check_unique_names(&table.names)?;
        wire::check_canonical(bytes.len(), Self::SHAPE, &table.settings, |i| table.spec(i))?;
        Ok(table)
    }

    /// Encodes the table into `buf` and returns the written prefix.
    ///
    /// The output is deterministic: equal tables give equal bytes, and
    /// [`Table::from_bytes`] of them gives back an equal table.
    ///
    /// # Errors
    ///
    /// [`EncodeError::BufferTooSmall`] when `buf` is too small;
    /// [`Table::MAX_ENCODED_LEN`] bytes always suffice.
    ///
    /// # Panics
    ///
    /// Never.
    pub fn to_slice<'b>(&self, buf: &'b mut [u8]) -> Result<&'b mut [u8], EncodeError> {
        wire::encode(Self::SHAPE, &self.settings, |i| self.spec(i), buf)
    }

    /// The statistics of class `i`, as slices.
    pub fn spec(&self, i: usize) -> Option<ClassSpec<'_, &[f32], &[f32]>> {
        let (ml, map, prior) = (self.ml.get(i)?, self.map.get(i)?, self.priors.get(i)?);
        Some(ClassSpec {
            name: self.names.get(i)?.as_str(),
            rows: *self.rows.get(i)?,
            mean: prior.mean,
            variance: prior.var,
            ml_range: (ml.lo, ml.hi),
            ml_freqs: &ml.freqs,
            map_range: (map.lo, map.hi),
            map_freqs: &map.freqs,
        })
    }

    /// A table of the right shape whose classes are all overwritten before it escapes.
    fn placeholder(settings: Settings) -> Self {
        const fn hist<const B: usize>() -> Histogram<[f32; B]> {
            Histogram {
                lo: 0.0,
                hi: 1.0,
                width: 1.0,
                inv_width: 1.0,
                freqs: [0.0; B],
            }
        }
        let prior = Gaussian {
            mean: 0.0,
            var: 1.0,
            neg_half_inv_var: -0.5,
            norm: 1.0,
        };
        Self {
            names: [ClassName {
                len: 0,
                bytes: [0; crate::name::NAME_MAX],
            }; K],
            rows: [0; K],
            priors: [prior; K],
            ml: [hist::<B_ML>(); K],
            map: [hist::<B_MAP>(); K],
            settings,
        }
    }

    fn set_class(&mut self, i: usize, c: wire::ValidClass<[f32; B_ML], [f32; B_MAP]>) {
        if let (Some(n), Some(r), Some(p), Some(ml), Some(map)) = (
            self.names.get_mut(i),
            self.rows.get_mut(i),
            self.priors.get_mut(i),
            self.ml.get_mut(i),
            self.map.get_mut(i),
        ) {
            *n = c.name;
            *r = c.rows;
            *p = c.prior;
            *ml = c.ml;
            *map = c.map;
        }
    }

    /// ML scores of one detection: `OS * (L_i + lambda) / sum_j (L_j + lambda)`.
    ///
    /// # Errors
    ///
    /// [`InferError::NanLogit`] for a NaN logit, [`InferError::Objectness`] for an
    /// objectness that is NaN or outside `[0, 1]`. `±inf` logits are valid (no
    /// likelihood, or the last bin above the support under [`UpperTail::Clamp`](crate::UpperTail::Clamp)).
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn ml(&self, logits: &[f32; K], objectness: f32) -> Result<Scores<K>, InferError> {
        let mut out = [0.0; K];
        let mut scratch = [0.0; K];
        layer::ml_into(
            &self.ml,
            self.settings.lambda_ml,
            self.settings.upper_tail,
            logits,
            objectness,
            &mut out,
            &mut scratch,
        )?;
        Ok(Scores(out))
    }

    /// MAP scores of one detection with the default [`Libm`] backend:
    /// `OS * (L_i P_i + lambda) / sum_j (L_j P_j + lambda)`.
    ///
    /// # Errors
    ///
    /// As [`Table::ml`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn map(&self, logits: &[f32; K], objectness: f32) -> Result<Scores<K>, InferError> {
        self.map_with::<Libm>(logits, objectness)
    }

    /// MAP scores of one detection with the maths backend `M` (for example `FastMath`).
    ///
    /// # Errors
    ///
    /// As [`Table::ml`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn map_with<M: Backend>(
        &self,
        logits: &[f32; K],
        objectness: f32,
    ) -> Result<Scores<K>, InferError> {
        let mut out = [0.0; K];
        let mut scratch = [0.0; K];
        layer::map_into::<_, M>(
            &self.map,
            &self.priors,
            self.settings.lambda_map,
            self.settings.upper_tail,
            logits,
            objectness,
            &mut out,
            &mut scratch,
        )?;
        Ok(Scores(out))
    }

    /// ML scores of a batch: row `r` of `logits` and `objectness` (1.0 for every row when
    /// `None`) into row `r` of `out`.
    ///
    /// # Errors
    ///
    /// [`BatchError::LengthMismatch`] (nothing written) when the slices differ in length;
    /// [`BatchError::Row`] for the first invalid row: the rows before it are written,
    /// the others untouched, so the caller may resume at `index + 1`.
    ///
    /// # Panics
    ///
    /// Never.
    pub fn ml_batch(
        &self,
        logits: &[[f32; K]],
        objectness: Option<&[f32]>,
        out: &mut [[f32; K]],
    ) -> Result<(), BatchError> {
        batch(logits, objectness, out, |x, os| self.ml(x, os))
    }

    /// MAP scores of a batch with the default [`Libm`] backend; see [`Table::ml_batch`].
    ///
    /// # Errors
    ///
    /// As [`Table::ml_batch`].
    ///
    /// # Panics
    ///
    /// Never.
    pub fn map_batch(
        &self,
        logits: &[[f32; K]],
        objectness: Option<&[f32]>,
        out: &mut [[f32; K]],
    ) -> Result<(), BatchError> {
        self.map_batch_with::<Libm>(logits, objectness, out)
    }

    /// MAP scores of a batch with the backend `M`; see [`Table::ml_batch`].
    ///
    /// # Errors
    ///
    /// As [`Table::ml_batch`].
    ///
    /// # Panics
    ///
    /// Never.
    pub fn map_batch_with<M: Backend>(
        &self,
        logits: &[[f32; K]],
        objectness: Option<&[f32]>,
        out: &mut [[f32; K]],
    ) -> Result<(), BatchError> {
        batch(logits, objectness, out, |x, os| self.map_with::<M>(x, os))
    }

    /// Name of class `i`.
    pub fn class_name(&self, i: usize) -> Option<&str> {
        self.names.get(i).map(ClassName::as_str)
    }

    /// Index of the class called `name`.
    pub fn class_index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n.as_str() == name)
    }

    /// Hyper-parameters and policies.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Number of training rows class `i` was fitted from.
    pub fn rows(&self, i: usize) -> Option<u64> {
        self.rows.get(i).copied()
    }

    /// The ML head's histogram of class `i`.
    pub fn ml_histogram(&self, i: usize) -> Option<&Histogram<[f32; B_ML]>> {
        self.ml.get(i)
    }

    /// The MAP head's histogram of class `i`.
    pub fn map_histogram(&self, i: usize) -> Option<&Histogram<[f32; B_MAP]>> {
        self.map.get(i)
    }

    /// The Gaussian prior of class `i`.
    pub fn prior(&self, i: usize) -> Option<&Gaussian> {
        self.priors.get(i)
    }
}

/// The `B` values of `v`, or `None` if it holds another number.
fn to_array<const B: usize>(v: &heapless::Vec<f32, B>) -> Option<[f32; B]> {
    if v.len() != B {
        return None;
    }
    let mut a = [0.0; B];
    for (d, s) in a.iter_mut().zip(v.iter()) {
        *d = *s;
    }
    Some(a)
}

/// Runs `score` over every row.
fn batch<const K: usize>(
    logits: &[[f32; K]],
    objectness: Option<&[f32]>,
    out: &mut [[f32; K]],
    score: impl Fn(&[f32; K], f32) -> Result<Scores<K>, InferError>,
) -> Result<(), BatchError> {
    if logits.len() != out.len() || objectness.is_some_and(|o| o.len() != logits.len()) {
        return Err(BatchError::LengthMismatch);
    }
    for (index, (x, o)) in logits.iter().zip(out.iter_mut()).enumerate() {
        let os = match objectness {
            Some(os) => os.get(index).copied().unwrap_or(f32::NAN),
            None => 1.0,
        };
        *o = score(x, os)
            .map_err(|error| BatchError::Row { index, error })?
            .0;
    }
    Ok(())
}
