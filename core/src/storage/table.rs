//! `Table<K, B_ML, B_MAP, B_BAYES, C, N, F>`: the [`TableInner`] over fixed-size arrays
//! ([`ArrayStorage`]), and the layer's typed entry points. Everything else it does is
//! done by the one [`TableInner`] (accessors, decoding) and its [`TableView`] (encoding,
//! scoring).

use crate::diagnostics::error::{BatchError, DecodeError, EncodeError, InferError, TableError};
use crate::format::name::ClassName;
use crate::format::wire::{self, ClassSpec, Settings};
use crate::heads::layer::Scores;
use crate::heads::recal::{Knot, MAX_KNOTS};
use crate::math::gaussian::Gaussian;
use crate::math::histogram::{Axis, Histogram};
use crate::math::Backend;
use crate::storage::inner::{private::Sealed, InUse, Storage, TableInner};
use crate::storage::lent::StorageShape;
use crate::storage::view::{self, BayesBackend, MapBackend, OpenBackend, TableView};

/// A fitted table for `K` classes: `B_ML` bins in the ML head's histograms, `B_MAP` in
/// the MAP head's, and, when `B_BAYES > 0`, a Bayes head with `B_BAYES` bins per logit
/// and `C` categories (`K`, or `K + 1` when the training data had `background` rows).
/// `B_BAYES` and `C` default to 0: no Bayes head (every version-1 table). `N` is the room
/// for each head's recalibration map, in knots (DESIGN §1.9; 0 by default: a table with a
/// map is refused with [`DecodeError::MapCapacity`]), and `F = 1` holds the Bayes head's
/// objectness feature (DESIGN §1.6; 0 by default: such a table is refused with
/// [`DecodeError::ObjectnessMismatch`], and with `F = 1` a table without it is).
///
/// Every `Table` satisfies the table invariants of DESIGN §1.3 (5): it can only be
/// obtained from [`Table::from_bytes`], [`Table::from_parts`] or the build-time
/// constant, all of which validate. Its size is fixed at compile time; it never
/// allocates.
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
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
pub type Table<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const B_BAYES: usize = 0,
    const C: usize = 0,
    const N: usize = 0,
    const F: usize = 0,
> = TableInner<ArrayStorage<K, B_ML, B_MAP, B_BAYES, C, N, F>>;

/// The storage of a [`Table`]: arrays of the table's shape, fixed at compile time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArrayStorage<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const B_BAYES: usize,
    const C: usize,
    const N: usize,
    const F: usize,
>;

impl<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
        const N: usize,
        const F: usize,
    > Sealed for ArrayStorage<K, B_ML, B_MAP, B_BAYES, C, N, F>
{
}

impl<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
        const N: usize,
        const F: usize,
    > Storage for ArrayStorage<K, B_ML, B_MAP, B_BAYES, C, N, F>
{
    type Names = [ClassName; K];
    type Rows = [u64; K];
    type Priors = [Gaussian; K];
    type MlFreqs = [f32; B_ML];
    type MapFreqs = [f32; B_MAP];
    type Ml = [Histogram<[f32; B_ML]>; K];
    type Map = [Histogram<[f32; B_MAP]>; K];
    type Settings = Settings;
    type Axes = [Axis; K];
    type Terms = [[[f32; C]; B_BAYES]; K];
    type Categories = [u64; C];
    type LogPrior = [f32; C];
    type Knots = [Knot; N];
    type ObjectnessAxis = [Axis; F];
    type ObjectnessTerms = [[[f32; C]; B_BAYES]; F];
    type Extent = ();
    type View<'a> = TableView<'a, [f32; B_ML], [f32; B_MAP]>;

    const NAME: &'static str = "Table";
    const OBJECTNESS_REQUIRED: bool = F > 0;

    /// All of it, known at compile time.
    #[inline(always)]
    fn in_use(_: &Table<K, B_ML, B_MAP, B_BAYES, C, N, F>) -> InUse {
        InUse {
            classes: K,
            bayes: B_BAYES > 0,
            categories: C,
            terms: K * B_BAYES * C,
            objectness: F > 0,
            objectness_terms: F * B_BAYES * C,
            maps: N > 0,
        }
    }

    /// Refuses another shape than the type's.
    fn prepare(
        _: &mut Table<K, B_ML, B_MAP, B_BAYES, C, N, F>,
        _: &StorageShape,
        (shape, bayes_shape): ((u16, u16, u16), (u16, u16)),
        _: usize,
    ) -> Result<(), DecodeError> {
        if shape != Table::<K, B_ML, B_MAP, B_BAYES, C, N, F>::SHAPE {
            return Err(DecodeError::ShapeMismatch {
                expected: Table::<K, B_ML, B_MAP, B_BAYES, C, N, F>::SHAPE,
                found: shape,
            });
        }
        if bayes_shape != Table::<K, B_ML, B_MAP, B_BAYES, C, N, F>::BAYES_SHAPE {
            return Err(DecodeError::BayesShapeMismatch {
                expected: Table::<K, B_ML, B_MAP, B_BAYES, C, N, F>::BAYES_SHAPE,
                found: bayes_shape,
            });
        }
        Ok(())
    }

    fn finish(
        _: &mut Table<K, B_ML, B_MAP, B_BAYES, C, N, F>,
        _: &StorageShape,
        _: bool,
        _: [usize; 4],
    ) {
    }

    #[inline(always)]
    fn wrap<'a>(
        _: &'a Table<K, B_ML, B_MAP, B_BAYES, C, N, F>,
        view: TableView<'a, [f32; B_ML], [f32; B_MAP]>,
    ) -> TableView<'a, [f32; B_ML], [f32; B_MAP]> {
        view
    }
}

impl<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
        const N: usize,
        const F: usize,
    > Table<K, B_ML, B_MAP, B_BAYES, C, N, F>
{
    /// Largest number of bytes [`Table::to_slice`] writes for this shape; size a static
    /// buffer with it.
    pub const MAX_ENCODED_LEN: usize = wire::max_encoded_len(K, B_ML, B_MAP, B_BAYES, C, N, F);

    const SHAPE_OK: () = assert!(
        K >= 2
            && K < u16::MAX as usize
            && B_ML >= 1
            && B_ML <= u16::MAX as usize
            && B_MAP >= 1
            && B_MAP <= u16::MAX as usize
            && B_BAYES <= u16::MAX as usize
            && ((B_BAYES == 0 && C == 0) || (B_BAYES >= 1 && (C == K || C == K + 1)))
            && N <= MAX_KNOTS
            && (F == 0 || (F == 1 && B_BAYES >= 1)),
        "a Table needs 2..65535 classes, 1..=65535 bins per head, either no Bayes head \
         (B_BAYES = C = 0) or one with K or K + 1 categories, at most MAX_KNOTS knots \
         per map, and F = 0, or F = 1 (the objectness feature) with a Bayes head"
    );

    /// `(K, B_ML, B_MAP)` as stored in a table header.
    const SHAPE: (u16, u16, u16) = (K as u16, B_ML as u16, B_MAP as u16);

    /// `(B_BAYES, C)` as stored in a table header.
    const BAYES_SHAPE: (u16, u16) = (B_BAYES as u16, C as u16);

    /// Builds a table without a Bayes head from fitted statistics, checking every
    /// invariant.
    ///
    /// # Errors
    ///
    /// The first broken invariant, as a [`TableError`]; [`TableError::BayesShape`] for
    /// a table type with a Bayes head (decode such tables with [`Table::from_bytes`]).
    ///
    /// # Panics
    ///
    /// Never (a bad shape is a compile-time error).
    pub fn from_parts(
        settings: Settings,
        classes: [ClassSpec<'_, [f32; B_ML], [f32; B_MAP]>; K],
    ) -> Result<Self, TableError> {
        Self::from_parts_named(settings, classes, ClassName::checked)
    }

    /// [`from_parts`](Self::from_parts) with the names stored by `store` (the whole
    /// rule, or what an older format version holds).
    fn from_parts_named(
        settings: Settings,
        classes: [ClassSpec<'_, [f32; B_ML], [f32; B_MAP]>; K],
        store: fn(&str) -> Result<ClassName, crate::NameError>,
    ) -> Result<Self, TableError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::SHAPE_OK;
        if B_BAYES > 0 {
            return Err(TableError::BayesShape);
        }
        settings.validate()?;
        let mut table = Self::placeholder(settings);
        for (i, spec) in classes.into_iter().enumerate() {
            let c = spec.validate_with(i, B_ML, B_MAP, store)?;
            if let (Some(n), Some(r), Some(p), Some(ml), Some(map)) = (
                table.names.get_mut(i),
                table.rows.get_mut(i),
                table.priors.get_mut(i),
                table.ml.get_mut(i),
                table.map.get_mut(i),
            ) {
                (*n, *r, *p, *ml, *map) = (c.name, c.rows, c.prior, c.ml, c.map);
            }
        }
        view::check_unique_names(&table.names)?;
        Ok(table)
    }

    /// Decodes and validates a table written by `mlmap fit` or [`Table::to_slice`].
    ///
    /// Checks, in order: the magic, the CRC-32, the format version, the shape against
    /// `K`, `B_ML`, `B_MAP` (and `B_BAYES`, `C`), the body's syntax, and every table
    /// invariant. Allocates nothing; the bytes are not borrowed past the call.
    ///
    /// # Examples
    ///
    /// ```
    /// # use mlmap_core as mlmap;
    /// // The table shipped with the crate (the default of the build-time embedding).
    /// let bytes = include_bytes!("../../../tables/default.mlmap");
    /// let table = mlmap::Table::<3, 22, 17, 22, 4>::from_bytes(bytes)?;
    /// assert_eq!(table.class_name(0), Some("car"));
    /// # Ok::<(), mlmap::DecodeError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// * [`DecodeError::NotATable`]: no `MLMP` magic.
    /// * [`DecodeError::Truncated`]: too short to hold a table.
    /// * [`DecodeError::Corrupted`]: CRC-32 mismatch.
    /// * [`DecodeError::UnsupportedVersion`]: a format version this build does not read.
    /// * [`DecodeError::ShapeMismatch`]: another `K` or ML / MAP bin count.
    /// * [`DecodeError::BayesShapeMismatch`]: another Bayes shape (a table with a Bayes
    ///   head decoded into a type without one, or the reverse).
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
        let mut table = Self::placeholder(Settings::ZERO);
        table.decode_with(bytes, |_| ([""; K], [(0, 0); K]))?;
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
        self.view().encode(buf)
    }

    /// A table of the right shape, all zeros (it does not satisfy the invariants): every
    /// class and the settings are overwritten before it escapes. All zeros, so that
    /// building it costs no constant data, only a cleared stack slot.
    fn placeholder(settings: Settings) -> Self {
        const fn hist<const B: usize>() -> Histogram<[f32; B]> {
            Histogram {
                lo: 0.0,
                hi: 0.0,
                width: 0.0,
                inv_width: 0.0,
                freqs: [0.0; B],
            }
        }
        Self {
            names: [ClassName::EMPTY; K],
            rows: [0; K],
            priors: [Gaussian::ZERO; K],
            ml: [hist::<B_ML>(); K],
            map: [hist::<B_MAP>(); K],
            settings,
            bayes_axes: [Axis::ZERO; K],
            bayes_terms: [[[0.0; C]; B_BAYES]; K],
            bayes_rows: [0; C],
            bayes_log_prior: [0.0; C],
            bayes_lambda: 0.0,
            bayes_log_lambda: 0.0,
            bayes_open: None,
            recal: [[Knot::ZERO; N]; 4],
            recal_len: [0; 4],
            bayes_os_axis: [Axis::ZERO; F],
            bayes_os_terms: [[[0.0; C]; B_BAYES]; F],
            extent: (),
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
        self.view()
            .ml_into(logits, objectness, &mut out, &mut scratch)?;
        Ok(Scores(out))
    }

    /// MAP scores of one detection with the default [`Libm`](crate::Libm) backend:
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
        self.map_with::<MapBackend>(logits, objectness)
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
        self.view()
            .map_into::<M>(logits, objectness, &mut out, &mut scratch)?;
        Ok(Scores(out))
    }

    /// Bayes scores of one detection (docs/DESIGN.md §1.6): `OS * p_i` with `p` the
    /// posterior over the categories. Only for a table type with a Bayes head
    /// (`B_BAYES > 0`): calling it on one without is a compile-time error.
    ///
    /// The softmax uses the crate's own [`FastMath`](crate::FastMath) `exp` (relative
    /// error at most [`FAST_MATH_MAX_REL_ERROR`](crate::FAST_MATH_MAX_REL_ERROR), a few
    /// `f32` ulp): it keeps this head within 1.5 times the Sigmoid layer's instructions
    /// (docs/PERFORMANCE.md). [`Table::bayes_with`] takes another backend, e.g. `Libm`.
    ///
    /// # Errors
    ///
    /// As [`Table::ml`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn bayes(&self, logits: &[f32; K], objectness: f32) -> Result<Scores<K>, InferError> {
        self.bayes_with::<BayesBackend>(logits, objectness)
    }

    /// Bayes scores of one detection with the maths backend `M`.
    ///
    /// # Errors
    ///
    /// As [`Table::ml`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn bayes_with<M: Backend>(
        &self,
        logits: &[f32; K],
        objectness: f32,
    ) -> Result<Scores<K>, InferError> {
        const {
            assert!(
                B_BAYES > 0,
                "this table type has no Bayes head (B_BAYES = 0)"
            )
        };
        let mut out = [0.0; K];
        let mut scratch = [0.0; C];
        self.view()
            .bayes_into::<M>(logits, objectness, &mut out, &mut scratch)?;
        Ok(Scores(out))
    }

    /// Open-head scores of one detection (docs/DESIGN.md §1.8): `OS * q * softmax(z / T)_i`,
    /// with `q` the probability that the detection is an object of a known class. The
    /// decision among the classes is the detector's own (the largest logit), so the head
    /// keeps its ranking and lowers only what looks unlike anything known. Only for a
    /// table type with a Bayes head (a compile-time error otherwise); a table without the
    /// open head's parameters (format versions 1 and 2) answers
    /// [`InferError::NoOpenHead`]. Uses [`FastMath`](crate::FastMath) as the Bayes head
    /// does; [`Table::open_with`] takes another backend.
    ///
    /// # Errors
    ///
    /// [`InferError::NoOpenHead`]; otherwise as [`Table::ml`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn open(&self, logits: &[f32; K], objectness: f32) -> Result<Scores<K>, InferError> {
        self.open_with::<OpenBackend>(logits, objectness)
    }

    /// Open-head scores of one detection with the maths backend `M`.
    ///
    /// # Errors
    ///
    /// As [`Table::open`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn open_with<M: Backend>(
        &self,
        logits: &[f32; K],
        objectness: f32,
    ) -> Result<Scores<K>, InferError> {
        const {
            assert!(
                B_BAYES > 0,
                "this table type has no Bayes head (B_BAYES = 0), so no open head"
            )
        };
        let mut out = [0.0; K];
        let mut scratch = [0.0; C];
        self.view()
            .open_into::<M>(logits, objectness, &mut out, &mut scratch)?;
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

    /// MAP scores of a batch with the default [`Libm`](crate::Libm) backend; see [`Table::ml_batch`].
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
        self.map_batch_with::<MapBackend>(logits, objectness, out)
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

    /// Bayes scores of a batch, as [`Table::bayes`]; see [`Table::ml_batch`]. Only for a
    /// table type with a Bayes head.
    ///
    /// # Errors
    ///
    /// As [`Table::ml_batch`].
    ///
    /// # Panics
    ///
    /// Never.
    pub fn bayes_batch(
        &self,
        logits: &[[f32; K]],
        objectness: Option<&[f32]>,
        out: &mut [[f32; K]],
    ) -> Result<(), BatchError> {
        batch(logits, objectness, out, |x, os| self.bayes(x, os))
    }

    /// Open-head scores of a batch, as [`Table::ml_batch`].
    ///
    /// # Errors
    ///
    /// As [`Table::ml_batch`].
    ///
    /// # Panics
    ///
    /// Never.
    pub fn open_batch(
        &self,
        logits: &[[f32; K]],
        objectness: Option<&[f32]>,
        out: &mut [[f32; K]],
    ) -> Result<(), BatchError> {
        batch(logits, objectness, out, |x, os| self.open(x, os))
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnostics::error::Head;
    use crate::format::wire::ClassWire;
    use std::vec::Vec;

    /// The decoder `Table::from_bytes` had before it decoded in place: the whole body
    /// into `heapless` vectors, then class by class into a table. Kept to show that the
    /// in-place decoder gives the same table, or the same error, for any bytes.
    fn from_bytes_via_vectors<const K: usize, const B_ML: usize, const B_MAP: usize>(
        bytes: &[u8],
    ) -> Result<Table<K, B_ML, B_MAP>, DecodeError> {
        type Freqs<const B: usize> = heapless::Vec<f32, B>;
        type Classes<'a, const K: usize, const M: usize, const P: usize> =
            heapless::Vec<ClassWire<'a, Freqs<M>, Freqs<P>>, K>;
        fn to_array<const B: usize>(v: &heapless::Vec<f32, B>) -> Option<[f32; B]> {
            (v.len() == B).then(|| core::array::from_fn(|i| v[i]))
        }
        let (header, body) = wire::open(bytes)?;
        if header.shape() != Table::<K, B_ML, B_MAP>::SHAPE {
            return Err(DecodeError::ShapeMismatch {
                expected: Table::<K, B_ML, B_MAP>::SHAPE,
                found: header.shape(),
            });
        }
        if header.bayes_shape() != (0, 0) {
            return Err(DecodeError::BayesShapeMismatch {
                expected: (0, 0),
                found: header.bayes_shape(),
            });
        }
        let (settings, classes) = wire::parse_body::<Classes<'_, K, B_ML, B_MAP>>(body)?;
        if classes.len() != K {
            return Err(DecodeError::Malformed);
        }
        let mut specs = Vec::new();
        for (i, c) in classes.into_iter().enumerate() {
            let c = c.into_spec();
            let class = u16::try_from(i).unwrap();
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
            spec.clone().validate_decoded(i, B_ML, B_MAP)?;
            specs.push(spec);
        }
        let Ok(specs) = <[_; K]>::try_from(specs) else {
            return Err(DecodeError::Malformed);
        };
        let table = Table::<K, B_ML, B_MAP>::from_parts_named(settings, specs, ClassName::stored)?;
        wire::check_canonical(bytes.len(), &table.view())?;
        Ok(table)
    }

    /// `bytes` with its CRC recomputed, so that decoding gets past the checksum.
    fn with_crc(mut bytes: Vec<u8>) -> Vec<u8> {
        if bytes.len() >= 4 {
            let n = bytes.len() - 4;
            let crc = wire::CRC.checksum(&bytes[..n]);
            bytes[n..].copy_from_slice(&crc.to_le_bytes());
        }
        bytes
    }

    /// Every mutation of `original` worth trying: each bit flipped, each byte set to a
    /// few values, each byte removed, a byte inserted anywhere, every truncation, and
    /// seeded random multi-byte edits; all with a correct CRC.
    fn mutations(original: &[u8]) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        let n = original.len();
        for i in 0..n - 4 {
            for bit in 0..8 {
                let mut b = original.to_vec();
                b[i] ^= 1 << bit;
                out.push(with_crc(b));
            }
            for v in [0x00, 0x01, 0x02, 0x03, 0x04, 0x7f, 0x80, 0xff] {
                let mut b = original.to_vec();
                b[i] = v;
                out.push(with_crc(b));
            }
            let mut b = original.to_vec();
            b.remove(i);
            out.push(with_crc(b));
            for v in [0x00, 0x80, 0x16] {
                let mut b = original.to_vec();
                b.insert(i, v);
                out.push(with_crc(b));
            }
        }
        // A frequency sequence one shorter or one longer than the shape, wherever a
        // byte could be its length.
        for i in 0..n - 4 {
            if original[i] > 1 && original[i] < 0x80 {
                let mut b = original.to_vec();
                b[i] -= 1;
                b.drain(i + 1..(i + 5).min(n - 4));
                out.push(with_crc(b));
                let mut b = original.to_vec();
                b[i] += 1;
                b.splice(i + 1..i + 1, 0.5f32.to_le_bytes());
                out.push(with_crc(b));
            }
        }
        for len in 0..n {
            let mut b = original[..len].to_vec();
            b.extend_from_slice(&[0; 4]);
            out.push(with_crc(b));
        }
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..20_000 {
            let mut b = original.to_vec();
            for _ in 0..1 + next() % 4 {
                let i = (next() % (n as u64 - 4)) as usize;
                b[i] = next() as u8;
            }
            out.push(with_crc(b));
        }
        out
    }

    /// `original` (a valid table of this shape) re-encoded with class names that break
    /// the name rules.
    fn bad_names<const K: usize, const B_ML: usize, const B_MAP: usize>(
        original: &[u8],
    ) -> Vec<Vec<u8>> {
        let t = Table::<K, B_ML, B_MAP>::from_bytes(original).unwrap();
        let long = "x".repeat(crate::NAME_MAX + 1);
        let first = t.class_name(0).unwrap();
        let mut out = Vec::new();
        for (class, name) in [
            (1, first),
            (K - 1, first),
            (0, ""),
            (1, "background"),
            (0, &long),
        ] {
            // Class names are unique and at most 31 bytes, so `[len, name...]` first
            // appears at the class's own name field: splice the new name in there.
            let old = t.class_name(class).unwrap().as_bytes();
            let mut needle = std::vec![old.len() as u8];
            needle.extend_from_slice(old);
            let at = original
                .windows(needle.len())
                .position(|w| w == &needle[..])
                .unwrap();
            let mut b = original[..at].to_vec();
            b.push(name.len() as u8);
            b.extend_from_slice(name.as_bytes());
            b.extend_from_slice(&original[at + needle.len()..]);
            out.push(with_crc(b));
        }
        out
    }

    fn same_as_vectors<const K: usize, const B_ML: usize, const B_MAP: usize>(original: &[u8]) {
        let mut all = mutations(original);
        if Table::<K, B_ML, B_MAP>::from_bytes(original).is_ok() {
            all.extend(bad_names::<K, B_ML, B_MAP>(original));
        }
        for bytes in all {
            assert_eq!(
                Table::<K, B_ML, B_MAP>::from_bytes(&bytes),
                from_bytes_via_vectors::<K, B_ML, B_MAP>(&bytes),
                "{bytes:02x?}"
            );
        }
    }

    #[test]
    fn in_place_decoding_equals_decoding_via_vectors() {
        // A version-1 table (the oracle reads version 1 only).
        let default = include_bytes!("../../../tests/golden/train_linspace.mlmap");
        assert!(Table::<3, 22, 17>::from_bytes(default).is_ok());
        same_as_vectors::<3, 22, 17>(default);
        let small = include_bytes!("../../../tests/golden/layer/small.mlmap");
        assert!(Table::<3, 4, 2>::from_bytes(small).is_ok());
        same_as_vectors::<3, 4, 2>(small);
        // Shapes that do not match the bytes.
        same_as_vectors::<2, 4, 2>(small);
        same_as_vectors::<4, 4, 2>(small);
        same_as_vectors::<3, 3, 2>(small);
    }
}
