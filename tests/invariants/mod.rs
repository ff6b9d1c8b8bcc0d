//! One property per invariant of DESIGN §1.3, on random valid tables of four shapes
//! (`Table<2, 1, 1>`, `Table<3, 22, 17>`, `Table<5, 7, 30>`, and `Table<7, 3, 2>`, a K
//! whose sums of equal masses do not always add up exactly) and random inputs.
//!
//! Tables have random edges (zero, tiny and large offsets, spans from 1e-2 to 1e4),
//! frequencies with exact zeros and weights over 30 decades, means inside and outside
//! the support, variances from the floor (1e-12) to 1e6, lambdas from 1e-12 to the
//! maximum and, now and then, the smallest normal and subnormal lambdas, and both tail
//! policies. Logits are inside the support, exactly on edges, near the prior's mean,
//! arbitrary (finite, huge, subnormal, ±0) or infinite; objectness is 0, 1, anything in
//! between or subnormal. Every case asserts its invariant. The case count is proptest's
//! default (256), or `PROPTEST_CASES`.
//!
//! Invariant 3 ("raising `L_i` with everything else fixed never lowers score `i`") is
//! realised three ways, each documented at its function: (a) ML, class `i`'s logit
//! moved between two bins, the other logits fixed (the ML mass depends on `L_i` only);
//! (b) both heads, two tables that differ only in the frequency of the bin holding
//! class `i`'s logit, so that `P_i` and every other input stay fixed; (c) class `i`'s
//! logit moved from outside its support (`L_i = 0`, mass `lambda` whatever `P_i`) to
//! anywhere.
//!
//! The invariants themselves are checked by `mlmap::invariants`, which the fuzz targets
//! use too; this file builds the cases.

use mlmap::invariants::{
    check_error, check_monotone, check_scores, check_table, check_unknown, expected_error, Sum,
    Violation,
};
use mlmap::{
    BatchError, ClassSpec, DecodeError, EdgeMode, InferError, Settings, Table, TableError,
    UpperTail,
};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

use crate::support::fix_crc;

/// A violated invariant as a proptest failure (so that the case is shrunk), with the
/// context the checker does not know.
fn holds(r: Result<(), Violation>, context: impl FnOnce() -> String) -> Result<(), TestCaseError> {
    r.map_err(|v| TestCaseError::fail(format!("{}: {v}", context())))
}

const NAMES: [&str; 7] = [
    "car",
    "cyclist",
    "pedestrian",
    "truck",
    "bus",
    "van",
    "tram",
];

/// One histogram before validation.
#[derive(Debug, Clone)]
struct HistParams {
    lo: f32,
    hi: f32,
    freqs: Vec<f32>,
}

/// One class before validation.
#[derive(Debug, Clone)]
struct ClassParams {
    rows: u64,
    mean: f32,
    variance: f32,
    ml: HistParams,
    map: HistParams,
}

/// Everything a table is built from, kept so that a property can rebuild the table with
/// exactly one thing changed.
#[derive(Debug, Clone)]
struct Params {
    settings: Settings,
    classes: Vec<ClassParams>,
}

fn array<const B: usize>(v: &[f32]) -> [f32; B] {
    v.try_into().expect("bin count of the shape")
}

impl Params {
    fn build<const K: usize, const BM: usize, const BP: usize>(
        &self,
    ) -> Result<Table<K, BM, BP>, TableError> {
        let specs = std::array::from_fn(|i| {
            let c = &self.classes[i];
            ClassSpec {
                name: NAMES[i],
                rows: c.rows,
                mean: c.mean,
                variance: c.variance,
                ml_range: (c.ml.lo, c.ml.hi),
                ml_freqs: array::<BM>(&c.ml.freqs),
                map_range: (c.map.lo, c.map.hi),
                map_freqs: array::<BP>(&c.map.freqs),
            }
        });
        Table::from_parts(self.settings, specs)
    }
}

/// `10^e` for `e` uniform in `[lo, hi)`: values spread over decades.
fn decades(lo: f64, hi: f64) -> impl Strategy<Value = f32> {
    (lo..hi).prop_map(|e| 10f64.powf(e) as f32)
}

fn signed(s: impl Strategy<Value = f32>) -> impl Strategy<Value = f32> {
    (any::<bool>(), s).prop_map(|(neg, v)| if neg { -v } else { v })
}

fn hist(bins: usize) -> impl Strategy<Value = HistParams> {
    let lo = prop_oneof![1 => Just(0.0f32), 4 => signed(decades(-3.0, 4.0))];
    let span = decades(-2.0, 4.0);
    // One u32 per bin (cheap to generate and shrink): a quarter of the bins empty, one
    // in eight with a weight anywhere in 30 decades, the others uniform in [0, 1).
    let weight = |bits: u32| {
        let u = f64::from(bits >> 3) / f64::from(1u32 << 29);
        match bits & 7 {
            0 | 1 => 0.0,
            2 => 10f64.powf(-30.0 * u),
            _ => u,
        }
    };
    let weights = prop::collection::vec(any::<u32>(), bins)
        .prop_map(move |bits| bits.into_iter().map(weight).collect::<Vec<f64>>());
    (lo, span, weights, 0..bins).prop_map(|(lo, span, mut w, one)| {
        if w.iter().sum::<f64>() == 0.0 {
            w[one] = 1.0;
        }
        let total: f64 = w.iter().sum();
        HistParams {
            lo,
            hi: lo + span,
            freqs: w.iter().map(|v| (v / total) as f32).collect(),
        }
    })
}

fn class(bins_ml: usize, bins_map: usize) -> impl Strategy<Value = ClassParams> {
    (
        hist(bins_ml),
        hist(bins_map),
        any::<bool>(),
        prop_oneof![Just(None), (-0.5f64..1.5).prop_map(Some)],
        signed(decades(-3.0, 4.0)),
        decades(-12.0, 6.0),
        any::<u64>(),
    )
        .prop_map(|(ml, map, same_range, at, far_mean, variance, rows)| {
            // A fit gives both heads the same range; allow independent ranges too.
            let mut map = map;
            if same_range {
                (map.lo, map.hi) = (ml.lo, ml.hi);
            }
            // The mean inside (or near) the support, or anywhere.
            let mean = match at {
                Some(u) => (f64::from(ml.lo) + u * f64::from(ml.hi - ml.lo)) as f32,
                None => far_mean,
            };
            ClassParams {
                rows,
                mean,
                variance,
                ml,
                map,
            }
        })
}

fn lambda() -> impl Strategy<Value = f32> {
    prop_oneof![
        8 => decades(-12.0, 6.0),
        1 => Just(f32::MIN_POSITIVE),
        1 => Just(f32::from_bits(1)),
    ]
}

fn params(k: usize, bins_ml: usize, bins_map: usize) -> impl Strategy<Value = Params> {
    let tail = prop_oneof![Just(UpperTail::Zero), Just(UpperTail::Clamp)];
    let mode = prop_oneof![Just(EdgeMode::Linspace), Just(EdgeMode::Matlab)];
    (
        lambda(),
        lambda(),
        tail,
        mode,
        prop::collection::vec(class(bins_ml, bins_map), k),
    )
        .prop_map(
            |(lambda_ml, lambda_map, upper_tail, edge_mode, classes)| Params {
                settings: Settings {
                    lambda_ml,
                    lambda_map,
                    edge_mode,
                    upper_tail,
                },
                classes,
            },
        )
}

/// A random valid table and the parameters it was built from.
fn table<const K: usize, const BM: usize, const BP: usize>(
) -> impl Strategy<Value = (Params, Table<K, BM, BP>)> {
    params(K, BM, BP).prop_filter_map("parameters must make a valid table", |p| {
        p.build::<K, BM, BP>().ok().map(|t| (p, t))
    })
}

/// How to pick one class's logit, resolved against the table.
#[derive(Debug, Clone, Copy)]
enum Logit {
    /// `lo + u (hi - lo)` of the ML (`true`) or MAP histogram.
    Support(bool, f64),
    /// Edge `k mod (B + 1)` of the ML or MAP histogram.
    Edge(bool, usize),
    /// `mean + z sigma`.
    Prior(f64),
    /// Any non-NaN `f32`: ±0, subnormal, normal, huge, ±inf.
    Raw(f32),
}

fn logit() -> impl Strategy<Value = Logit> {
    use proptest::num::f32 as f;
    let raw = f::POSITIVE | f::NEGATIVE | f::NORMAL | f::SUBNORMAL | f::ZERO | f::INFINITE;
    prop_oneof![
        4 => (any::<bool>(), -0.2f64..1.2).prop_map(|(ml, u)| Logit::Support(ml, u)),
        2 => (any::<bool>(), 0usize..64).prop_map(|(ml, k)| Logit::Edge(ml, k)),
        1 => (-8.0f64..8.0).prop_map(Logit::Prior),
        2 => raw.prop_map(Logit::Raw),
        1 => prop_oneof![
            Just(f32::INFINITY),
            Just(f32::NEG_INFINITY),
            Just(f32::MAX),
            Just(f32::MIN),
            Just(1e-40f32),
            Just(-1e-40f32),
        ]
        .prop_map(Logit::Raw),
    ]
}

fn resolve<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
    class: usize,
    l: Logit,
) -> f32 {
    let range = |ml: bool| {
        if ml {
            let h = t.ml_histograms().get(class).unwrap();
            (h.lo(), h.hi(), h.bins())
        } else {
            let h = t.map_histograms().get(class).unwrap();
            (h.lo(), h.hi(), h.bins())
        }
    };
    match l {
        Logit::Support(ml, u) => {
            let (lo, hi, _) = range(ml);
            (f64::from(lo) + u * (f64::from(hi) - f64::from(lo))) as f32
        }
        Logit::Edge(ml, k) => {
            let (_, _, bins) = range(ml);
            let k = k % (bins + 1);
            if ml {
                t.ml_histograms().get(class).unwrap().edge(k)
            } else {
                t.map_histograms().get(class).unwrap().edge(k)
            }
        }
        Logit::Prior(z) => {
            let g = t.priors().get(class).unwrap();
            (f64::from(g.mean()) + z * f64::from(g.variance()).sqrt()) as f32
        }
        Logit::Raw(v) => v,
    }
}

fn logits<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
    recipe: &[Logit; K],
) -> [f32; K] {
    std::array::from_fn(|i| resolve(t, i, recipe[i]))
}

fn objectness() -> impl Strategy<Value = f32> {
    prop_oneof![
        1 => Just(0.0f32),
        1 => Just(1.0f32),
        4 => 0.0f32..=1.0,
        1 => proptest::num::f32::POSITIVE | proptest::num::f32::SUBNORMAL,
        1 => Just(1.0f32.next_down()),
    ]
}

/// The heads under test: ML, MAP with `Libm`, MAP with `FastMath`, and MAP with
/// `Micromath` when built.
fn heads<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
    x: &[f32; K],
    os: f32,
) -> Vec<(&'static str, Result<[f32; K], InferError>)> {
    let heads = [
        ("ML", t.ml(x, os).map(|s| s.0)),
        ("MAP", t.map(x, os).map(|s| s.0)),
        (
            "MAP FastMath",
            t.map_with::<mlmap::FastMath>(x, os).map(|s| s.0),
        ),
    ];
    #[cfg(feature = "micromath")]
    let micromath = Some((
        "MAP Micromath",
        t.map_with::<mlmap::Micromath>(x, os).map(|s| s.0),
    ));
    #[cfg(not(feature = "micromath"))]
    let micromath = None;
    heads.into_iter().chain(micromath).collect()
}

/// Invariant 1: every score in `[0, OS]`, the scores summing to `OS` (relative 1e-5).
mod properties;
use properties::*;

macro_rules! properties {
    ($($module:ident: $k:literal, $bm:literal, $bp:literal;)*) => {$(
        mod $module {
            use super::*;

            type T = Table<$k, $bm, $bp>;

            proptest! {
                #[test]
                fn invariant_1_scores_in_range_and_sum_to_os(
                    (_, t) in table::<$k, $bm, $bp>(),
                    recipe in proptest::array::uniform::<_, $k>(logit()),
                    os in objectness(),
                ) {
                    let x = logits(&t, &recipe);
                    scores_in_range_and_sum_to_os(&t, &x, os)?;
                }

                #[test]
                fn invariant_2_out_of_support_is_exactly_os_over_k(
                    (_, t) in table::<$k, $bm, $bp>(),
                    picks in proptest::array::uniform::<_, $k>((any::<u8>(), 0.0f32..10.0)),
                    os in objectness(),
                ) {
                    out_of_support_is_os_over_k(&t, &picks, os)?;
                }

                #[test]
                fn invariant_3_ml_score_follows_likelihood(
                    (_, t) in table::<$k, $bm, $bp>(),
                    recipe in proptest::array::uniform::<_, $k>(logit()),
                    i in 0..$k as usize,
                    alt in logit(),
                    os in objectness(),
                ) {
                    let x = logits(&t, &recipe);
                    let alt = resolve(&t, i, alt);
                    ml_score_follows_likelihood(&t, &x, i, alt, os)?;
                }

                #[test]
                fn invariant_3_evidence_never_lowers_score(
                    (_, t) in table::<$k, $bm, $bp>(),
                    recipe in proptest::array::uniform::<_, $k>(logit()),
                    i in 0..$k as usize,
                    pick in any::<u8>(),
                    os in objectness(),
                ) {
                    let x = logits(&t, &recipe);
                    evidence_never_lowers_score(&t, &x, i, pick, os)?;
                }

                #[test]
                fn invariant_4_bad_inputs_are_errors(
                    (_, t) in table::<$k, $bm, $bp>(),
                    recipe in proptest::array::uniform::<_, $k>(logit()),
                    nan_at in proptest::array::uniform::<_, $k>(prop::bool::weighted(0.3)),
                    nan_bits in any::<u32>(),
                    bad_os in bad_objectness(),
                    good_os in objectness(),
                ) {
                    let x = logits(&t, &recipe);
                    bad_inputs_are_errors(&t, &x, &nan_at, nan_bits, bad_os, good_os)?;
                }

                #[test]
                fn invariant_5_random_bytes_decode_safely(
                    body in prop::collection::vec(any::<u8>(), 0..800),
                    header in any::<bool>(),
                    crc in any::<bool>(),
                ) {
                    // Raw bytes, or bytes after a valid header of this shape (so that
                    // parsing goes past the header), with or without a valid CRC.
                    let mut bytes = Vec::new();
                    if header {
                        bytes.extend_from_slice(b"MLMP\x01");
                        for v in [$k as u16, $bm, $bp] {
                            let mut v = v;
                            while v >= 0x80 {
                                bytes.push((v as u8) | 0x80);
                                v >>= 7;
                            }
                            bytes.push(v as u8);
                        }
                    }
                    bytes.extend_from_slice(&body);
                    if crc {
                        bytes = crate::support::with_crc(&bytes);
                    }
                    decode_is_safe::<$k, $bm, $bp>(&bytes)?;
                    #[cfg(feature = "std")]
                    let _ = mlmap::host::DynTable::from_bytes(&bytes);
                }

                #[test]
                fn invariant_5_mutated_encodings_decode_safely(
                    (_, t) in table::<$k, $bm, $bp>(),
                    edits in prop::collection::vec(mutation(), 1..4),
                ) {
                    mutated_encoding_is_safe::<$k, $bm, $bp>(&t, &edits)?;
                }

                #[test]
                fn round_trip_of_random_tables_is_exact((p, t) in table::<$k, $bm, $bp>()) {
                    let mut buf = vec![0u8; T::MAX_ENCODED_LEN];
                    let bytes = t.to_slice(&mut buf).unwrap().to_vec();
                    let back = T::from_bytes(&bytes).unwrap();
                    prop_assert_eq!(&back, &t);
                    prop_assert_eq!(back.to_slice(&mut buf).unwrap(), &bytes[..]);
                    // The stored values are exactly the ones the table was built from.
                    for (c, cp) in p.classes.iter().enumerate() {
                        let spec = back.spec(c).unwrap();
                        prop_assert_eq!(spec.ml_freqs, &cp.ml.freqs[..]);
                        prop_assert_eq!(spec.map_freqs, &cp.map.freqs[..]);
                        prop_assert_eq!(spec.ml_range, (cp.ml.lo, cp.ml.hi));
                        prop_assert_eq!(spec.map_range, (cp.map.lo, cp.map.hi));
                        prop_assert_eq!(spec.rows, cp.rows);
                        prop_assert_eq!(spec.mean.to_bits(), cp.mean.to_bits());
                        prop_assert_eq!(spec.variance.to_bits(), cp.variance.to_bits());
                    }
                    assert_table_invariants(&back)?;
                }
            }
        }
    )*};
}

properties! {
    k2_b1_b1: 2, 1, 1;
    k3_b22_b17: 3, 22, 17;
    k5_b7_b30: 5, 7, 30;
    k7_b3_b2: 7, 3, 2;
}

/// Construction (b) of invariant 3 needs two bins in a head; `Table<2, 1, 1>` is
/// covered by constructions (a) and (c).
macro_rules! raised_bin_properties {
    ($($module:ident: $k:literal, $bm:literal, $bp:literal;)*) => {$(
        mod $module {
            use super::*;

            proptest! {
                #[test]
                fn invariant_3_raised_bin_never_lowers_score(
                    (p, t) in table::<$k, $bm, $bp>(),
                    recipe in proptest::array::uniform::<_, $k>(logit()),
                    i in 0..$k as usize,
                    ml_head in any::<bool>(),
                    (k, m) in (any::<usize>(), any::<usize>()),
                    share in prop_oneof![Just(1.0f32), 0.0f32..1.0],
                    os in objectness(),
                ) {
                    let x = logits(&t, &recipe);
                    raised_bin_never_lowers_score(&p, &t, &x, i, ml_head, k, m, share, os)?;
                }
            }
        }
    )*};
}

raised_bin_properties! {
    k3_b22_b17_raised_bin: 3, 22, 17;
    k5_b7_b30_raised_bin: 5, 7, 30;
    k7_b3_b2_raised_bin: 7, 3, 2;
}

/// The Bayes head (DESIGN §1.6): random heads fitted from random counts, attached to the
/// random tables above (`DynTable::with_bayes`) and converted to fixed shapes
/// (`Table::try_from`), one property per invariant of §1.6.
///
/// A head is built as `fit` builds it (`host/src/fit/bayes.rs`): random training rows per
/// category (1 to 30, each row a bin per logit, so bins are often empty), their counts,
/// and the terms `ln(count / n_c + lambda)` computed in `f64` and rounded to `f32`;
/// lambda from 1e-6 to 1; the row counts scaled by 1, 1000 or 1e12 (the same
/// frequencies, other priors' magnitudes). Shapes: K from 2 to 5, 1 to 8 bins, with and
/// without `background`.
///
/// FastMath against Libm: the two compute the same `f32` log-scores and differ only in
/// `exp`, whose results for the largest category are exactly 1 in both; the other
/// categories' masses stand in a ratio within `[(1 - e_F)/(1 + e_L), (1 + e_F)/(1 - e_L)]`
/// (`e_F = FAST_MATH_MAX_REL_ERROR`, `e_L = 8e-8`), and the normalisation rounds
/// `C + 1` times per backend. That is the setting of `fast_math_max_score_error(k)` with
/// `k = C` categories (which allows three roundings per mass and `k + 3` in the
/// normalisation, more than the Bayes head's), so the bound asserted is
/// `fast_math_max_score_error(C) * OS`, plus `OS * f32::MIN_POSITIVE` for masses below
/// the normal range (absolute rounding `2^-149` on a total of at least 1) and two
/// subnormal steps for subnormal scores.
#[cfg(feature = "std")]
pub(crate) mod bayes;
/// Random Bayes heads and the tables built from them.
#[cfg(feature = "std")]
pub(crate) mod bayes_tables;
