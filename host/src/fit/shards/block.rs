//! Rows given as arrays: a block of row-major logits and integer labels, as numpy holds
//! them. The fast path of both passes for callers that hold arrays (the Python package,
//! its Dask and Spark recipes): one loop over the block, no per-row record, and exact
//! sums of `f32` logits in per-exponent integer buckets. The results are those of
//! [`FitStats::push`] and [`FitCounts::push`] on the same rows, to the bit.

use super::{FitCounts, FitStats};
use crate::dataset::{DataError, DataErrorKind, Label, Location, Row};
use crate::fit::exact::{F32Sums, F32_ROOM};
use crate::fit::FitError;

mod sealed {
    pub trait Sealed {}
}

/// The element type of the logits of [`FitStats::push_rows`] and
/// [`FitCounts::push_rows`]: `f32` or `f64`.
///
/// `f32` logits take the faster path (their exact sums need no wide integers); both
/// give the statistics of the values as `f64`, as [`FitStats::push`] reads them.
pub trait FitLogit: Copy + sealed::Sealed {
    /// Whether [`as_f32`](Self::as_f32) always gives the value.
    #[doc(hidden)]
    const IS_F32: bool;

    /// The value as an `f64` (exact).
    fn to_f64(self) -> f64;

    /// The value in the layer's precision (an `f64` rounded to the nearest `f32`).
    fn to_f32(self) -> f32;

    /// The value when it is an `f32`.
    #[doc(hidden)]
    fn as_f32(self) -> Option<f32>;
}

impl sealed::Sealed for f32 {}
impl sealed::Sealed for f64 {}

impl FitLogit for f32 {
    const IS_F32: bool = true;

    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }

    #[inline]
    fn to_f32(self) -> f32 {
        self
    }

    #[inline]
    fn as_f32(self) -> Option<f32> {
        Some(self)
    }
}

impl FitLogit for f64 {
    const IS_F32: bool = false;

    #[inline]
    fn to_f64(self) -> f64 {
        self
    }

    #[inline]
    fn to_f32(self) -> f32 {
        self as f32
    }

    #[inline]
    fn as_f32(self) -> Option<f32> {
        None
    }
}

/// The element type of the labels of [`FitStats::push_rows`] and
/// [`FitCounts::push_rows`]: any primitive integer, `0..K` a class index and `-1`
/// background, as in `labels.npy` (DESIGN §2).
pub trait FitLabel: Copy + sealed::Sealed {
    /// The value, exactly.
    fn value(self) -> i128;

    /// The category of the label among `k` classes: `Some(c)` for a class `c < k`,
    /// `Some(k)` for background (`-1`), `None` for any other value.
    #[inline]
    fn category(self, k: usize) -> Option<usize> {
        match self.value() {
            -1 => Some(k),
            v => usize::try_from(v).ok().filter(|&c| c < k),
        }
    }

    /// Whether [`category`](Self::category) is `Some` (without a branch).
    #[doc(hidden)]
    #[inline]
    fn is_valid(self, k: usize) -> bool {
        // -1 ..= k - 1, shifted to 0 ..= k.
        (self.value() + 1) as u128 <= k as u128
    }

    /// The category of a valid label (without a branch).
    #[doc(hidden)]
    #[inline]
    fn index(self, k: usize) -> usize {
        match self.value() {
            v if v < 0 => k,
            v => v as usize,
        }
    }
}

macro_rules! labels {
    ($($t:ty),*) => {$(
        impl sealed::Sealed for $t {}

        impl FitLabel for $t {
            #[inline]
            fn value(self) -> i128 {
                i128::from(self)
            }
        }
    )*};
}

labels!(i8, i16, i32, i64, u8, u16, u32, u64);

/// Checks a block: K logits per label, every label a class index or `-1`.
fn check_block<T, L: FitLabel>(logits: &[T], labels: &[L], k: usize) -> Result<(), FitError> {
    let expected = (labels.len() as u64).saturating_mul(k as u64);
    if logits.len() as u64 != expected {
        let kind = DataErrorKind::Length {
            what: "logits",
            expected,
            found: logits.len() as u64,
        };
        return Err(DataError::new("logits", kind).into());
    }
    // One pass without early exit (it vectorises), then the row of the first bad one.
    if labels.iter().fold(true, |ok, l| ok & l.is_valid(k)) {
        return Ok(());
    }
    match labels.iter().position(|l| l.category(k).is_none()) {
        None => Ok(()),
        Some(i) => {
            let value = labels.get(i).map_or(0, |l| l.value());
            let kind = DataErrorKind::LabelIndex { value, classes: k };
            Err(DataError::new("labels", kind)
                .at(Location::Row(i as u64))
                .into())
        }
    }
}

/// The row of category `c` (`K` background) with the logits `x` as a [`Row`] holds them.
fn with_row<T: FitLogit, R>(c: usize, k: usize, x: &[T], f: impl FnOnce(&Row<'_>) -> R) -> R {
    let logits: Vec<f64> = x.iter().map(|v| v.to_f64()).collect();
    f(&Row {
        index: 0,
        line: None,
        id: None,
        label: if c < k {
            Label::Class(c)
        } else {
            Label::Background
        },
        objectness: 1.0,
        logits: &logits,
    })
}

impl FitStats {
    /// Adds a block of rows held as arrays: `logits` row-major with one value per class
    /// and row (a C-ordered `(N, K)` array), `labels` one per row (`0..K` a class
    /// index, `-1` background).
    ///
    /// The result is the state [`push`](Self::push) of every row gives, to the bit,
    /// several times faster (above all for `f32` logits).
    ///
    /// ```
    /// use mlmap_host::dataset::{Label, Row};
    /// use mlmap_host::fit::FitStats;
    ///
    /// let logits = [2.5f32, -1.0, 0.25, 3.0, -4.0, 1.5];
    /// let labels = [0i64, 1, -1];
    /// let mut block = FitStats::new(&["car", "person"]);
    /// block.push_rows(&logits, &labels).unwrap();
    ///
    /// let mut rows = FitStats::new(&["car", "person"]);
    /// for (x, label) in logits.chunks(2).zip([Label::Class(0), Label::Class(1), Label::Background]) {
    ///     let x: Vec<f64> = x.iter().map(|&v| f64::from(v)).collect();
    ///     rows.push(&Row { index: 0, line: None, id: None, label, objectness: 1.0, logits: &x });
    /// }
    /// assert_eq!(block.to_bytes(), rows.to_bytes());
    /// ```
    ///
    /// # Errors
    ///
    /// [`FitError::Data`] when `logits` does not hold K values per label, or a label is
    /// neither `-1` nor a class index (naming its row in the block). Nothing is added
    /// then.
    pub fn push_rows<T: FitLogit, L: FitLabel>(
        &mut self,
        logits: &[T],
        labels: &[L],
    ) -> Result<(), FitError> {
        let k = self.classes.len();
        check_block(logits, labels, k)?;
        if k == 0 {
            for l in labels {
                let c = l.category(k).unwrap_or(k);
                with_row(c, k, &[] as &[T], |row| self.push(row));
            }
            return Ok(());
        }
        let mut sums: Vec<F32Sums> = if T::IS_F32 {
            vec![F32Sums::default(); k]
        } else {
            Vec::new()
        };
        // At most F32_ROOM values of a class between two flushes of its sums.
        for (xs, ls) in logits.chunks(F32_ROOM * k).zip(labels.chunks(F32_ROOM)) {
            for (x, &l) in xs.chunks_exact(k).zip(ls) {
                match l.index(k) {
                    c if c < k => {
                        if let (Some(m), Some(&v)) = (self.moments.get_mut(c), x.get(c)) {
                            match (v.as_f32(), sums.get_mut(c)) {
                                (Some(v), Some(s)) => m.push_f32(v, s),
                                _ => m.push(v.to_f64()),
                            }
                        }
                        self.bayes.push_values(c, x);
                    }
                    c => self.bayes.push_values(c, x),
                }
            }
            for (m, s) in self.moments.iter_mut().zip(&mut sums) {
                m.flush_f32(s);
            }
        }
        self.rows = self.rows.saturating_add(labels.len() as u64);
        Ok(())
    }
}

impl FitCounts {
    /// Counts a block of rows held as arrays, laid out as for
    /// [`FitStats::push_rows`].
    ///
    /// The counts are those [`push`](Self::push) of every row gives. Returns the index
    /// (in the block) of the first row with a value outside its axis, where `push`
    /// returns `false` (every row is counted all the same), or `None`.
    ///
    /// # Errors
    ///
    /// As [`FitStats::push_rows`]; nothing is counted then.
    pub fn push_rows<T: FitLogit, L: FitLabel>(
        &mut self,
        logits: &[T],
        labels: &[L],
    ) -> Result<Option<usize>, FitError> {
        let k = self.edges.classes.len();
        check_block(logits, labels, k)?;
        let mut first_outside = None;
        if k == 0 {
            for (i, l) in labels.iter().enumerate() {
                let c = l.category(k).unwrap_or(k);
                if !with_row(c, k, &[] as &[T], |row| self.push(row)) && first_outside.is_none() {
                    first_outside = Some(i);
                }
            }
            return Ok(first_outside);
        }
        for (i, (x, &l)) in logits.chunks_exact(k).zip(labels).enumerate() {
            let inside = match l.index(k) {
                c if c < k => {
                    let mut inside = true;
                    if let (Some(a), Some(b), Some(&v)) =
                        (self.ml.get_mut(c), self.map.get_mut(c), x.get(c))
                    {
                        let v = v.to_f32();
                        inside &= a.add(v) & b.add(v);
                    }
                    if let Some(b) = &mut self.bayes {
                        inside &= b.add_values(c, x);
                    }
                    inside
                }
                c => self.bayes.as_mut().is_none_or(|b| b.add_values(c, x)),
            };
            if !inside && first_outside.is_none() {
                first_outside = Some(i);
            }
        }
        self.rows = self.rows.saturating_add(labels.len() as u64);
        Ok(first_outside)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::{FitParams, FitStats};
    use std::string::ToString;

    const CLASSES: [&str; 3] = ["car", "cyclist", "pedestrian"];

    /// A deterministic block: `n` rows of 3 logits spread over many exponents (and the
    /// odd zero and subnormal), labels cycling over the classes and background.
    fn block(n: usize) -> (Vec<f32>, Vec<i64>) {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let logits = (0..3 * n)
            .map(|i| match i % 997 {
                0 => 0.0,
                1 => -f32::from_bits(3),
                _ => {
                    let r = next();
                    let x = (r >> 40) as f32 / (1u64 << 24) as f32 * 16.0 - 8.0;
                    x * if r & 3 == 0 { 1e-3 } else { 1.0 }
                }
            })
            .collect();
        let labels = (0..n).map(|i| (i % 4) as i64 - 1).collect();
        (logits, labels)
    }

    /// `push` of every row, as a row source gives them (logits widened to `f64`).
    fn by_rows(logits: &[f32], labels: &[i64]) -> (FitStats, Vec<Vec<f64>>, Vec<Label>) {
        let rows: Vec<Vec<f64>> = logits
            .chunks(3)
            .map(|x| x.iter().map(|&v| f64::from(v)).collect())
            .collect();
        let labels: Vec<Label> = labels
            .iter()
            .map(|&l| match l {
                -1 => Label::Background,
                c => Label::Class(c as usize),
            })
            .collect();
        let mut s = FitStats::new(&CLASSES);
        for (x, &label) in rows.iter().zip(&labels) {
            s.push(&row(x, label));
        }
        (s, rows, labels)
    }

    fn row(x: &[f64], label: Label) -> Row<'_> {
        Row {
            index: 0,
            line: None,
            id: None,
            label,
            objectness: 1.0,
            logits: x,
        }
    }

    #[test]
    fn blocks_give_the_bytes_of_row_by_row_pushes() {
        // More rows than a class takes between two flushes of its f32 sums.
        let (logits, labels) = block(3 * F32_ROOM + 1234);
        let (want, rows, row_labels) = by_rows(&logits, &labels);

        let mut f32_blocks = FitStats::new(&CLASSES);
        let cut = 7 * 1001;
        f32_blocks
            .push_rows(&logits[..3 * cut], &labels[..cut])
            .unwrap();
        f32_blocks
            .push_rows(&logits[3 * cut..], &labels[cut..])
            .unwrap();
        assert_eq!(f32_blocks.to_bytes(), want.to_bytes());

        let wide: Vec<f64> = logits.iter().map(|&v| f64::from(v)).collect();
        let narrow: Vec<i8> = labels.iter().map(|&l| l as i8).collect();
        let mut f64_block = FitStats::new(&CLASSES);
        f64_block.push_rows(&wide, &narrow).unwrap();
        assert_eq!(f64_block.to_bytes(), want.to_bytes());

        // Pass (b) over the edges of those statistics, with and without a Bayes head.
        for params in [
            FitParams::default(),
            FitParams {
                bayes: None,
                ..FitParams::default()
            },
        ] {
            let edges = want.edges(&params).unwrap();
            let mut counts = FitCounts::new(&edges);
            for (x, &label) in rows.iter().zip(&row_labels) {
                assert!(counts.push(&row(x, label)));
            }
            let mut blocks = FitCounts::new(&edges);
            // Labels of rows 1 and 2 (classes 0 and 1) as another integer type.
            let unsigned: Vec<u16> = labels.iter().map(|&l| l as u16).collect();
            assert_eq!(blocks.push_rows(&logits[..3], &labels[..1]), Ok(None));
            assert_eq!(blocks.push_rows(&wide[3..9], &unsigned[1..3]), Ok(None));
            assert_eq!(blocks.push_rows(&logits[9..], &labels[3..]), Ok(None));
            assert_eq!(blocks.to_bytes(), counts.to_bytes());
        }
    }

    #[test]
    fn bad_blocks_are_refused_and_change_nothing() {
        let (logits, labels) = block(10);
        let mut s = FitStats::new(&CLASSES);
        s.push_rows(&logits, &labels).unwrap();
        let before = s.to_bytes();
        let e = s.push_rows(&logits[..5], &labels[..2]).unwrap_err();
        assert_eq!(e.to_string(), "logits: logits holds 5 values; 6 are needed");
        let e = s.push_rows(&logits[..9], &[0i32, 3, 1]).unwrap_err();
        assert!(e.to_string().starts_with("labels: row index 1: "), "{e}");
        assert!(s.push_rows(&logits[..6], &[255u8, 0]).is_err());
        assert!(s.push_rows(&logits[..6], &[0i16, -2]).is_err());
        assert_eq!(s.to_bytes(), before);

        let edges = s.edges(&FitParams::default()).unwrap();
        let mut c = FitCounts::new(&edges);
        assert!(c.push_rows(&logits[..6], &[5u64, 0]).is_err());
        assert_eq!(c.rows(), 0);
    }

    #[test]
    fn the_first_row_outside_the_edges_is_reported() {
        let (logits, labels) = block(40);
        let mut s = FitStats::new(&CLASSES);
        s.push_rows(&logits[..60], &labels[..20]).unwrap();
        let edges = s.edges(&FitParams::default()).unwrap();
        let mut c = FitCounts::new(&edges);
        // Rows 0..20 were seen; row 21 of the block holds 100, beyond every edge.
        let mut more = logits[..90].to_vec();
        more[3 * 21 + 1] = 100.0;
        more[3 * 25] = -100.0;
        assert_eq!(c.push_rows(&more, &labels[..30]), Ok(Some(21)));
        assert_eq!(c.rows(), 30);
        // Background rows in counts made without background statistics.
        let mut s = FitStats::new(&CLASSES);
        s.push_rows(&logits[3..12], &labels[1..4]).unwrap();
        let mut c = FitCounts::new(&s.edges(&FitParams::default()).unwrap());
        assert_eq!(c.push_rows(&logits[3..12], &labels[1..4]), Ok(None));
        assert_eq!(c.push_rows(&logits[3..12], &[0i64, -1, 1]), Ok(Some(1)));
    }
}
