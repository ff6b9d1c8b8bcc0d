//! Exact sums of `f64` values and of their squares, in fixed point.
//!
//! Every finite `f64` is an integer multiple of `2^-1074` below `2^1024`, and its square
//! an integer multiple of `2^-2148` below `2^2048`. A [`Fixed`] accumulator holds such a
//! sum as one big integer in limbs ("chunks") of 32 bits, each kept in an `i64` so that
//! up to 2^31 additions can land in a chunk before its carries must be passed up (a
//! superaccumulator in the manner of Neal's `xsum`). Adding a value adds its 53-bit
//! mantissa, or the 106-bit integer square of that mantissa, split into 32-bit words,
//! at its bit position: no rounding, so the sum is exact and does not depend on the
//! order of the additions. Merging two sums adds their chunks.
//!
//! [`Fixed::normalize`] brings a sum to its canonical form (every chunk but the top one
//! in `[0, 2^32)`), which equal sums share: it is what is compared and serialized.
//!
//! Mean and variance are then computed from the exact sums with big integers
//! ([`mean`], [`sample_variance`]): each is the exact rational rounded once to the
//! nearest `f64` (except below `2^-1022`, where the result may be rounded twice).

use num_bigint::{BigInt, BigUint, Sign};

/// Chunks of a sum of values: bits `0..2176` in units of `2^-1074`. A finite value
/// reaches bit 2098; 2^64 of them, bit 2162.
pub(crate) const VALUE_CHUNKS: usize = 68;
/// Chunks of a sum of squares: bits `0..4288` in units of `2^-2148`. A square reaches
/// bit 4196; 2^64 of them, bit 4260.
pub(crate) const SQUARE_CHUNKS: usize = 134;

/// Additions allowed between carry propagations: every addition adds less than 2^32
/// to a chunk in `[0, 2^32)`, so a chunk stays below 2^63 in magnitude.
const ROOM: u32 = (1 << 31) - 2;

/// Largest magnitude accepted for the top chunk of a decoded sum (the sum of 2^64
/// values needs less than 2^19 there).
const TOP_LIMIT: i64 = 1 << 40;

/// The parts of a finite `f64`: `(negative, mantissa, position)` with
/// `|x| = mantissa * 2^(position - 1074)`; `None` for NaN and infinities.
#[inline]
pub(crate) fn split(x: f64) -> Option<(bool, u64, u32)> {
    let bits = x.to_bits();
    let negative = bits >> 63 != 0;
    let exponent = ((bits >> 52) & 0x7ff) as u32;
    let fraction = bits & ((1 << 52) - 1);
    match exponent {
        0x7ff => None,
        0 => Some((negative, fraction, 0)),
        e => Some((negative, fraction | (1 << 52), e - 1)),
    }
}

/// An exact sum of integers placed at bit positions, `N` chunks of 32 bits.
#[derive(Debug, Clone)]
pub(crate) struct Fixed<const N: usize> {
    chunks: [i64; N],
    /// Additions left before [`Fixed::normalize`] must run.
    room: u32,
}

impl<const N: usize> Default for Fixed<N> {
    fn default() -> Self {
        Self {
            chunks: [0; N],
            room: ROOM,
        }
    }
}

impl<const N: usize> Fixed<N> {
    /// Adds (or subtracts, when `negative`) the integer `v` at bit `pos`.
    ///
    /// `pos` must leave the shifted value inside the accumulator (the callers' bit
    /// budgets above); words past the last chunk are dropped, never written out of
    /// bounds.
    #[inline]
    pub(crate) fn add(&mut self, negative: bool, v: u128, pos: u32) {
        if self.room == 0 {
            self.normalize();
        }
        self.room -= 1;
        let shift = pos & 31;
        let low = v << shift;
        // The bits shifted past bit 127 (at most 31 of them).
        let top = v.checked_shr(128 - shift).unwrap_or(0) & u128::from(u32::MAX);
        let words = [
            low as u32,
            (low >> 32) as u32,
            (low >> 64) as u32,
            (low >> 96) as u32,
            top as u32,
        ];
        let start = (pos >> 5) as usize;
        let chunks = self.chunks.iter_mut().skip(start);
        if negative {
            for (c, w) in chunks.zip(words) {
                *c -= i64::from(w);
            }
        } else {
            for (c, w) in chunks.zip(words) {
                *c += i64::from(w);
            }
        }
    }

    /// Passes every carry up: afterwards each chunk but the top one is in `[0, 2^32)`.
    pub(crate) fn normalize(&mut self) {
        let mut carry = 0i64;
        let last = N.saturating_sub(1);
        for (i, c) in self.chunks.iter_mut().enumerate() {
            let v = c.wrapping_add(carry);
            if i == last {
                *c = v;
            } else {
                carry = v >> 32;
                *c = v & 0xffff_ffff;
            }
        }
        self.room = ROOM;
    }

    /// Adds another sum (both are normalized first).
    pub(crate) fn merge(&mut self, other: &Self) {
        let mut other = other.clone();
        other.normalize();
        self.normalize();
        for (c, o) in self.chunks.iter_mut().zip(other.chunks) {
            *c = c.wrapping_add(o);
        }
        self.normalize();
    }

    /// The canonical form: `(offset, chunks)`, the normalized chunks without the zero
    /// chunks at either end, the first of them being chunk `offset`.
    pub(crate) fn to_words(&self) -> (u32, Vec<i64>) {
        let mut n = self.clone();
        n.normalize();
        let first = n.chunks.iter().position(|&c| c != 0);
        let last = n.chunks.iter().rposition(|&c| c != 0);
        match (first, last) {
            (Some(a), Some(b)) => (
                a as u32,
                n.chunks.get(a..=b).map(<[i64]>::to_vec).unwrap_or_default(),
            ),
            _ => (0, Vec::new()),
        }
    }

    /// The sum of canonical words, or `None` when they are not a valid normalized sum
    /// (out of the accumulator, or chunks out of range).
    pub(crate) fn from_words(offset: u32, words: &[i64]) -> Option<Self> {
        let offset = offset as usize;
        let end = offset.checked_add(words.len())?;
        if end > N {
            return None;
        }
        let mut s = Self::default();
        for (i, (c, &w)) in s.chunks.iter_mut().skip(offset).zip(words).enumerate() {
            let ok = if offset + i + 1 == N {
                (-TOP_LIMIT..=TOP_LIMIT).contains(&w)
            } else {
                (0..=0xffff_ffff).contains(&w)
            };
            if !ok {
                return None;
            }
            *c = w;
        }
        Some(s)
    }

    /// The exact sum as an integer (in the accumulator's unit).
    pub(crate) fn to_bigint(&self) -> BigInt {
        let mut acc = BigInt::default();
        for &c in self.chunks.iter().rev() {
            acc = (acc << 32u32) + BigInt::from(c);
        }
        acc
    }
}

impl<const N: usize> PartialEq for Fixed<N> {
    fn eq(&self, other: &Self) -> bool {
        self.to_words() == other.to_words()
    }
}

/// Value buckets: one per 32-bit chunk position of a value's mantissa.
const VALUE_BUCKETS: usize = 64;
/// Square buckets: one per 8 positions of a value (16 bits of its square).
const SQUARE_BUCKETS: usize = 256;
/// Additions a square bucket takes before it must be flushed: each adds less than
/// 2^120 (a 106-bit square shifted by at most 14 bits), so 256 stay below 2^128.
const BUCKET_ROOM: u32 = 256;

/// The exact sum and sum of squares of `f64` values: the fast path of
/// [`ClassMoments`](super::ClassMoments).
///
/// A value is added with one 128-bit addition to a bucket chosen by its exponent (its
/// mantissa pre-shifted within the bucket), its square with another; every 256 values
/// the buckets touched are flushed into the [`Fixed`] accumulators. Values of a class
/// have few distinct exponents, so few buckets are touched.
#[derive(Debug, Clone)]
pub(crate) struct Sums {
    /// Bucket `i`: a signed sum of mantissas shifted by `pos & 31`, at bit `32 i`.
    values: [i128; VALUE_BUCKETS],
    /// Bucket `i`: a sum of squared mantissas shifted by `2 (pos & 7)`, at bit `16 i`.
    squares: [u128; SQUARE_BUCKETS],
    /// Range of buckets touched since the last flush (`lo > hi` when none).
    touched_lo: usize,
    touched_hi: usize,
    /// Values added since the last flush.
    pending: u32,
    sum: Fixed<VALUE_CHUNKS>,
    sum_sq: Fixed<SQUARE_CHUNKS>,
}

impl Default for Sums {
    fn default() -> Self {
        Self {
            values: [0; VALUE_BUCKETS],
            squares: [0; SQUARE_BUCKETS],
            touched_lo: SQUARE_BUCKETS,
            touched_hi: 0,
            pending: 0,
            sum: Fixed::default(),
            sum_sq: Fixed::default(),
        }
    }
}

impl Sums {
    /// Adds a finite value's parts ([`split`]).
    #[inline]
    pub(crate) fn add(&mut self, negative: bool, m: u64, pos: u32) {
        if self.pending == BUCKET_ROOM {
            self.flush();
        }
        self.pending += 1;
        let p = pos as usize;
        let v = i128::from(m) << (pos & 31);
        if let Some(b) = self.values.get_mut(p >> 5) {
            *b += if negative { -v } else { v };
        }
        let sq = (u128::from(m) * u128::from(m)) << (2 * (pos & 7));
        let i = p >> 3;
        if let Some(b) = self.squares.get_mut(i) {
            *b += sq;
        }
        self.touched_lo = self.touched_lo.min(i);
        self.touched_hi = self.touched_hi.max(i);
    }

    /// Moves the buckets into the exact accumulators.
    fn flush(&mut self) {
        let (lo, hi) = (self.touched_lo, self.touched_hi);
        if lo <= hi {
            // Square bucket i covers value positions 8i..8i+7, value bucket i / 4.
            for j in (lo >> 2)..=(hi >> 2) {
                if let Some(b) = self.values.get_mut(j) {
                    let v = std::mem::take(b);
                    if v != 0 {
                        self.sum.add(v < 0, v.unsigned_abs(), 32 * j as u32);
                    }
                }
            }
            for i in lo..=hi {
                if let Some(b) = self.squares.get_mut(i) {
                    let v = std::mem::take(b);
                    if v != 0 {
                        self.sum_sq.add(false, v, 16 * i as u32);
                    }
                }
            }
        }
        self.touched_lo = SQUARE_BUCKETS;
        self.touched_hi = 0;
        self.pending = 0;
    }

    /// The exact sums, `(values, squares)`.
    pub(crate) fn exact(&self) -> (Fixed<VALUE_CHUNKS>, Fixed<SQUARE_CHUNKS>) {
        let mut s = self.clone();
        s.flush();
        s.sum.normalize();
        s.sum_sq.normalize();
        (s.sum, s.sum_sq)
    }

    /// Adds other sums.
    pub(crate) fn merge(&mut self, other: &Self) {
        self.flush();
        let (a, b) = other.exact();
        self.sum.merge(&a);
        self.sum_sq.merge(&b);
    }

    /// Sums holding exactly `sum` and `sum_sq`.
    pub(crate) fn from_exact(sum: Fixed<VALUE_CHUNKS>, sum_sq: Fixed<SQUARE_CHUNKS>) -> Self {
        Self {
            sum,
            sum_sq,
            ..Self::default()
        }
    }
}

/// Buckets of an [`F32Sums`]: one per biased `f32` exponent (255, NaN and infinities,
/// is never filled).
const F32_BUCKETS: usize = 256;

/// Values an [`F32Sums`] takes between two flushes: a squared 24-bit mantissa is below
/// 2^48, so 2^16 of them stay below 2^64 in a square bucket (and the signed sums of
/// mantissas, below 2^40, far inside an `i64`).
pub(crate) const F32_ROOM: usize = 1 << 16;

/// Position (in units of `2^-1074`) of the mantissa of an `f32` of biased exponent `e`:
/// `|x| = m 2^(max(e, 1) - 150)` and `-150 + 1074 = 924`.
#[inline]
fn f32_position(e: usize) -> u32 {
    e.clamp(1, 254) as u32 + 924
}

/// The exact sum and sum of squares of `f32` values between two flushes into a
/// [`Sums`]: per biased exponent, the signed sum of the 24-bit mantissas and the sum of
/// their 48-bit squares. A value costs two integer additions and no shift; the caller
/// flushes ([`flush_into`](Self::flush_into)) at least every [`F32_ROOM`] values.
///
/// An `f32` is an `f64` with a shorter mantissa, so the flushed sums are exactly those
/// [`Sums::add`] gives for the same values converted to `f64`.
#[derive(Debug, Clone)]
pub(crate) struct F32Sums {
    values: [i64; F32_BUCKETS],
    squares: [u64; F32_BUCKETS],
}

impl Default for F32Sums {
    fn default() -> Self {
        Self {
            values: [0; F32_BUCKETS],
            squares: [0; F32_BUCKETS],
        }
    }
}

impl F32Sums {
    /// Adds `x`; `false` (and nothing added) when it is NaN or infinite.
    #[inline]
    pub(crate) fn add(&mut self, x: f32) -> bool {
        let bits = x.to_bits();
        let e = ((bits >> 23) & 0xff) as usize;
        if e == 0xff {
            return false;
        }
        let fraction = bits & 0x7f_ffff;
        let m = if e == 0 {
            fraction
        } else {
            fraction | 0x80_0000
        };
        let m = i64::from(m);
        let signed = if bits >> 31 != 0 { -m } else { m };
        if let Some(b) = self.values.get_mut(e) {
            *b += signed;
        }
        if let Some(b) = self.squares.get_mut(e) {
            *b += (m * m) as u64;
        }
        true
    }

    /// Moves the buckets into `sums` (and empties them).
    pub(crate) fn flush_into(&mut self, sums: &mut Sums) {
        for (e, (v, sq)) in self.values.iter_mut().zip(&mut self.squares).enumerate() {
            // A square bucket is 0 only when every mantissa added there was 0.
            let (v, sq) = (std::mem::take(v), std::mem::take(sq));
            if sq == 0 {
                continue;
            }
            let pos = f32_position(e);
            if v != 0 {
                sums.sum.add(v < 0, u128::from(v.unsigned_abs()), pos);
            }
            sums.sum_sq.add(false, u128::from(sq), 2 * pos);
        }
    }
}

impl PartialEq for Sums {
    fn eq(&self, other: &Self) -> bool {
        self.exact() == other.exact()
    }
}

/// `num / den * 2^exp2` rounded to the nearest `f64` (ties to even); `den > 0`.
pub(crate) fn ratio_to_f64(num: &BigInt, den: &BigUint, exp2: i64) -> f64 {
    let (sign, mag) = (num.sign(), num.magnitude());
    if mag.bits() == 0 || den.bits() == 0 {
        return 0.0;
    }
    // Scale so that the quotient has 66 or 67 bits: 13 or more below the f64's 53, the
    // lowest of which records whether anything was left over (so rounding is exact).
    let shift = 66 - (mag.bits() as i64 - den.bits() as i64);
    let (n, d) = if shift >= 0 {
        (mag << shift as u64, den.clone())
    } else {
        (mag.clone(), den << shift.unsigned_abs())
    };
    let (q, r) = (&n / &d, &n % &d);
    let digits = q.to_u64_digits();
    let mut q128 = digits
        .iter()
        .rev()
        .fold(0u128, |acc, &w| (acc << 64) | u128::from(w));
    if r.bits() != 0 {
        q128 |= 1;
    }
    let e = (exp2 - shift).clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
    let v = libm::scalbn(q128 as f64, e);
    if sign == Sign::Minus {
        -v
    } else {
        v
    }
}

/// The exact mean `s1 / n` rounded to `f64` (0 when `n = 0`), for a sum of values in
/// units of `2^-1074`.
pub(crate) fn mean(n: u64, s1: &Fixed<VALUE_CHUNKS>) -> f64 {
    if n == 0 {
        return 0.0;
    }
    ratio_to_f64(&s1.to_bigint(), &BigUint::from(n), -1074)
}

/// The exact sample variance `(n s2 - s1^2) / (n (n - 1))` rounded to `f64` (0 when
/// `n < 2`), for sums of values (units `2^-1074`) and squares (units `2^-2148`).
pub(crate) fn sample_variance(n: u64, s1: &Fixed<VALUE_CHUNKS>, s2: &Fixed<SQUARE_CHUNKS>) -> f64 {
    if n < 2 {
        return 0.0;
    }
    let a = s1.to_bigint();
    let b = s2.to_bigint();
    // n s2 - s1^2 in units of 2^-2148: both terms are exact integers.
    let num = BigInt::from(n) * b - &a * &a;
    let den = BigUint::from(n) * BigUint::from(n - 1);
    ratio_to_f64(&num, &den, -2148).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sums(values: &[f64]) -> (Fixed<VALUE_CHUNKS>, Fixed<SQUARE_CHUNKS>) {
        let mut s = Sums::default();
        for &x in values {
            let (neg, m, pos) = split(x).unwrap();
            s.add(neg, m, pos);
        }
        s.exact()
    }

    #[test]
    fn split_gives_mantissa_and_position() {
        assert_eq!(split(1.0), Some((false, 1 << 52, 1022)));
        assert_eq!(split(-0.5), Some((true, 1 << 52, 1021)));
        assert_eq!(split(0.0), Some((false, 0, 0)));
        assert_eq!(split(f64::from_bits(1)), Some((false, 1, 0)));
        assert_eq!(split(f64::MAX).map(|s| s.2), Some(2045));
        assert_eq!(split(f64::NAN), None);
        assert_eq!(split(f64::NEG_INFINITY), None);
    }

    #[test]
    fn sums_are_exact_where_f64_addition_is_not() {
        // 1e16 + 1 - 1e16 is 0 in f64 (1 is lost), 1 exactly here.
        let (s1, _) = sums(&[1e16, 1.0, -1e16]);
        assert_eq!(s1.to_bigint(), BigInt::from(1) << 1074u32);
        assert_eq!(mean(3, &s1), 1.0 / 3.0);
        // The extremes of the range, and cancellation to exactly zero.
        let (s1, s2) = sums(&[f64::MAX, f64::from_bits(1), -f64::MAX, -f64::from_bits(1)]);
        assert_eq!(s1.to_words(), (0, vec![]));
        // 2 (MAX^2 + tiny^2) in units of 2^-2148: MAX = m 2^(2045 - 1074), tiny = 2^-1074.
        let m = BigInt::from((1u64 << 53) - 1);
        let want = BigInt::from(2) * (&m * &m * (BigInt::from(1) << (2 * 2045u32)) + 1);
        assert_eq!(s2.to_bigint(), want);
    }

    #[test]
    fn variance_has_no_cancellation() {
        // 1e9 + {0, 1, 2}: sample variance exactly 1; mean exactly 1e9 + 1.
        let v = [1e9, 1e9 + 1.0, 1e9 + 2.0];
        let (s1, s2) = sums(&v);
        assert_eq!(sample_variance(3, &s1, &s2), 1.0);
        assert_eq!(mean(3, &s1), 1e9 + 1.0);
    }

    #[test]
    fn order_does_not_matter_and_merge_is_addition() {
        // More values than a bucket takes between flushes, over many exponents.
        let v: Vec<f64> = (0..2000)
            .map(|i| ((i as f64) * 0.7309).sin() * 10f64.powi(i % 17 - 8))
            .collect();
        let (a1, a2) = sums(&v);
        let mut rev = v.clone();
        rev.reverse();
        let (b1, b2) = sums(&rev);
        assert_eq!(a1.to_words(), b1.to_words());
        assert_eq!(a2.to_words(), b2.to_words());
        let (mut c1, mut c2) = sums(&v[..777]);
        let (d1, d2) = sums(&v[777..]);
        c1.merge(&d1);
        c2.merge(&d2);
        assert_eq!(c1, a1);
        assert_eq!(c2, a2);
    }

    #[test]
    fn f32_buckets_give_the_sums_of_the_values_as_f64() {
        // Every kind of f32: zeros, subnormals, the smallest and largest normals, both
        // signs, and many values of one exponent (more than a flush interval).
        let mut v: std::vec::Vec<f32> = vec![
            0.0,
            -0.0,
            f32::from_bits(1),
            -f32::from_bits(0x7f_ffff),
            f32::MIN_POSITIVE,
            f32::MAX,
            -f32::MAX,
            1.5,
            -2.75,
        ];
        v.extend((0..3 * F32_ROOM as u32).map(|i| ((i as f32) * 0.618).sin() * 3.0));
        v.extend((0..2000).map(|i| ((i as f32) * 0.7309).cos() * 10f32.powi(i % 61 - 30)));
        let want = sums(
            &v.iter()
                .map(|&x| f64::from(x))
                .collect::<std::vec::Vec<_>>(),
        );
        let mut got = Sums::default();
        let mut buckets = F32Sums::default();
        for (i, &x) in v.iter().enumerate() {
            if i % F32_ROOM == F32_ROOM - 1 {
                buckets.flush_into(&mut got);
            }
            assert!(buckets.add(x));
        }
        buckets.flush_into(&mut got);
        assert_eq!(got.exact(), want);
        // By hand: the smallest subnormal is 2^-149 = 2^(925 - 1074); 2^-149 - 3 2^-149
        // = -2 2^-149, and the squares 10 2^-298 = 10 2^(1850 - 2148).
        let mut s = Sums::default();
        let mut b = F32Sums::default();
        for x in [f32::from_bits(1), -3.0 * f32::from_bits(1)] {
            assert!(b.add(x));
        }
        b.flush_into(&mut s);
        let (s1, s2) = s.exact();
        assert_eq!(s1.to_bigint(), -(BigInt::from(2) << 925u32));
        assert_eq!(s2.to_bigint(), BigInt::from(10) << 1850u32);
        assert!(!b.add(f32::NAN) && !b.add(f32::INFINITY) && !b.add(f32::NEG_INFINITY));
    }

    #[test]
    fn carries_pass_up_after_many_additions() {
        let mut s = Fixed::<VALUE_CHUNKS> {
            room: 3,
            ..Fixed::default()
        };
        for _ in 0..10 {
            s.add(false, (1 << 53) - 1, 31);
        }
        let want = (BigInt::from(10) * BigInt::from((1u64 << 53) - 1)) << 31u32;
        assert_eq!(s.to_bigint(), want);
    }

    #[test]
    fn full_buckets_are_flushed_before_they_overflow() {
        // 4.0.next_down() = (2^53 - 1) 2^-51: the largest mantissa at position 1023, the
        // largest shift of its square bucket (2 (1023 & 7) = 14 bits).
        let x = 4.0f64.next_down();
        assert_eq!(split(x), Some((false, (1 << 53) - 1, 1023)));
        let (s1, s2) = sums(&[x; 1000]);
        let m = BigInt::from((1u64 << 53) - 1);
        assert_eq!(s1.to_bigint(), (BigInt::from(1000) * &m) << 1023u32);
        assert_eq!(s2.to_bigint(), (BigInt::from(1000) * &m * &m) << 2046u32);
        assert_eq!(mean(1000, &s1), x);
        assert_eq!(sample_variance(1000, &s1, &s2), 0.0);
    }

    #[test]
    fn words_round_trip_and_bad_words_are_refused() {
        let (s1, _) = sums(&[-3.25, 7.0, 1e-300]);
        let (off, w) = s1.to_words();
        assert_eq!(Fixed::<VALUE_CHUNKS>::from_words(off, &w), Some(s1));
        assert!(Fixed::<VALUE_CHUNKS>::from_words(67, &[1, 2]).is_none());
        assert!(Fixed::<VALUE_CHUNKS>::from_words(0, &[1 << 33]).is_none());
        assert!(Fixed::<VALUE_CHUNKS>::from_words(0, &[-1]).is_none());
        assert!(Fixed::<VALUE_CHUNKS>::from_words(u32::MAX, &[1]).is_none());
    }

    #[test]
    fn ratio_rounds_to_nearest_even() {
        // 1/3, 2/3 and a tie: (2^53 + 1) / 1 rounds to 2^53 (even).
        let one = BigUint::from(1u8);
        assert_eq!(
            ratio_to_f64(&BigInt::from(1), &BigUint::from(3u8), 0),
            1.0 / 3.0
        );
        assert_eq!(
            ratio_to_f64(&BigInt::from(-2), &BigUint::from(3u8), 0),
            -2.0 / 3.0
        );
        let tie = BigInt::from((1u64 << 53) + 1);
        assert_eq!(ratio_to_f64(&tie, &one, 0), 9007199254740992.0);
        // Just above the tie rounds up.
        let above = (BigInt::from((1u64 << 53) + 1) << 1u32) + 1;
        assert_eq!(ratio_to_f64(&above, &one, -1), 9007199254740994.0);
        assert_eq!(ratio_to_f64(&BigInt::from(0), &one, 5), 0.0);
    }
}
