//! Shared pieces of the mlmap fuzz targets: structured inputs built with `arbitrary`,
//! and checks of every table and score they meet.
//!
//! The invariants of DESIGN §1.3 are checked by `mlmap::invariants`, the checkers the
//! property tests use too; this crate adds what only the fuzz targets check (numpy's bin
//! rule at every edge, the scores against the formula, the batch API and `DynTable`
//! agreeing bit for bit), for the ML and MAP heads and, on tables that have them, the Bayes
//! head (DESIGN §1.6; arbitrary heads from [`ArbBayes`]) and the open head (DESIGN §1.8;
//! arbitrary temperatures and epsilons from [`ArbOpen`]). Every check panics (which
//! libFuzzer reports as a crash) when it does not hold, with a message naming the
//! invariant.

use std::fmt::Display;

use arbitrary::{Arbitrary, Unstructured};
use mlmap::host::BayesSpec;
use mlmap::host::DynTable;
use mlmap::invariants::{
    self, Sum, Violation, SUBNORMAL_STEP as TINY, SUM_RELATIVE_TOLERANCE as SUM_TOLERANCE,
};
use mlmap::{
    fast_math_max_score_error, Backend, BatchError, ClassSpec, EdgeMode, FastMath, Gaussian, Head,
    Histogram, InferError, Libm, Scores, Settings, Table, TableError, UpperTail,
    FAST_MATH_MAX_SCORE_ERROR, MAX_EPSILON, MAX_TEMPERATURE, MIN_TEMPERATURE,
};

/// The table shipped with the crate: K = 3, 22 ML bins, 17 MAP bins.
pub const SHIPPED: &[u8] = include_bytes!("../../tables/default.mlmap");

/// The shape of [`SHIPPED`].
pub type Shipped = Table<3, 22, 17, 22, 4>;

/// CRC-32/ISO-HDLC, the checksum of the table format.
pub const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// `bytes` with its last four bytes replaced by the CRC-32 of the bytes before them, so
/// that mutated bodies get past the checksum and reach the parser and the validation.
pub fn with_valid_crc(bytes: &[u8]) -> Option<Vec<u8>> {
    let body = bytes.get(..bytes.len().checked_sub(4)?)?;
    let mut v = body.to_vec();
    v.extend_from_slice(&CRC.checksum(body).to_le_bytes());
    Some(v)
}

/// Panics with `context` and the violation's message when an invariant does not hold.
pub fn must(result: Result<(), Violation>, context: impl Display) {
    if let Err(v) = result {
        panic!("{context}: {v}");
    }
}

// ---------------------------------------------------------------------------------------
// Table invariants (DESIGN §1.3, invariant 5)
// ---------------------------------------------------------------------------------------

/// Checks one histogram against every table invariant and the bin rule of numpy.
pub fn check_histogram<F: AsRef<[f32]>>(h: &Histogram<F>, head: Head, class: usize, bins: usize) {
    must(
        invariants::check_histogram(head, class, h, bins),
        "table invariants",
    );
    let what = format!("{head} histogram {class}");
    let (lo, hi) = (h.lo(), h.hi());
    assert_eq!(h.edge(0).to_bits(), lo.to_bits(), "{what}: e_0 != lo");
    assert_eq!(h.edge(bins).to_bits(), hi.to_bits(), "{what}: e_B != hi");
    // The bin rule: an edge opens the bin to its right, the last edge is closed, and
    // nothing outside [e_0, e_B] is in a bin.
    for k in 0..bins {
        let e = h.edge(k);
        assert_eq!(h.bin(e), Some(k), "{what}: edge {k} = {e} not in bin {k}");
        let below_next = h.edge(k + 1).next_down();
        assert_eq!(
            h.bin(below_next),
            Some(k),
            "{what}: {below_next} (just below edge {}) not in bin {k}",
            k + 1
        );
    }
    assert_eq!(
        h.bin(hi),
        Some(bins - 1),
        "{what}: last edge not in the last bin"
    );
    assert_eq!(h.bin(lo.next_down()), None, "{what}: below e_0 is in a bin");
    assert_eq!(h.bin(hi.next_up()), None, "{what}: above e_B is in a bin");
    assert_eq!(h.bin(f32::NAN), None, "{what}: NaN is in a bin");
    for (k, &f) in h.frequencies().iter().enumerate() {
        let l = h.likelihood(h.edge(k), UpperTail::Zero);
        assert_eq!(l.to_bits(), f.to_bits(), "{what}: likelihood at edge {k}");
    }
}

/// Checks one prior: finite mean, finite positive variance, a finite positive density.
pub fn check_prior(g: &Gaussian, class: usize) {
    must(
        invariants::check_prior(class, g.mean(), g.variance()),
        "table invariants",
    );
    let what = format!("prior {class}");
    let peak = g.pdf::<Libm>(g.mean());
    assert!(
        peak.is_finite() && peak > 0.0,
        "{what}: pdf at the mean {peak}"
    );
    assert_eq!(g.pdf::<Libm>(f32::INFINITY), 0.0, "{what}: pdf(+inf)");
    assert_eq!(g.pdf::<Libm>(f32::NEG_INFINITY), 0.0, "{what}: pdf(-inf)");
}

/// Checks every table invariant of a fixed-size table through its accessors.
pub fn check_table<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
) {
    must(invariants::check_table(t), "table invariants");
    for i in 0..K {
        let ml = t
            .ml_histogram(i)
            .expect("ML histogram of an existing class");
        let map = t
            .map_histogram(i)
            .expect("MAP histogram of an existing class");
        check_histogram(ml, Head::Ml, i, B_ML);
        check_histogram(map, Head::Map, i, B_MAP);
        check_prior(t.prior(i).expect("prior of an existing class"), i);
        assert_eq!(t.class_index(t.class_name(i).unwrap_or_default()), Some(i));
    }
    assert!(t.class_name(K).is_none() && t.ml_histogram(K).is_none() && t.spec(K).is_none());
}

/// Checks every table invariant of a run-time shaped table.
pub fn check_dyn_table(t: &DynTable) {
    let k = t.k();
    assert!((2..=usize::from(u16::MAX)).contains(&k), "K = {k}");
    must(invariants::check_dyn_table(t), "table invariants");
    assert_eq!(t.rows().len(), k);
    for (i, h) in t.ml_histograms().iter().enumerate() {
        check_histogram(h, Head::Ml, i, t.bins_ml());
    }
    for (i, h) in t.map_histograms().iter().enumerate() {
        check_histogram(h, Head::Map, i, t.bins_map());
    }
    for (i, g) in t.priors().iter().enumerate() {
        check_prior(g, i);
    }
}

/// Encodes `t` and asserts the result is `expected` byte for byte, twice (encoding is
/// deterministic), and that decoding it gives `t` back.
pub fn check_encoding<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    expected: Option<&[u8]>,
) -> Vec<u8> {
    let mut buf = vec![0u8; Table::<K, B_ML, B_MAP, BB, C>::MAX_ENCODED_LEN];
    let first = t
        .to_slice(&mut buf)
        .expect("MAX_ENCODED_LEN suffices")
        .to_vec();
    let mut buf2 = vec![0xA5u8; Table::<K, B_ML, B_MAP, BB, C>::MAX_ENCODED_LEN];
    let second = t.to_slice(&mut buf2).expect("MAX_ENCODED_LEN suffices");
    assert_eq!(first.as_slice(), &*second, "encoding is not deterministic");
    if let Some(expected) = expected {
        assert_eq!(first.as_slice(), expected, "re-encoding changed the bytes");
    }
    let back = Table::<K, B_ML, B_MAP, BB, C>::from_bytes(&first).expect("own encoding decodes");
    assert_eq!(&back, t, "encode -> decode changed the table");
    // Host and device share the format: the run-time shaped table reads the same bytes
    // into the same statistics and writes them back identically.
    let dynt = DynTable::from_bytes(&first).expect("own encoding decodes as DynTable");
    assert_eq!(dynt, DynTable::from_table(t), "DynTable differs from Table");
    assert_eq!(
        dynt.to_vec().expect("encodes"),
        first,
        "DynTable re-encodes differently"
    );
    let again = Table::<K, B_ML, B_MAP, BB, C>::try_from(&dynt).expect("DynTable converts back");
    assert_eq!(&again, t, "Table -> DynTable -> Table changed the table");
    first
}

// ---------------------------------------------------------------------------------------
// Structured tables
// ---------------------------------------------------------------------------------------

/// A real number from fuzz input: mostly ordinary magnitudes, sometimes any `f32` bit
/// pattern (NaN, ±inf, subnormals, extremes).
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Real {
    /// `v / 64`: values of order 1 to 500, the range logits live in.
    Small(i16),
    /// `m * 2^e`: any magnitude, exactly representable.
    Scaled(i16, i8),
    /// Any bit pattern.
    Bits(u32),
}

impl Real {
    /// The value.
    pub fn get(self) -> f32 {
        match self {
            Real::Small(v) => f32::from(v) / 64.0,
            Real::Scaled(m, e) => f32::from(m) * 2f32.powi(i32::from(e)),
            Real::Bits(b) => f32::from_bits(b),
        }
    }

    /// The value made non-negative, except for raw bit patterns (which may be anything,
    /// so that validation sees negative and non-finite values too).
    pub fn positive(self) -> f32 {
        match self {
            Real::Bits(b) => f32::from_bits(b),
            other => other.get().abs(),
        }
    }
}

/// Frequencies of a `B`-bin histogram.
#[derive(Arbitrary, Debug, Clone)]
pub enum Freqs<const B: usize> {
    /// Proportional to integer weights (uniform when they are all 0).
    Weights([u16; B]),
    /// All mass in one bin.
    OneHot(u16),
    /// Any bit patterns (almost always invalid).
    Bits([u32; B]),
}

impl<const B: usize> Freqs<B> {
    /// The `B` frequencies.
    pub fn get(&self) -> [f32; B] {
        match self {
            Freqs::Weights(w) => {
                let total: u64 = w.iter().map(|&v| u64::from(v)).sum();
                if total == 0 {
                    [1.0 / B as f32; B]
                } else {
                    w.map(|v| (f64::from(v) / total as f64) as f32)
                }
            }
            Freqs::OneHot(i) => {
                let mut f = [0.0; B];
                f[usize::from(*i) % B] = 1.0;
                f
            }
            Freqs::Bits(b) => b.map(f32::from_bits),
        }
    }
}

/// One histogram: first edge, width of the support, frequencies.
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbHistogram<const B: usize> {
    lo: Real,
    span: Real,
    freqs: Freqs<B>,
}

impl<const B: usize> ArbHistogram<B> {
    fn range(&self) -> (f32, f32) {
        let lo = self.lo.get();
        (lo, lo + self.span.positive())
    }
}

/// A class name: a usual one, or any string.
#[derive(Arbitrary, Debug, Clone)]
pub enum ArbName {
    /// One of a few usual names (so that duplicates occur).
    Known(u8),
    /// Any UTF-8 string.
    Text(String),
}

impl ArbName {
    fn get(&self) -> &str {
        const KNOWN: [&str; 8] = [
            "car",
            "cyclist",
            "pedestrian",
            "truck",
            "bus",
            "background",
            "x",
            "a-class-name-of-exactly-31-bytes",
        ];
        match self {
            ArbName::Known(i) => KNOWN[usize::from(*i) % KNOWN.len()],
            ArbName::Text(s) => s,
        }
    }
}

/// One class's statistics.
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbClass<const B_ML: usize, const B_MAP: usize> {
    name: ArbName,
    rows: u64,
    mean: Real,
    variance: Real,
    ml: ArbHistogram<B_ML>,
    map: ArbHistogram<B_MAP>,
}

impl<const B_ML: usize, const B_MAP: usize> ArbClass<B_ML, B_MAP> {
    fn spec(&self) -> ClassSpec<'_, [f32; B_ML], [f32; B_MAP]> {
        ClassSpec {
            name: self.name.get(),
            rows: self.rows,
            mean: self.mean.get(),
            variance: self.variance.positive(),
            ml_range: self.ml.range(),
            ml_freqs: self.ml.freqs.get(),
            map_range: self.map.range(),
            map_freqs: self.map.freqs.get(),
        }
    }
}

/// Settings of a table.
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbSettings {
    lambda_ml: Real,
    lambda_map: Real,
    matlab: bool,
    clamp: bool,
}

impl ArbSettings {
    fn get(&self) -> Settings {
        Settings {
            lambda_ml: self.lambda_ml.positive(),
            lambda_map: self.lambda_map.positive(),
            edge_mode: if self.matlab {
                EdgeMode::Matlab
            } else {
                EdgeMode::Linspace
            },
            upper_tail: if self.clamp {
                UpperTail::Clamp
            } else {
                UpperTail::Zero
            },
        }
    }
}

/// A whole table, valid or not; [`ArbTable::build`] validates it.
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbTable<const K: usize, const B_ML: usize, const B_MAP: usize> {
    settings: ArbSettings,
    classes: [ArbClass<B_ML, B_MAP>; K],
}

impl<const K: usize, const B_ML: usize, const B_MAP: usize> ArbTable<K, B_ML, B_MAP> {
    /// `Table::from_parts` of these statistics. When it succeeds, asserts that the table
    /// stores the statistics exactly as given.
    pub fn build(&self) -> Result<Table<K, B_ML, B_MAP>, TableError> {
        let settings = self.settings.get();
        let specs: [ClassSpec<'_, [f32; B_ML], [f32; B_MAP]>; K] =
            core::array::from_fn(|i| self.classes[i].spec());
        let t = Table::from_parts(settings, specs.clone())?;
        assert_eq!(bits_of_settings(t.settings()), bits_of_settings(&settings));
        for (i, want) in specs.iter().enumerate() {
            let got = t.spec(i).expect("spec of an existing class");
            assert_eq!(got.name, want.name, "class {i}: name");
            assert_eq!(got.rows, want.rows, "class {i}: rows");
            let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
            assert_eq!(scalars(&got), scalars(want), "class {i}: statistics");
            assert_eq!(
                bits(got.ml_freqs),
                bits(&want.ml_freqs),
                "class {i}: ML freqs"
            );
            assert_eq!(
                bits(got.map_freqs),
                bits(&want.map_freqs),
                "class {i}: MAP freqs"
            );
        }
        Ok(t)
    }
}

/// The scalar statistics of a class, as bits.
fn scalars<F, G>(c: &ClassSpec<'_, F, G>) -> [u32; 6] {
    [
        c.mean,
        c.variance,
        c.ml_range.0,
        c.ml_range.1,
        c.map_range.0,
        c.map_range.1,
    ]
    .map(f32::to_bits)
}

fn bits_of_settings(s: &Settings) -> (u32, u32, EdgeMode, UpperTail) {
    (
        s.lambda_ml.to_bits(),
        s.lambda_map.to_bits(),
        s.edge_mode,
        s.upper_tail,
    )
}

// ---------------------------------------------------------------------------------------
// Inference invariants (DESIGN §1.3, invariants 1, 2 and 4)
// ---------------------------------------------------------------------------------------

/// A logit from fuzz input.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Logit {
    /// Any bit pattern: NaN (any payload), ±inf, subnormals, ±0, extremes.
    Bits(u32),
    /// `v / 256`, the range real logits live in.
    Grid(i16),
    /// An edge of this class's ML (`map = false`) or MAP histogram, moved by `ulps`
    /// representable steps: bin boundaries, where rounding decides.
    Edge {
        /// The MAP histogram (else the ML one).
        map: bool,
        /// The edge, modulo the histogram's edge count.
        k: u16,
        /// Representable steps from the edge.
        ulps: i8,
    },
    /// An edge of this logit's Bayes axis (when the table has that head; else 0), moved
    /// by `ulps` steps.
    BayesEdge {
        /// The edge, modulo the axis's edge count.
        k: u16,
        /// Representable steps from the edge.
        ulps: i8,
    },
}

/// An objectness score from fuzz input.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Objectness {
    /// Any bit pattern (mostly outside [0, 1]).
    Bits(u32),
    /// `v / 65535`, in [0, 1].
    Unit(u16),
    /// Exactly 1 (plain classifiers).
    One,
    /// A value at or just beyond the bounds of [0, 1], or a subnormal.
    Special(u8),
}

impl Objectness {
    /// The value.
    pub fn get(self) -> f32 {
        match self {
            Objectness::Bits(b) => f32::from_bits(b),
            Objectness::Unit(v) => f32::from(v) / 65535.0,
            Objectness::One => 1.0,
            Objectness::Special(i) => {
                const S: [f32; 10] = [
                    0.0,
                    -0.0,
                    1.0,
                    1.000_000_1,
                    0.999_999_94,
                    -1.0e-45,
                    1.0e-45,
                    f32::MIN_POSITIVE,
                    f32::INFINITY,
                    f32::NAN,
                ];
                S[usize::from(i) % S.len()]
            }
        }
    }
}

/// Turns fuzz logits into values for table `t`.
pub fn logits<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    raw: &[Logit; K],
) -> [f32; K] {
    core::array::from_fn(|i| match raw[i] {
        Logit::Bits(b) => f32::from_bits(b),
        Logit::Grid(v) => f32::from(v) / 256.0,
        Logit::Edge { map, k, ulps } => {
            let k = usize::from(k);
            let x = if map {
                let h = t.map_histogram(i).expect("class exists");
                h.edge(k % (B_MAP + 1))
            } else {
                let h = t.ml_histogram(i).expect("class exists");
                h.edge(k % (B_ML + 1))
            };
            step(x, ulps)
        }
        Logit::BayesEdge { k, ulps } => {
            let axis = t.bayes_head().and_then(|h| h.axis(i).copied());
            let x = axis.map_or(0.0, |a| a.edge(usize::from(k) % (a.bins() + 1)));
            step(x, ulps)
        }
    })
}

/// `x` moved by `ulps` representable steps.
fn step(mut x: f32, ulps: i8) -> f32 {
    for _ in 0..ulps.unsigned_abs() {
        x = if ulps > 0 { x.next_up() } else { x.next_down() };
    }
    x
}

/// Checks scores for valid inputs against invariants 1 and 2 and against the formula.
///
/// `mass[i]` is class i's evidence (`L_i` for ML, `L_i * P_i` for MAP, as the public
/// accessors compute them) and `lambda` the head's smoothing.
pub fn check_scores(head: &str, s: &[f32], objectness: f32, mass: &[f32], lambda: f32) {
    let os = f64::from(objectness);
    // Invariant 1: every score in [0, OS], the sum OS within 1e-5 relative.
    must(
        invariants::check_scores(s, objectness, Sum::Equal),
        format_args!("{head}: scores {s:?}"),
    );
    // Invariant 2 (an evidence of 0, inside or outside the support): no evidence at all
    // gives exactly OS / K for every class.
    if mass.iter().all(|&m| m == 0.0) {
        must(
            invariants::check_unknown(s, objectness),
            format_args!("{head}: scores {s:?}"),
        );
    }
    // The formula, in f64: OS * (m_i + lambda) / sum_j (m_j + lambda).
    let a = |m: f32| f64::from(m) + f64::from(lambda);
    let total: f64 = mass.iter().map(|&m| a(m)).sum();
    for (i, (&v, &m)) in s.iter().zip(mass).enumerate() {
        let want = os * a(m) / total;
        assert!(
            (f64::from(v) - want).abs() <= SUM_TOLERANCE * os + 4.0 * TINY,
            "{head}: score {i} = {v:e}, formula gives {want:e}; scores {s:?}, mass {mass:?}, lambda {lambda:e}"
        );
    }
}

/// The likelihood by definition (DESIGN §1.2), independently of the library's lookup:
/// a binary search for the last edge `e_k <= x` (numpy's rule, the last bin closed).
pub fn reference_likelihood<F: AsRef<[f32]>>(h: &Histogram<F>, x: f32, tail: UpperTail) -> f32 {
    let last = h.bins() - 1;
    let k = if x >= h.lo() && x <= h.hi() {
        // Invariant: e_lo <= x, and x < e_hi or hi = last + 1.
        let (mut lo, mut hi) = (0usize, last + 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if x >= h.edge(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    } else if x > h.hi() && tail == UpperTail::Clamp {
        last
    } else {
        return 0.0;
    };
    h.frequencies()[k]
}

/// The library's likelihood of every logit equals the definition's, for both heads.
fn check_likelihoods<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    x: &[f32; K],
) {
    let tail = t.settings().upper_tail;
    for (i, &xi) in x.iter().enumerate() {
        let ml = t.ml_histogram(i).expect("class exists");
        let map = t.map_histogram(i).expect("class exists");
        for (head, got, want) in [
            (
                "ML",
                ml.likelihood(xi, tail),
                reference_likelihood(ml, xi, tail),
            ),
            (
                "MAP",
                map.likelihood(xi, tail),
                reference_likelihood(map, xi, tail),
            ),
        ] {
            assert_eq!(
                got.to_bits(),
                want.to_bits(),
                "{head} likelihood of class {i} at x = {xi:e}: {got:e}, by definition {want:e}"
            );
        }
    }
}

fn map_mass<
    M: Backend,
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    x: &[f32; K],
) -> [f32; K] {
    let tail = t.settings().upper_tail;
    core::array::from_fn(|i| {
        let h = t.map_histogram(i).expect("class exists");
        let l = h.likelihood(x[i], tail);
        if l > 0.0 {
            l * t.prior(i).expect("class exists").pdf::<M>(x[i])
        } else {
            0.0
        }
    })
}

/// Scores one detection with every head and checks invariants 1, 2 and 4, the formula,
/// the batch API and the run-time shaped table (which must agree bit for bit).
///
/// `fast_bound`: also assert the documented [`FAST_MATH_MAX_SCORE_ERROR`] between the
/// `FastMath` and `Libm` MAP scores (it is documented for the shipped table), scaled by
/// `OS`, plus the rounding of scores in the subnormal range (`OS` below about `1e-38`).
pub fn check_detection<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    dynt: &DynTable,
    x: &[f32; K],
    objectness: f32,
    fast_bound: bool,
) {
    check_likelihoods(t, x);
    let expected = invariants::expected_error(x, objectness);
    let ml = t.ml(x, objectness);
    let map = t.map(x, objectness);
    let fast = t.map_with::<FastMath>(x, objectness);
    for (head, r) in [("ML", &ml), ("MAP", &map), ("MAP fast", &fast)] {
        must(
            invariants::check_error(x, objectness, r.err()),
            format_args!("{head}: x = {x:?}, OS = {objectness:e}"),
        );
    }
    let tail = t.settings().upper_tail;
    if let (Ok(ml), Ok(map), Ok(fast)) = (ml, map, fast) {
        let l: [f32; K] = core::array::from_fn(|i| {
            let h = t.ml_histogram(i).expect("class exists");
            h.likelihood(x[i], tail)
        });
        check_scores("ML", &ml.0, objectness, &l, t.settings().lambda_ml);
        let lambda = t.settings().lambda_map;
        check_scores(
            "MAP",
            &map.0,
            objectness,
            &map_mass::<Libm, K, B_ML, B_MAP, BB, C>(t, x),
            lambda,
        );
        let m = map_mass::<FastMath, K, B_ML, B_MAP, BB, C>(t, x);
        check_scores("MAP fast", &fast.0, objectness, &m, lambda);
        if fast_bound {
            for (a, b) in map.0.iter().zip(fast.0) {
                assert!(
                    f64::from((a - b).abs())
                        <= f64::from(FAST_MATH_MAX_SCORE_ERROR * objectness) + 2.0 * TINY,
                    "FastMath differs by more than the documented bound: {:?} vs {:?}, x = {x:?}",
                    map.0,
                    fast.0
                );
            }
        }
        check_same_elsewhere(t, dynt, x, objectness, [ml, map, fast]);
    } else {
        let mut out = [[0.0f32; K]; 1];
        let batch = t.ml_batch(&[*x], Some(&[objectness]), &mut out);
        let want = mlmap::BatchError::Row {
            index: 0,
            error: expected.expect("an error was expected"),
        };
        assert_eq!(batch, Err(want), "ml_batch of an invalid row");
        let mut o = [0.0f32; K];
        let mut scratch = [0.0f32; K];
        assert_eq!(
            dynt.ml_into(x, objectness, &mut o, &mut scratch),
            Err(want_err(want))
        );
        assert_eq!(
            dynt.map_into::<Libm>(x, objectness, &mut o, &mut scratch),
            Err(want_err(want))
        );
    }
}

fn want_err(b: mlmap::BatchError) -> mlmap::InferError {
    match b {
        mlmap::BatchError::Row { error, .. } => error,
        other => panic!("not a row error: {other:?}"),
    }
}

/// The batch API and the run-time shaped table compute the very same bits.
fn check_same_elsewhere<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    dynt: &DynTable,
    x: &[f32; K],
    objectness: f32,
    [ml, map, fast]: [Scores<K>; 3],
) {
    let bits = |s: &[f32; K]| s.map(f32::to_bits);
    let mut out = [[0.0f32; K]; 2];
    let xs = [*x, *x];
    let os = [objectness, objectness];
    t.ml_batch(&xs, Some(&os), &mut out).expect("valid rows");
    assert_eq!(bits(&out[1]), bits(&ml.0), "ml_batch differs from ml");
    t.map_batch(&xs, Some(&os), &mut out).expect("valid rows");
    assert_eq!(bits(&out[1]), bits(&map.0), "map_batch differs from map");
    t.map_batch_with::<FastMath>(&xs, Some(&os), &mut out)
        .expect("valid rows");
    assert_eq!(
        bits(&out[1]),
        bits(&fast.0),
        "map_batch_with differs from map_with"
    );
    let mut o = [0.0f32; K];
    let mut scratch = [0.0f32; K];
    dynt.ml_into(x, objectness, &mut o, &mut scratch)
        .expect("valid");
    assert_eq!(bits(&o), bits(&ml.0), "DynTable ML differs");
    dynt.map_into::<Libm>(x, objectness, &mut o, &mut scratch)
        .expect("valid");
    assert_eq!(bits(&o), bits(&map.0), "DynTable MAP differs");
    dynt.map_into::<FastMath>(x, objectness, &mut o, &mut scratch)
        .expect("valid");
    assert_eq!(bits(&o), bits(&fast.0), "DynTable MAP fast differs");
}

/// Most detections one fuzz input holds: small inputs keep executions fast, and the
/// fuzzer explores one detection at a time anyway.
pub const MAX_DETECTIONS: usize = 8;

/// Scores detections read from `u` until it is exhausted (at most [`MAX_DETECTIONS`]).
pub fn check_detections<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    u: &mut Unstructured<'_>,
    fast_bound: bool,
) {
    let dynt = DynTable::from_table(t);
    for_detections(t, u, |x, os| check_detection(t, &dynt, x, os, fast_bound));
}

/// As [`check_detections`], plus [`check_bayes_detection`] for each detection, and
/// [`check_open_detection`] when the table has the open head (a version-2 table must
/// answer [`InferError::NoOpenHead`]): for a table type with a Bayes head (`BB > 0`).
pub fn check_detections_with_bayes<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    u: &mut Unstructured<'_>,
    fast_bound: bool,
) {
    check_detections_with_open(t, None, u, fast_bound);
}

/// As [`check_detections_with_bayes`], plus, when `higher` is given (the same table with
/// a larger epsilon), [`check_open_monotone`] for each detection.
pub fn check_detections_with_open<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    higher: Option<&Table<K, B_ML, B_MAP, BB, C>>,
    u: &mut Unstructured<'_>,
    fast_bound: bool,
) {
    let dynt = DynTable::from_table(t);
    let has_open = t.open_params().is_some();
    for_detections(t, u, |x, os| {
        check_detection(t, &dynt, x, os, fast_bound);
        check_bayes_detection(t, &dynt, x, os);
        if has_open {
            check_open_detection(t, &dynt, x, os);
        } else {
            // No open head: asked for, it is an error whatever the input.
            assert_eq!(
                t.open(x, os),
                Err(InferError::NoOpenHead),
                "version-2 table"
            );
        }
        if let Some(h) = higher {
            check_open_monotone(t, h, x, os);
        }
    });
}

/// Reads detections from `u` until it is exhausted (at most [`MAX_DETECTIONS`]).
fn for_detections<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    u: &mut Unstructured<'_>,
    mut check: impl FnMut(&[f32; K], f32),
) {
    for _ in 0..MAX_DETECTIONS {
        if u.is_empty() {
            break;
        }
        let (Ok(raw), Ok(os)) = (u.arbitrary::<[Logit; K]>(), u.arbitrary::<Objectness>()) else {
            break;
        };
        let x = logits(t, &raw);
        check(&x, os.get());
    }
}

// ---------------------------------------------------------------------------------------
// The Bayes head (DESIGN §1.6)
// ---------------------------------------------------------------------------------------

/// An arbitrary Bayes head for a table of `K` classes, `BB` bins per logit and `C`
/// categories: a lambda, a range per logit, rows per category and per (category,
/// logit) frequencies from integer weights, stored as a fit stores them
/// (`ln(h + lambda)` in `f64`, rounded to `f32`); now and then a term of any bits.
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbBayes<const K: usize, const BB: usize, const C: usize> {
    lambda: BayesLambda,
    ranges: [(Real, Real); K],
    rows: [u32; C],
    weights: [[[u16; BB]; K]; C],
    /// A term to overwrite with any bits (index into the terms, then the bits).
    hostile: Option<(u16, u32)>,
    /// The objectness feature (DESIGN §1.6): its axis (start, span) and per category
    /// integer weights of its bins.
    objectness: Option<((Real, Real), [[u16; BB]; C])>,
}

/// The Bayes head's smoothing from fuzz input.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum BayesLambda {
    /// `10^(-v / 4096)`: from 1 down to about 1e-16.
    Decades(u16),
    /// Any bits (mostly invalid).
    Bits(u32),
}

impl<const K: usize, const BB: usize, const C: usize> ArbBayes<K, BB, C> {
    /// The head as a [`BayesSpec`] (valid unless a range, the rows, lambda or a hostile
    /// term make it invalid).
    pub fn spec(&self) -> BayesSpec {
        let lambda = match self.lambda {
            BayesLambda::Decades(v) => 10f64.powf(-f64::from(v) / 4096.0) as f32,
            BayesLambda::Bits(b) => f32::from_bits(b),
        };
        let mut terms = Vec::with_capacity(K * BB * C);
        for j in 0..K {
            for b in 0..BB {
                for w in &self.weights {
                    let total: u64 = w[j].iter().map(|&v| u64::from(v)).sum();
                    let h = if total == 0 {
                        1.0 / BB as f64
                    } else {
                        f64::from(w[j][b]) / total as f64
                    };
                    terms.push((h + f64::from(lambda)).ln() as f32);
                }
            }
        }
        if let Some((i, bits)) = self.hostile {
            let n = terms.len();
            terms[usize::from(i) % n] = f32::from_bits(bits);
        }
        // The feature's terms: bin-major, then category.
        let objectness = self.objectness.as_ref().map(|((lo, span), weights)| {
            let span = span.positive();
            let span = if span == 0.0 { 1.0 } else { span };
            let mut t = Vec::with_capacity(BB * C);
            for b in 0..BB {
                for w in weights {
                    let total: u64 = w.iter().map(|&v| u64::from(v)).sum();
                    let h = if total == 0 {
                        1.0 / BB as f64
                    } else {
                        f64::from(w[b]) / total as f64
                    };
                    t.push((h + f64::from(lambda)).ln() as f32);
                }
            }
            ((lo.get(), lo.get() + span), t)
        });
        BayesSpec {
            lambda,
            // 0 rows (invalid) only for `u32::MAX`, a span of 0 (invalid) made 1: most
            // heads are valid even when the input runs out (and reads as zeros).
            rows: self
                .rows
                .iter()
                .map(|&n| u64::from(n.wrapping_add(1)))
                .collect(),
            ranges: self
                .ranges
                .iter()
                .map(|(lo, span)| {
                    let span = span.positive();
                    let span = if span == 0.0 { 1.0 } else { span };
                    (lo.get(), lo.get() + span)
                })
                .collect(),
            terms,
            objectness,
        }
    }

    /// `table` with this Bayes head, as the fixed-size type `Table<K, B_ML, B_MAP, BB,
    /// C>` (through `DynTable::with_bayes` and the wire format), checked by
    /// [`check_dyn_table`] and [`check_table`]; `None` when `with_bayes` refuses the head.
    /// Asserts that it never accepts terms that [`invariants::check_bayes_terms`]
    /// refuses.
    pub fn attach<const B_ML: usize, const B_MAP: usize>(
        &self,
        table: &Table<K, B_ML, B_MAP>,
    ) -> Option<Table<K, B_ML, B_MAP, BB, C>> {
        let spec = self.spec();
        let valid_terms = (0..C).all(|c| {
            (0..K).all(|j| {
                let terms = (0..BB).map(|b| spec.terms[(j * BB + b) * C + c]);
                invariants::check_bayes_terms(c, j, spec.lambda, terms, BB).is_ok()
            })
        });
        if spec.objectness.is_some() {
            // The objectness feature (DESIGN §1.6): checked on its own (the checks below
            // are written for heads without it); no table for them.
            if let Ok(d) = DynTable::from_table(table).with_bayes(spec.clone()) {
                check_objectness_feature::<K, B_ML, B_MAP, BB, C>(&d);
            }
            return None;
        }
        match DynTable::from_table(table).with_bayes(spec.clone()) {
            Ok(d) => {
                assert!(
                    valid_terms,
                    "with_bayes accepted terms the checkers refuse: {spec:?}"
                );
                check_dyn_table(&d);
                let t = Table::<K, B_ML, B_MAP, BB, C>::try_from(&d)
                    .expect("a valid Bayes head converts to its shape");
                check_table(&t);
                assert_eq!(DynTable::from_table(&t), d, "Table and DynTable differ");
                Some(t)
            }
            Err(_) => None,
        }
    }
}

/// A table with the objectness feature (DESIGN §1.6): its bytes decode to the same table
/// (version 4), the fixed-size type with `F = 1` scores the Bayes head bit for bit as
/// the host's table for objectness values across the axis and both ends, every score in
/// `[0, OS]` and their sum at most `OS`; a type without room refuses it.
pub fn check_objectness_feature<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    d: &DynTable,
) {
    let bytes = d.to_vec().expect("a valid table encodes");
    assert_eq!(bytes[4], 4, "the objectness feature is format version 4");
    assert_eq!(&DynTable::from_bytes(&bytes).expect("decodes"), d);
    assert_eq!(
        Table::<K, B_ML, B_MAP, BB, C>::from_bytes(&bytes).err(),
        Some(mlmap::DecodeError::ObjectnessMismatch { found: true })
    );
    let t = Table::<K, B_ML, B_MAP, BB, C, 0, 1>::from_bytes(&bytes).expect("room for it");
    let x = [0.0f32; K];
    let (mut out, mut scratch) = ([0.0f32; K], [0.0f32; C]);
    for os in [0.0f32, 1e-30, 0.1, 0.5, 0.9, 1.0 - f32::EPSILON, 1.0] {
        let s = t.bayes(&x, os).expect("a valid detection");
        d.bayes_into::<mlmap::FastMath>(&x, os, &mut out, &mut scratch)
            .expect("a valid detection");
        assert_eq!(s.0.map(f32::to_bits), out.map(f32::to_bits), "OS = {os:e}");
        assert!(s.0.iter().all(|&v| (0.0..=os).contains(&v)), "{s:?}");
        assert!(s.0.iter().sum::<f32>() <= os * (1.0 + 1e-5), "{s:?}");
    }
}

/// Scores one detection with the Bayes head (FastMath, the default, and Libm) and
/// checks DESIGN §1.6: errors for bad inputs (invariant 4, from `Table`, `DynTable` and
/// the batch); otherwise scores in `[0, OS]` with the head's sum rule, within
/// [`invariants::bayes_score_tolerance`] of the formula evaluated in `f64` from the
/// view's terms ([`invariants::bayes_reference`]), the prior's shares when every logit
/// is outside its axis, FastMath within `fast_math_max_score_error(C) * OS` of Libm
/// (plus `OS * f32::MIN_POSITIVE` and two subnormal steps, see `tests/invariants.rs`),
/// and the same bits from `DynTable` and the batch.
pub fn check_bayes_detection<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    dynt: &DynTable,
    x: &[f32; K],
    objectness: f32,
) {
    let head = t.bayes_head().expect("a table type with a Bayes head");
    let fast = t.bayes(x, objectness);
    let libm = t.bayes_with::<Libm>(x, objectness);
    let what = format_args!("Bayes: x = {x:?}, OS = {objectness:e}");
    for r in [&fast, &libm] {
        must(invariants::check_error(x, objectness, r.err()), what);
    }
    let mut out = [0.0f32; K];
    let mut scratch = [0.0f32; C];
    let mut batch = [[0.0f32; K]; 2];
    let xs = [*x, *x];
    let os = [objectness, objectness];
    let (Ok(fast), Ok(libm)) = (fast, libm) else {
        let error = invariants::expected_error(x, objectness).expect("an error was expected");
        assert_eq!(
            dynt.bayes_into::<FastMath>(x, objectness, &mut out, &mut scratch),
            Err(error),
            "{what}: DynTable"
        );
        assert_eq!(
            t.bayes_batch(&xs, Some(&os), &mut batch),
            Err(mlmap::BatchError::Row { index: 0, error }),
            "{what}: bayes_batch"
        );
        return;
    };
    let mut want = [0.0f64; K];
    let mut s64 = [0.0f64; C];
    assert!(invariants::bayes_reference(
        &head, x, objectness, &mut want, &mut s64
    ));
    let unknown = (0..K).all(|j| head.axis(j).and_then(|a| a.bin(x[j])).is_none());
    for (name, s) in [("FastMath", &fast.0), ("Libm", &libm.0)] {
        must(
            invariants::check_scores(s, objectness, invariants::bayes_sum(&head)),
            format_args!("{what}: {name} {s:?}"),
        );
        if let Some(i) = invariants::bayes_mismatch(&head, s, &want, objectness) {
            panic!(
                "{what}: {name} score {i} of {s:?} is not the formula's {want:?} within a relative {:e}",
                invariants::bayes_score_tolerance(&head)
            );
        }
        if unknown {
            must(
                invariants::check_prior_share(s, objectness, &head),
                format_args!("{what}: {name} {s:?}"),
            );
        }
    }
    let os64 = f64::from(objectness);
    let bound = f64::from(fast_math_max_score_error(C)) * os64
        + os64 * f64::from(f32::MIN_POSITIVE)
        + 2.0 * TINY;
    for (a, b) in fast.0.iter().zip(&libm.0) {
        assert!(
            f64::from((a - b).abs()) <= bound,
            "{what}: FastMath {:?} and Libm {:?} more than {bound:e} apart",
            fast.0,
            libm.0
        );
    }
    let bits = |s: &[f32; K]| s.map(f32::to_bits);
    dynt.bayes_into::<FastMath>(x, objectness, &mut out, &mut scratch)
        .expect("valid");
    assert_eq!(bits(&out), bits(&fast.0), "{what}: DynTable differs");
    dynt.bayes_into::<Libm>(x, objectness, &mut out, &mut scratch)
        .expect("valid");
    assert_eq!(bits(&out), bits(&libm.0), "{what}: DynTable Libm differs");
    t.bayes_batch(&xs, Some(&os), &mut batch)
        .expect("valid rows");
    assert_eq!(
        bits(&batch[1]),
        bits(&fast.0),
        "{what}: bayes_batch differs"
    );
}

// ---------------------------------------------------------------------------------------
// The open head (DESIGN §1.8)
// ---------------------------------------------------------------------------------------

/// The open head's temperature from fuzz input.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum ArbTemperature {
    /// 1, what `fit` writes.
    One,
    /// `10^(12 v / 65535 - 6)`: every decade of the allowed `[1e-6, 1e6]`.
    Decades(u16),
    /// A bound of the allowed range, one step beyond it, or a value never allowed.
    Bound(u8),
    /// Any bits (mostly invalid).
    Bits(u32),
}

impl ArbTemperature {
    /// The value.
    pub fn get(self) -> f32 {
        match self {
            ArbTemperature::One => 1.0,
            ArbTemperature::Decades(v) => 10f64.powf(12.0 * f64::from(v) / 65535.0 - 6.0) as f32,
            ArbTemperature::Bound(i) => {
                const S: [f32; 8] = [
                    MIN_TEMPERATURE,
                    MAX_TEMPERATURE,
                    MIN_TEMPERATURE.next_down(),
                    MAX_TEMPERATURE.next_up(),
                    0.0,
                    -1.0,
                    f32::INFINITY,
                    f32::NAN,
                ];
                S[usize::from(i) % S.len()]
            }
            ArbTemperature::Bits(b) => f32::from_bits(b),
        }
    }
}

/// The open head's epsilon (the unknown category's prior weight) from fuzz input.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum ArbEpsilon {
    /// 0: no unknown category, what `fit` writes.
    Zero,
    /// `10^(68 v / 65535 - 38)`: every decade from about `f32::MIN_POSITIVE` to the
    /// allowed maximum `1e30`.
    Decades(u16),
    /// A bound of the allowed values, one step beyond one, or a value never allowed
    /// (negative zero, a subnormal, infinity, NaN).
    Bound(u8),
    /// Any bits (mostly invalid).
    Bits(u32),
}

impl ArbEpsilon {
    /// The value.
    pub fn get(self) -> f32 {
        match self {
            ArbEpsilon::Zero => 0.0,
            ArbEpsilon::Decades(v) => 10f64.powf(68.0 * f64::from(v) / 65535.0 - 38.0) as f32,
            ArbEpsilon::Bound(i) => {
                const S: [f32; 9] = [
                    f32::MIN_POSITIVE,
                    MAX_EPSILON,
                    1.0,
                    -0.0,
                    f32::MIN_POSITIVE.next_down(),
                    MAX_EPSILON.next_up(),
                    -1.0e-3,
                    f32::INFINITY,
                    f32::NAN,
                ];
                S[usize::from(i) % S.len()]
            }
            ArbEpsilon::Bits(b) => f32::from_bits(b),
        }
    }
}

/// The open head's parameters, and a second, larger epsilon for the monotonicity check.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub struct ArbOpen {
    temperature: ArbTemperature,
    epsilon: ArbEpsilon,
    /// The larger epsilon: `epsilon * 2^(raise / 256)` (from 0: `10^(raise / 1024 - 37.5)`),
    /// at most the allowed maximum.
    raise: u16,
}

impl ArbOpen {
    /// The temperature and epsilon.
    pub fn params(&self) -> (f32, f32) {
        (self.temperature.get(), self.epsilon.get())
    }

    /// An epsilon no smaller than [`ArbOpen::params`]' (when that one is valid).
    pub fn raised(&self) -> f32 {
        let e = self.epsilon.get();
        let up = if e == 0.0 {
            10f64.powf(f64::from(self.raise) / 1024.0 - 37.5)
        } else {
            f64::from(e) * 2f64.powf(f64::from(self.raise) / 256.0)
        };
        // Never below e: f32 rounding of the product cannot go under it (up >= e).
        (up.min(f64::from(MAX_EPSILON)) as f32).max(e)
    }

    /// `table` (which must have a Bayes head) with this open head, through
    /// `DynTable::with_open` and the wire format (version 3), checked by
    /// [`check_dyn_table`] and [`check_table`], with the parameters stored bit for bit;
    /// `None` when `with_open` refuses the parameters, which must then be the ones
    /// [`invariants::check_open_params`] refuses (and the other way round).
    pub fn attach<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const BB: usize,
        const C: usize,
    >(
        &self,
        table: &Table<K, B_ML, B_MAP, BB, C>,
    ) -> Option<Table<K, B_ML, B_MAP, BB, C>> {
        let (temperature, epsilon) = self.params();
        with_open(table, temperature, epsilon)
    }

    /// `table` with the temperature of [`ArbOpen::params`] and [`ArbOpen::raised`] as
    /// epsilon (unchecked beyond what decoding checks: [`ArbOpen::attach`] checks the
    /// same code on the other epsilon).
    pub fn attach_raised<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const BB: usize,
        const C: usize,
    >(
        &self,
        table: &Table<K, B_ML, B_MAP, BB, C>,
    ) -> Option<Table<K, B_ML, B_MAP, BB, C>> {
        let d = DynTable::from_table(table)
            .with_open(self.temperature.get(), self.raised())
            .ok()?;
        Table::try_from(&d).ok()
    }
}

/// `table` with the open head `(temperature, epsilon)`: see [`ArbOpen::attach`].
fn with_open<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    table: &Table<K, B_ML, B_MAP, BB, C>,
    temperature: f32,
    epsilon: f32,
) -> Option<Table<K, B_ML, B_MAP, BB, C>> {
    let valid = invariants::check_open_params(temperature, epsilon).is_ok();
    let what = format!("with_open(T = {temperature:e}, epsilon = {epsilon:e})");
    match DynTable::from_table(table).with_open(temperature, epsilon) {
        Ok(d) => {
            assert!(valid, "{what} accepted parameters the checkers refuse");
            check_dyn_table(&d);
            let t = Table::<K, B_ML, B_MAP, BB, C>::try_from(&d)
                .expect("a table with a valid open head converts to its shape");
            check_table(&t);
            let p = t
                .open_params()
                .expect("the open head survives the wire format");
            assert_eq!(
                (p.temperature().to_bits(), p.epsilon().to_bits()),
                (temperature.to_bits(), epsilon.to_bits()),
                "{what}: stored as {p:?}"
            );
            let bytes = d.to_vec().expect("a valid table encodes");
            // Version 3: the open head without a map (a table is written in the lowest
            // version that holds it).
            assert_eq!(
                bytes.get(4).copied(),
                Some(3),
                "{what}: not written as format version 3"
            );
            Some(t)
        }
        Err(e) => {
            assert!(!valid, "{what} refused valid parameters: {e}");
            assert!(
                matches!(e, TableError::Temperature | TableError::Epsilon),
                "{what}: {e:?}"
            );
            None
        }
    }
}

/// Scores one detection with the open head (FastMath, the default, and Libm) and checks
/// DESIGN §1.8 through the shared checkers: errors for bad inputs
/// ([`invariants::check_error`], and the same error from `DynTable`, the view's
/// `score_into(Head::Open)` and the batch); otherwise scores in `[0, OS]` summing to at
/// most `OS` ([`invariants::check_scores`] with [`Sum::AtMost`]), the detector's decision
/// ([`invariants::check_open_decision`]), within [`invariants::open_score_tolerance`] of
/// the `f64` formula ([`invariants::open_mismatch`] against
/// [`invariants::open_reference`]); with epsilon 0 and no background category, bit for
/// bit the temperature layer; and the same bits from `DynTable`, the view and the batch.
pub fn check_open_detection<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    dynt: &DynTable,
    x: &[f32; K],
    objectness: f32,
) {
    let head = t.bayes_head().expect("a table type with a Bayes head");
    let params = t.open_params().expect("a table with the open head");
    let fast = t.open(x, objectness);
    let libm = t.open_with::<Libm>(x, objectness);
    let what = format_args!("open: x = {x:?}, OS = {objectness:e}, {params:?}");
    for r in [&fast, &libm] {
        must(invariants::check_error(x, objectness, r.err()), what);
    }
    let view = t.view();
    let mut out = [0.0f32; K];
    let mut scratch = [0.0f32; C];
    let mut batch = [[0.0f32; K]; 2];
    let xs = [*x, *x];
    let os = [objectness, objectness];
    let (Ok(fast), Ok(libm)) = (fast, libm) else {
        let error = invariants::expected_error(x, objectness).expect("an error was expected");
        assert_eq!(
            dynt.open_into::<FastMath>(x, objectness, &mut out, &mut scratch),
            Err(error),
            "{what}: DynTable"
        );
        assert_eq!(
            view.score_into(Head::Open, x, objectness, &mut out, &mut scratch),
            Err(error),
            "{what}: score_into"
        );
        assert_eq!(
            t.open_batch(&xs, Some(&os), &mut batch),
            Err(BatchError::Row { index: 0, error }),
            "{what}: open_batch"
        );
        return;
    };
    let mut want = [0.0f64; K];
    let mut s64 = [0.0f64; C];
    assert!(
        invariants::open_reference(&head, &params, x, objectness, &mut want, &mut s64).is_some(),
        "{what}: the reference refused the lengths"
    );
    for (name, s) in [("FastMath", &fast.0), ("Libm", &libm.0)] {
        must(
            invariants::check_scores(s, objectness, Sum::AtMost),
            format_args!("{what}: {name} {s:?}"),
        );
        must(
            invariants::check_open_decision(s, x),
            format_args!("{what}: {name} {s:?}"),
        );
        if let Some(i) = invariants::open_mismatch(&head, &params, x, s, &want, objectness) {
            panic!(
                "{what}: {name} score {i} of {s:?} is not the formula's {want:?} within a relative {:e}",
                invariants::open_score_tolerance(&head, &params, x)
            );
        }
    }
    let bits = |s: &[f32; K]| s.map(f32::to_bits);
    // epsilon 0 and no background category: q = 1 exactly, the temperature layer.
    if params.epsilon() == 0.0 && C == K {
        for (name, got, want) in [
            (
                "FastMath",
                fast,
                mlmap::baseline::temperature::<FastMath, K>(x, params.temperature(), objectness),
            ),
            (
                "Libm",
                libm,
                mlmap::baseline::temperature::<Libm, K>(x, params.temperature(), objectness),
            ),
        ] {
            let want = want.expect("valid inputs");
            assert_eq!(
                bits(&got.0),
                bits(&want.0),
                "{what}: {name} epsilon 0 without background is not the temperature layer"
            );
        }
    }
    dynt.open_into::<FastMath>(x, objectness, &mut out, &mut scratch)
        .expect("valid");
    assert_eq!(bits(&out), bits(&fast.0), "{what}: DynTable differs");
    dynt.open_into::<Libm>(x, objectness, &mut out, &mut scratch)
        .expect("valid");
    assert_eq!(bits(&out), bits(&libm.0), "{what}: DynTable Libm differs");
    view.score_into(Head::Open, x, objectness, &mut out, &mut scratch)
        .expect("valid");
    assert_eq!(bits(&out), bits(&fast.0), "{what}: score_into differs");
    t.open_batch(&xs, Some(&os), &mut batch)
        .expect("valid rows");
    assert_eq!(bits(&batch[1]), bits(&fast.0), "{what}: open_batch differs");
}

/// DESIGN §1.8: raising epsilon never raises a score, with either backend, not even by a
/// rounding step. `low` and `high` are one table with two epsilons, `high`'s the larger.
pub fn check_open_monotone<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    low: &Table<K, B_ML, B_MAP, BB, C>,
    high: &Table<K, B_ML, B_MAP, BB, C>,
    x: &[f32; K],
    objectness: f32,
) {
    let (lo, hi) = match (low.open_params(), high.open_params()) {
        (Some(a), Some(b)) => (a, b),
        _ => panic!("both tables must have the open head"),
    };
    assert!(
        lo.epsilon() <= hi.epsilon() && lo.temperature() == hi.temperature(),
        "{lo:?} vs {hi:?}"
    );
    for (name, a, b) in [
        (
            "FastMath",
            low.open(x, objectness),
            high.open(x, objectness),
        ),
        (
            "Libm",
            low.open_with::<Libm>(x, objectness),
            high.open_with::<Libm>(x, objectness),
        ),
    ] {
        let (Ok(a), Ok(b)) = (a, b) else {
            assert_eq!(
                a.err(),
                b.err(),
                "{name}: the two epsilons give other errors"
            );
            continue;
        };
        for (i, (sa, sb)) in a.0.iter().zip(&b.0).enumerate() {
            assert!(
                sb <= sa,
                "{name}: class {i}: epsilon {:e} gives {sa:e}, the larger {:e} gives {sb:e}; x = {x:?}, OS = {objectness:e}, T = {:e}",
                lo.epsilon(),
                hi.epsilon(),
                lo.temperature()
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// Recalibration maps (DESIGN §1.9)
// ---------------------------------------------------------------------------------------

/// One arbitrary map: mostly knots built to the rule (x from positive steps normalised
/// to end at 1, y from non-negative steps), sometimes knots of any bits.
#[derive(Arbitrary, Debug, Clone)]
pub enum ArbKnots {
    /// Steps in x and y: knot `i` is at the running sums, x scaled to end at 1.
    Steps(Vec<(u8, u8)>, u8),
    /// Any `(x, y)` bit patterns.
    Bits(Vec<(u32, u32)>),
}

impl ArbKnots {
    /// The knots.
    pub fn knots(&self) -> Vec<mlmap::Knot> {
        match self {
            Self::Steps(steps, y0) => {
                let total: f32 = steps.iter().map(|&(dx, _)| f32::from(dx)).sum();
                let (mut x, mut y) = (0.0f32, f32::from(*y0) / 255.0);
                let mut out = vec![mlmap::Knot { x: 0.0, y }];
                for (i, &(dx, dy)) in steps.iter().enumerate() {
                    x += f32::from(dx);
                    y = (y + f32::from(dy) / 1024.0).min(1.0);
                    let at = if i + 1 == steps.len() { 1.0 } else { x / total };
                    out.push(mlmap::Knot { x: at, y });
                }
                out
            }
            Self::Bits(b) => b
                .iter()
                .map(|&(x, y)| mlmap::Knot {
                    x: f32::from_bits(x),
                    y: f32::from_bits(y),
                })
                .collect(),
        }
    }
}

/// An arbitrary map for each head (or none).
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbMaps(pub [Option<ArbKnots>; 4]);

/// The heads in the order of [`ArbMaps`].
pub const MAP_HEADS: [Head; 4] = [Head::Ml, Head::Map, Head::Bayes, Head::Open];

impl ArbMaps {
    /// `table` with the maps `DynTable::with_map` accepts; each is accepted exactly
    /// when `RecalMap::new` accepts its knots and the table has the head. The table
    /// round-trips through its bytes (version 4 when it holds a map) and its maps are
    /// stored bit for bit.
    pub fn attach(&self, table: &DynTable) -> DynTable {
        let mut t = table.clone();
        for (head, knots) in MAP_HEADS.iter().zip(&self.0) {
            let Some(k) = knots else { continue };
            let knots = k.knots();
            let has = match head {
                Head::Ml | Head::Map => true,
                Head::Bayes => t.bayes().is_some(),
                Head::Open => t.open().is_some(),
            };
            let valid = mlmap::RecalMap::new(&knots).is_ok() && has;
            match t.clone().with_map(*head, knots.clone()) {
                Ok(with) => {
                    assert!(valid, "with_map({head}) accepted {knots:?}");
                    let g = with.recal_map(*head).expect("the map is held");
                    let same = g.knots().iter().zip(&knots).all(|(a, b)| {
                        a.x.to_bits() == b.x.to_bits() && a.y.to_bits() == b.y.to_bits()
                    });
                    assert!(
                        same && g.knots().len() == knots.len(),
                        "{head}: map not stored"
                    );
                    t = with;
                }
                Err(e) => assert!(!valid, "with_map({head}) refused {knots:?}: {e}"),
            }
        }
        let bytes = t.to_vec().expect("a table with maps encodes");
        let back = DynTable::from_bytes(&bytes).expect("its encoding decodes");
        assert_eq!(back, t, "maps changed through the bytes");
        let any = MAP_HEADS.iter().any(|&h| t.recal_map(h).is_some());
        assert_eq!(
            bytes.get(4) == Some(&4),
            any,
            "format version 4 iff a map is held"
        );
        let plain = t.clone().without_maps().to_vec().expect("encodes");
        assert_eq!(
            plain,
            table.clone().without_maps().to_vec().expect("encodes")
        );
        t
    }
}

/// One detection on a table with maps, every head it has: the same error as without
/// the maps, or the mapped top is `g(top)` of the head's own top, every other score
/// is strictly below it, the scores keep the head's order and its decision; a
/// fixed-size `Table` with room for the maps gives the same bits.
pub fn check_mapped_detection<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    mapped: &DynTable,
    fixed: &Table<K, B_ML, B_MAP, BB, C, { mlmap::MAX_KNOTS }>,
    x: &[f32; K],
    os: f32,
) {
    let raw = mapped.clone().without_maps();
    for head in MAP_HEADS {
        let (mut m, mut r, mut scratch) = ([0.0f32; K], [0.0f32; K], vec![0.0f32; K + 1]);
        let got = mapped.view().score_into(head, x, os, &mut m, &mut scratch);
        let own = raw.view().score_into(head, x, os, &mut r, &mut scratch);
        assert_eq!(got, own, "{head}: mapped and own results differ");
        let mut fm = [0.0f32; K];
        let f = fixed.view().score_into(head, x, os, &mut fm, &mut scratch);
        assert_eq!(f, got, "{head}: Table and DynTable results differ");
        if got.is_err() {
            continue;
        }
        assert_eq!(
            fm.map(f32::to_bits),
            m.map(f32::to_bits),
            "{head}: Table differs"
        );
        let Some(g) = mapped.recal_map(head) else {
            assert_eq!(m.map(f32::to_bits), r.map(f32::to_bits), "{head}: no map");
            continue;
        };
        let top = r.iter().fold(0.0f32, |a, &v| a.max(v));
        if top == 0.0 {
            assert!(
                m.iter().all(|&v| v == 0.0),
                "{head}: zero scores mapped to {m:?}"
            );
            continue;
        }
        let gt = g.eval(top);
        for i in 0..K {
            if r[i] == top {
                assert_eq!(
                    m[i].to_bits(),
                    gt.to_bits(),
                    "{head}: top {top} -> {} != g = {gt}",
                    m[i]
                );
            } else {
                assert!(
                    m[i] < gt && m[i] >= 0.0,
                    "{head}: score {i} {} not below g(top) {gt}",
                    m[i]
                );
            }
            for j in 0..K {
                if r[i] >= r[j] {
                    assert!(m[i] >= m[j], "{head}: order of {i}, {j}: {r:?} -> {m:?}");
                }
            }
        }
        assert_eq!(
            mlmap::decide(&m, x),
            mlmap::decide(&r, x),
            "{head}: decision changed"
        );
    }
}

/// Detections read from `u` on `table` given the arbitrary maps `maps`.
pub fn check_detections_with_maps<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    table: &Table<K, B_ML, B_MAP, BB, C>,
    maps: &ArbMaps,
    u: &mut Unstructured<'_>,
) {
    let mapped = maps.attach(&DynTable::from_table(table));
    let bytes = mapped.to_vec().expect("encodes");
    let fixed = Table::<K, B_ML, B_MAP, BB, C, { mlmap::MAX_KNOTS }>::from_bytes(&bytes)
        .expect("a table type with room for the maps decodes them");
    for_detections(table, u, |x, os| {
        check_mapped_detection(&mapped, &fixed, x, os)
    });
}
