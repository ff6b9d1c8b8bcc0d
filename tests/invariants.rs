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
fn scores_in_range_and_sum_to_os<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
    x: &[f32; K],
    os: f32,
) -> Result<(), TestCaseError> {
    for (head, scores) in heads(t, x, os) {
        let scores = scores.map_err(|e| TestCaseError::fail(format!("{head}: {e:?}")))?;
        // The sum's tolerance includes one subnormal step per score: below OS ~ 1e-39
        // each score carries that much rounding, which the relative bound cannot absorb.
        holds(check_scores(&scores, os, Sum::Equal), || {
            format!("{head} for {x:?}: {scores:?}")
        })?;
    }
    // The FastMath backend stays within its documented distance of Libm (for lambdas
    // that are not negligible against the prior; see the `FastMath` docs).
    if t.settings().lambda_map >= 1e-13 {
        let exact = t.map(x, os).unwrap();
        let fast = t.map_with::<mlmap::FastMath>(x, os).unwrap();
        for (a, b) in exact.0.iter().zip(fast.0) {
            prop_assert!(
                (a - b).abs() <= mlmap::FAST_MATH_MAX_SCORE_ERROR * os + 1e-6 * os,
                "FastMath {b} vs Libm {a} for {x:?}, OS {os}"
            );
        }
    }
    Ok(())
}

/// A logit outside class `c`'s support under both heads (below `e_0`, or above `e_B`
/// when the tail policy is the zero tail); `pick` chooses among the possibilities.
fn outside<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
    c: usize,
    pick: u8,
    u: f32,
) -> f32 {
    let (ml, map) = (
        t.ml_histograms().get(c).unwrap(),
        t.map_histograms().get(c).unwrap(),
    );
    let lo = ml.lo().min(map.lo());
    let hi = ml.hi().max(map.hi());
    let below = (lo - (hi - lo) * u).min(lo.next_down());
    let above = (hi + (hi - lo) * u).max(hi.next_up());
    let zero_tail = t.settings().upper_tail == UpperTail::Zero;
    match pick % 6 {
        0 => f32::NEG_INFINITY,
        1 => lo.next_down(),
        2 => below,
        3 if zero_tail => f32::INFINITY,
        4 if zero_tail => hi.next_up(),
        5 if zero_tail => above,
        _ => f32::MIN,
    }
}

/// Invariant 2: outside every class's support, exactly `OS / K` under both heads.
fn out_of_support_is_os_over_k<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
    picks: &[(u8, f32); K],
    os: f32,
) -> Result<(), TestCaseError> {
    let x: [f32; K] = std::array::from_fn(|c| outside(t, c, picks[c].0, picks[c].1));
    for (head, scores) in heads(t, &x, os) {
        let scores = scores.map_err(|e| TestCaseError::fail(format!("{head}: {e:?}")))?;
        holds(check_unknown(&scores, os), || format!("{head} for {x:?}"))?;
    }
    Ok(())
}

/// Invariant 3, construction (a), ML head: class `i`'s logit moves between two values
/// `xa`, `xb`, all other logits fixed. The ML mass of class `i` depends only on `L_i`,
/// so this changes `L_i` and nothing else: the score must follow `L_i`'s order, and
/// equal likelihoods give bit-identical scores.
fn ml_score_follows_likelihood<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
    x: &[f32; K],
    i: usize,
    alt: f32,
    os: f32,
) -> Result<(), TestCaseError> {
    let tail = t.settings().upper_tail;
    let h = t.ml_histograms().get(i).unwrap();
    let (mut xa, mut xb) = (*x, *x);
    xb[i] = alt;
    let (la, lb) = (h.likelihood(xa[i], tail), h.likelihood(xb[i], tail));
    if la > lb {
        std::mem::swap(&mut xa, &mut xb);
    }
    let (sa, sb) = (t.ml(&xa, os).unwrap().0[i], t.ml(&xb, os).unwrap().0[i]);
    holds(check_monotone(i, sa, sb), || {
        format!("L {la} / {lb} for {xa:?} / {xb:?}")
    })?;
    if la == lb {
        prop_assert_eq!(sa.to_bits(), sb.to_bits());
    }
    Ok(())
}

/// Invariant 3, construction (b), both heads: two tables that differ only in class
/// `i`'s frequency of bin `k` of one head, raised by moving mass from another bin `m`
/// of the same histogram (so both still sum to 1). The logit of class `i` sits on edge
/// `e_k`, which opens bin `k` in both tables, so `L_i` rises and every other input of
/// the formula (`P_i`, which depends only on the mean and variance; every `L_j`, `P_j`
/// for `j != i`; lambda; OS) is identical. The other bins of class `i` are not read for
/// this logit, so moving mass between them is not a change of "everything else".
/// Score `i` of the changed head must not drop, and the untouched head must not move.
#[allow(clippy::too_many_arguments)]
fn raised_bin_never_lowers_score<const K: usize, const BM: usize, const BP: usize>(
    p: &Params,
    t: &Table<K, BM, BP>,
    x: &[f32; K],
    i: usize,
    ml_head: bool,
    k: usize,
    m: usize,
    share: f32,
    os: f32,
) -> Result<(), TestCaseError> {
    let bins = if ml_head { BM } else { BP };
    assert!(
        bins >= 2,
        "the construction needs a second bin to take mass from"
    );
    let k = k % bins;
    let m = (k + 1 + m % (bins - 1)) % bins;
    let mut raised = p.clone();
    let h = if ml_head {
        &mut raised.classes[i].ml
    } else {
        &mut raised.classes[i].map
    };
    let moved = h.freqs[m] * share;
    h.freqs[m] -= moved;
    h.freqs[k] += moved;
    let Ok(t2) = raised.build::<K, BM, BP>() else {
        // Rounding pushed the sum out of tolerance: not a valid pair of tables.
        return Err(TestCaseError::reject(
            "rebuilt frequencies out of tolerance",
        ));
    };
    let mut x = *x;
    x[i] = if ml_head {
        t.ml_histograms().get(i).unwrap().edge(k)
    } else {
        t.map_histograms().get(i).unwrap().edge(k)
    };
    let (before, after) = if ml_head {
        (t.ml(&x, os).unwrap(), t2.ml(&x, os).unwrap())
    } else {
        (t.map(&x, os).unwrap(), t2.map(&x, os).unwrap())
    };
    holds(check_monotone(i, before.0[i], after.0[i]), || {
        format!("bin {k} raised by {moved} for {x:?}")
    })?;
    let (same_before, same_after) = if ml_head {
        (t.map(&x, os).unwrap(), t2.map(&x, os).unwrap())
    } else {
        (t.ml(&x, os).unwrap(), t2.ml(&x, os).unwrap())
    };
    prop_assert_eq!(same_before, same_after);
    Ok(())
}

/// Invariant 3, construction (c), MAP head (and ML): class `i`'s logit moves from
/// outside its support (`L_i = 0`, so its mass is `0 * P_i + lambda = lambda` whatever
/// `P_i` is) to anywhere. That is `L_i` raised from 0 with `P_i` taken at the new
/// logit, everything else fixed; the score must not drop.
fn evidence_never_lowers_score<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
    x: &[f32; K],
    i: usize,
    pick: u8,
    os: f32,
) -> Result<(), TestCaseError> {
    let mut none = *x;
    none[i] = outside(t, i, pick, 0.5);
    for (head, with, without) in [
        ("ML", t.ml(x, os), t.ml(&none, os)),
        ("MAP", t.map(x, os), t.map(&none, os)),
    ] {
        let (with, without) = (with.unwrap().0[i], without.unwrap().0[i]);
        holds(check_monotone(i, without, with), || {
            format!("{head}: likelihood raised from 0, {none:?} -> {x:?}")
        })?;
    }
    Ok(())
}

/// Invariant 4: a NaN logit, or an objectness that is NaN or outside [0, 1], is an
/// error (the first NaN class for logits), never a panic or a NaN score; also in batches.
fn bad_inputs_are_errors<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
    x: &[f32; K],
    nan_at: &[bool; K],
    nan_bits: u32,
    bad_os: f32,
    good_os: f32,
) -> Result<(), TestCaseError> {
    // Any NaN: exponent all ones, non-zero mantissa, either sign.
    let nan = f32::from_bits(0x7f80_0000 | (nan_bits & 0x807f_ffff) | 1);
    prop_assert!(nan.is_nan());
    let mut with_nan = *x;
    for (v, &n) in with_nan.iter_mut().zip(nan_at) {
        if n {
            *v = nan;
        }
    }
    match nan_at.iter().position(|&n| n) {
        Some(first) => {
            let want = InferError::NanLogit {
                class: first as u16,
            };
            prop_assert_eq!(expected_error(&with_nan, good_os), Some(want));
            for (head, got) in heads(t, &with_nan, good_os) {
                holds(check_error(&with_nan, good_os, got.err()), || {
                    format!("{head} for {with_nan:?}, OS {good_os}")
                })?;
            }
            let mut out = [[-7.0f32; K]; 2];
            let rows = [*x, with_nan];
            prop_assert_eq!(
                t.ml_batch(&rows, None, &mut out),
                Err(BatchError::Row {
                    index: 1,
                    error: want
                })
            );
            prop_assert_eq!(out[1], [-7.0f32; K]);
            prop_assert_eq!(
                t.map_batch(&rows, Some(&[good_os, good_os]), &mut out),
                Err(BatchError::Row {
                    index: 1,
                    error: want
                })
            );
        }
        None => {
            // Valid inputs: scores, and none of them NaN.
            for (head, got) in heads(t, x, good_os) {
                holds(check_error(x, good_os, got.err()), || {
                    format!("{head} for {x:?}, OS {good_os}")
                })?;
                let got = got.map_err(|e| TestCaseError::fail(format!("{head}: {e:?}")))?;
                prop_assert!(got.iter().all(|s| !s.is_nan()), "{}: {:?}", head, got);
            }
        }
    }
    prop_assert!(!(0.0..=1.0).contains(&bad_os));
    prop_assert_eq!(expected_error(x, bad_os), Some(InferError::Objectness));
    for (head, got) in heads(t, x, bad_os) {
        holds(check_error(x, bad_os, got.err()), || {
            format!("{head} for {x:?}, OS {bad_os}")
        })?;
    }
    Ok(())
}

fn bad_objectness() -> impl Strategy<Value = f32> {
    use proptest::num::f32 as f;
    prop_oneof![
        Just(f32::NAN),
        Just(-f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(1.0f32.next_up()),
        Just(-f32::from_bits(1)),
        (f::NEGATIVE | f::NORMAL | f::SUBNORMAL | f::INFINITE),
        (1.0f32..f32::MAX).prop_filter("above 1", |v| *v > 1.0),
    ]
}

/// Invariant 5: every table invariant, checked from the public accessors only.
fn assert_table_invariants<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
) -> Result<(), TestCaseError> {
    holds(check_table(t), || format!("{t:?}"))
}

/// Invariant 5: decoding `bytes` either fails or yields a table that satisfies every
/// invariant and survives an encode/decode round trip. (The re-encoding need not be
/// `bytes` itself: the decoder also accepts over-long varints and `-0.0` for `0.0`,
/// which the encoder never writes.)
fn decode_is_safe<const K: usize, const BM: usize, const BP: usize>(
    bytes: &[u8],
) -> Result<Option<DecodeError>, TestCaseError> {
    match Table::<K, BM, BP>::from_bytes(bytes) {
        Err(e) => Ok(Some(e)),
        Ok(t) => {
            assert_table_invariants(&t)?;
            let mut buf = vec![0u8; Table::<K, BM, BP>::MAX_ENCODED_LEN];
            let again = t.to_slice(&mut buf).expect("MAX_ENCODED_LEN suffices");
            prop_assert_eq!(Table::<K, BM, BP>::from_bytes(again), Ok(t));
            Ok(None)
        }
    }
}

/// An edit of an encoded table.
#[derive(Debug, Clone)]
enum Mutation {
    Xor(usize, u8),
    Set(usize, u8),
    /// Overwrite four bytes with an `f32` (a plausible or hostile float field).
    Float(usize, f32),
    Insert(usize, u8),
    Remove(usize),
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        3 => (any::<usize>(), 1..=255u8).prop_map(|(p, m)| Mutation::Xor(p, m)),
        1 => (any::<usize>(), any::<u8>()).prop_map(|(p, v)| Mutation::Set(p, v)),
        3 => (any::<usize>(), any::<f32>()).prop_map(|(p, v)| Mutation::Float(p, v)),
        1 => (any::<usize>(), any::<u8>()).prop_map(|(p, v)| Mutation::Insert(p, v)),
        1 => any::<usize>().prop_map(Mutation::Remove),
        1 => any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn mutate(bytes: &mut Vec<u8>, edits: &[Mutation]) {
    for e in edits {
        let n = bytes.len().max(1);
        match *e {
            Mutation::Xor(p, m) if !bytes.is_empty() => bytes[p % n] ^= m,
            Mutation::Set(p, v) if !bytes.is_empty() => bytes[p % n] = v,
            Mutation::Float(p, v) if bytes.len() >= 4 => {
                let p = p % (bytes.len() - 3);
                bytes[p..p + 4].copy_from_slice(&v.to_le_bytes());
            }
            Mutation::Insert(p, v) => bytes.insert(p % (bytes.len() + 1), v),
            Mutation::Remove(p) if !bytes.is_empty() => {
                bytes.remove(p % n);
            }
            Mutation::Truncate(p) => bytes.truncate(p % (bytes.len() + 1)),
            _ => {}
        }
    }
}

/// Invariant 5 on mutated encodings of a valid table: with the CRC left as it is (the
/// mutation must be caught), and with the CRC recomputed (so that the body's parsing
/// and validation are what is tested).
fn mutated_encoding_is_safe<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
    edits: &[Mutation],
) -> Result<(), TestCaseError> {
    let mut buf = vec![0u8; Table::<K, BM, BP>::MAX_ENCODED_LEN];
    let original = t.to_slice(&mut buf).unwrap().to_vec();
    let decoded = Table::<K, BM, BP>::from_bytes(&original);
    prop_assert_eq!(decoded.as_ref(), Ok(t));
    let mut bytes = original.clone();
    mutate(&mut bytes, edits);
    let raw = decode_is_safe::<K, BM, BP>(&bytes)?;
    if bytes != original {
        // A changed file with the old checksum is rejected.
        prop_assert!(raw.is_some(), "mutated bytes accepted without a new CRC");
    }
    decode_is_safe::<K, BM, BP>(&fix_crc(&bytes))?;
    #[cfg(feature = "std")]
    for b in [bytes.clone(), fix_crc(&bytes)] {
        if let Ok(d) = mlmap::host::DynTable::from_bytes(&b) {
            let again = d.to_vec().unwrap();
            prop_assert_eq!(mlmap::host::DynTable::from_bytes(&again), Ok(d));
        }
    }
    Ok(())
}

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
pub(crate) mod bayes {
    use mlmap::host::{BayesSpec, DynTable};
    use mlmap::invariants::{
        bayes_mismatch, bayes_reference, bayes_score_tolerance, bayes_sum, check_dyn_table,
        check_open_decision, check_prior_share, open_mismatch, open_reference,
        open_score_tolerance, SUBNORMAL_STEP,
    };
    use mlmap::{fast_math_max_score_error, BayesView, FastMath, Libm};

    use super::*;

    /// A Bayes head before validation, as counts.
    #[derive(Debug, Clone)]
    pub(crate) struct BayesParams {
        lambda: f32,
        bins: usize,
        ranges: Vec<(f32, f32)>,
        /// Rows per category (K classes, then background if present).
        rows: Vec<u64>,
        /// Counts, category-major: `(c K + j) B + b`.
        counts: Vec<u64>,
    }

    impl BayesParams {
        /// The terms `ln(count / n_c + lambda)` in `f64`, rounded to `f32`, logit-major.
        fn spec(&self) -> BayesSpec {
            let (k, b, cats) = (self.ranges.len(), self.bins, self.rows.len());
            let mut terms = Vec::with_capacity(k * b * cats);
            for j in 0..k {
                for bin in 0..b {
                    for (c, &n) in self.rows.iter().enumerate() {
                        let count = self.counts[(c * k + j) * b + bin];
                        let h = count as f64 / n as f64;
                        terms.push((h + f64::from(self.lambda)).ln() as f32);
                    }
                }
            }
            BayesSpec {
                lambda: self.lambda,
                rows: self.rows.clone(),
                ranges: self.ranges.clone(),
                terms,
                objectness: None,
            }
        }
    }

    fn bayes_params(k: usize, bins: usize, background: bool) -> impl Strategy<Value = BayesParams> {
        let cats = k + usize::from(background);
        let range = (
            prop_oneof![1 => Just(0.0f32), 4 => signed(decades(-3.0, 3.0))],
            decades(-2.0, 3.0),
        )
            .prop_map(|(lo, span)| (lo, lo + span));
        // Each category's training rows: a bin per logit.
        let category = prop::collection::vec(prop::collection::vec(0..bins, k), 1..=30);
        (
            prop_oneof![8 => decades(-6.0, 0.0), 1 => Just(1.0f32), 1 => Just(1e-6f32)],
            prop::collection::vec(range, k),
            prop::collection::vec(category, cats),
            prop_oneof![Just(1u64), Just(1000), Just(1_000_000_000_000)],
        )
            .prop_map(move |(lambda, ranges, data, scale)| {
                let mut counts = vec![0u64; cats * k * bins];
                let mut rows = Vec::with_capacity(cats);
                for (c, category_rows) in data.iter().enumerate() {
                    rows.push(category_rows.len() as u64 * scale);
                    for row in category_rows {
                        for (j, &b) in row.iter().enumerate() {
                            counts[(c * k + j) * bins + b] += scale;
                        }
                    }
                }
                BayesParams {
                    lambda,
                    bins,
                    ranges,
                    rows,
                    counts,
                }
            })
    }

    /// A random run-time shaped table of `k` classes (ML and MAP heads of 3 and 2 bins)
    /// with a random Bayes head of `bins` bins.
    pub(crate) fn dyn_table(
        k: usize,
        bins: usize,
        background: bool,
    ) -> impl Strategy<Value = (BayesParams, DynTable)> {
        (params(k, 3, 2), bayes_params(k, bins, background)).prop_filter_map(
            "parameters must make a valid table",
            move |(p, b)| {
                let classes = p
                    .classes
                    .iter()
                    .enumerate()
                    .map(|(i, c)| ClassSpec {
                        name: NAMES[i],
                        rows: c.rows,
                        mean: c.mean,
                        variance: c.variance,
                        ml_range: (c.ml.lo, c.ml.hi),
                        ml_freqs: c.ml.freqs.clone(),
                        map_range: (c.map.lo, c.map.hi),
                        map_freqs: c.map.freqs.clone(),
                    })
                    .collect();
                let t = DynTable::new(p.settings, classes).ok()?;
                // Every fitted head is valid: only the base table may be refused.
                let d = t
                    .with_bayes(b.spec())
                    .expect("a fitted Bayes head is valid");
                Some((b, d))
            },
        )
    }

    /// A random fixed-size table of shape `Table<K, BM, BP, BB, C>` with a random Bayes
    /// head, and the same table run-time shaped.
    fn fixed<const K: usize, const BM: usize, const BP: usize, const BB: usize, const C: usize>(
    ) -> impl Strategy<Value = (BayesParams, DynTable, Table<K, BM, BP, BB, C>)> {
        (table::<K, BM, BP>(), bayes_params(K, BB, C > K)).prop_map(|((_, t), b)| {
            let d = DynTable::from_table(&t)
                .with_bayes(b.spec())
                .expect("a fitted Bayes head is valid");
            let fixed = Table::<K, BM, BP, BB, C>::try_from(&d).expect("the shape fits");
            (b, d, fixed)
        })
    }

    /// How to pick one logit, resolved against its axis.
    #[derive(Debug, Clone, Copy)]
    enum BLogit {
        /// `lo + u (hi - lo)`.
        Inside(f64),
        /// Edge `k mod (B + 1)`.
        Edge(usize),
        /// Below `lo` (`false`) or above `hi` by `10^e` times the span, or infinite.
        Outside(bool, f64),
        /// Any non-NaN `f32`.
        Raw(f32),
    }

    fn blogit() -> impl Strategy<Value = BLogit> {
        use proptest::num::f32 as f;
        let raw = f::POSITIVE | f::NEGATIVE | f::NORMAL | f::SUBNORMAL | f::ZERO | f::INFINITE;
        prop_oneof![
            5 => (0.0f64..=1.0).prop_map(BLogit::Inside),
            2 => (0usize..16).prop_map(BLogit::Edge),
            2 => outside(),
            1 => raw.prop_map(BLogit::Raw),
        ]
    }

    fn outside() -> impl Strategy<Value = BLogit> {
        (
            any::<bool>(),
            prop_oneof![4 => -6.0f64..3.0, 1 => Just(f64::INFINITY)],
        )
            .prop_map(|(above, e)| BLogit::Outside(above, e))
    }

    fn resolve_b(head: &BayesView<'_>, j: usize, l: BLogit) -> f32 {
        let axis = head.axis(j).expect("logit exists");
        let (lo, hi) = (f64::from(axis.lo()), f64::from(axis.hi()));
        match l {
            BLogit::Inside(u) => (lo + u * (hi - lo)) as f32,
            BLogit::Edge(k) => axis.edge(k % (axis.bins() + 1)),
            BLogit::Outside(above, e) => {
                let d = 10f64.powf(e) * (hi - lo);
                let x = if above {
                    (hi + d) as f32
                } else {
                    (lo - d) as f32
                };
                // Rounding may land on the edge itself: step off it.
                match (above, axis.bin(x)) {
                    (_, None) => x,
                    (true, Some(_)) => axis.hi().next_up(),
                    (false, Some(_)) => axis.lo().next_down(),
                }
            }
            BLogit::Raw(v) => v,
        }
    }

    fn resolve_all(head: &BayesView<'_>, recipe: &[BLogit]) -> Vec<f32> {
        recipe
            .iter()
            .enumerate()
            .map(|(j, &l)| resolve_b(head, j, l))
            .collect()
    }

    fn bits(s: &[f32]) -> Vec<u32> {
        s.iter().map(|v| v.to_bits()).collect()
    }

    /// Scores one detection on the run-time shaped table with both backends and checks
    /// every score invariant of §1.6: errors for bad inputs, otherwise scores in
    /// `[0, OS]` with the head's sum rule, within `bayes_score_tolerance` of the `f64`
    /// formula, the backends within the bound derived above, and the prior's shares
    /// when every logit is outside its axis. Returns the FastMath scores (or the error).
    fn bayes_detection(
        d: &DynTable,
        x: &[f32],
        os: f32,
    ) -> Result<Result<Vec<f32>, InferError>, TestCaseError> {
        let head = d.bayes_head().expect("the table has a Bayes head");
        let (k, cats) = (head.logits(), head.categories());
        let ctx = || format!("x = {x:?}, OS = {os:e}, lambda = {:e}", head.lambda());
        let mut fast = vec![0.0f32; k];
        let mut libm = vec![0.0f32; k];
        let mut scratch = vec![0.0f32; cats];
        let rf = d.bayes_into::<FastMath>(x, os, &mut fast, &mut scratch);
        let rl = d.bayes_into::<Libm>(x, os, &mut libm, &mut scratch);
        holds(check_error(x, os, rf.err()), || {
            format!("FastMath: {}", ctx())
        })?;
        holds(check_error(x, os, rl.err()), || format!("Libm: {}", ctx()))?;
        if let Err(e) = rf {
            return Ok(Err(e));
        }
        let mut want = vec![0.0f64; k];
        let mut s64 = vec![0.0f64; cats];
        prop_assert!(bayes_reference(&head, x, os, &mut want, &mut s64));
        let unknown = (0..k).all(|j| head.axis(j).and_then(|a| a.bin(x[j])).is_none());
        for (name, s) in [("FastMath", &fast), ("Libm", &libm)] {
            holds(check_scores(s, os, bayes_sum(&head)), || {
                format!("{name}: {s:?}, {}", ctx())
            })?;
            prop_assert!(
                bayes_mismatch(&head, s, &want, os).is_none(),
                "{name}: {s:?}, formula {want:?} (relative tolerance {:e}), {}",
                bayes_score_tolerance(&head),
                ctx()
            );
            if unknown {
                holds(check_prior_share(s, os, &head), || {
                    format!("{name}: {s:?}, {}", ctx())
                })?;
            }
        }
        let bound = f64::from(fast_math_max_score_error(cats)) * f64::from(os)
            + f64::from(os) * f64::from(f32::MIN_POSITIVE)
            + 2.0 * SUBNORMAL_STEP;
        for (a, b) in fast.iter().zip(&libm) {
            prop_assert!(
                f64::from((a - b).abs()) <= bound,
                "FastMath {fast:?} vs Libm {libm:?}: more than {bound:e} apart, {}",
                ctx()
            );
        }
        Ok(Ok(fast))
    }

    /// NaN logits at `nan_at` (payload `nan_bits`) and a bad objectness, each alone and
    /// together: the error of invariant 4 from every entry point.
    fn bad_inputs(
        d: &DynTable,
        x: &[f32],
        nan_at: &[bool],
        nan_bits: u32,
        bad_os: f32,
    ) -> Result<(), TestCaseError> {
        let nan = f32::from_bits(0x7fc0_0000 | (nan_bits & 0x003f_ffff) | (nan_bits & 0x8000_0000));
        let mut with_nan = x.to_vec();
        for (v, &n) in with_nan.iter_mut().zip(nan_at) {
            if n {
                *v = nan;
            }
        }
        for (xs, os) in [(&with_nan, 0.5), (&x.to_vec(), bad_os), (&with_nan, bad_os)] {
            let got = bayes_detection(d, xs, os)?;
            prop_assert_eq!(got.err(), expected_error(xs, os));
        }
        Ok(())
    }

    proptest! {
        #[test]
        fn bayes_tables_of_any_k_and_bins_hold_every_invariant(
            (k, bins, background, (b, d), recipe, far, os) in (2usize..=5, 1usize..=8, any::<bool>())
                .prop_flat_map(|(k, bins, background)| (
                    Just(k),
                    Just(bins),
                    Just(background),
                    dyn_table(k, bins, background),
                    prop::collection::vec(blogit(), k),
                    prop::collection::vec(outside(), k),
                    objectness(),
                )),
        ) {
            prop_assert_eq!(d.k(), k);
            holds(check_dyn_table(&d), || format!("{b:?}"))?;
            let head = d.bayes_head().unwrap();
            prop_assert_eq!(head.bins(), bins);
            prop_assert_eq!(head.has_background(), background);
            let x = resolve_all(&head, &recipe);
            prop_assert!(bayes_detection(&d, &x, os)?.is_ok());
            // Every logit outside its axis: the prior's shares.
            let x = resolve_all(&head, &far);
            prop_assert!(bayes_detection(&d, &x, os)?.is_ok());
        }
    }

    macro_rules! bayes_properties {
        ($($module:ident: $k:literal, $bm:literal, $bp:literal, $bb:literal, $c:literal;)*) => {$(
            mod $module {
                use super::*;

                type T = Table<$k, $bm, $bp, $bb, $c>;

                proptest! {
                    #[test]
                    fn bayes_table_invariants_and_exact_storage(
                        (b, d, t) in fixed::<$k, $bm, $bp, $bb, $c>(),
                    ) {
                        holds(check_table(&t), || format!("{b:?}"))?;
                        holds(check_dyn_table(&d), || format!("{b:?}"))?;
                        prop_assert_eq!(&DynTable::from_table(&t), &d);
                        let head = t.bayes_head().unwrap();
                        let spec = b.spec();
                        prop_assert_eq!(bits(head.all_terms()), bits(&spec.terms));
                        prop_assert_eq!(head.all_rows(), &spec.rows[..]);
                        prop_assert_eq!(head.lambda().to_bits(), b.lambda.to_bits());
                        for (j, &(lo, hi)) in spec.ranges.iter().enumerate() {
                            let axis = head.axis(j).unwrap();
                            prop_assert_eq!((axis.lo().to_bits(), axis.hi().to_bits()), (lo.to_bits(), hi.to_bits()));
                        }
                    }

                    #[test]
                    fn bayes_scores_hold_every_invariant_and_agree_everywhere(
                        (_, d, t) in fixed::<$k, $bm, $bp, $bb, $c>(),
                        recipes in prop::collection::vec(
                            proptest::array::uniform::<_, $k>(blogit()), 1..4),
                        os in prop::collection::vec(objectness(), 3),
                    ) {
                        let head = t.bayes_head().unwrap();
                        let xs: Vec<[f32; $k]> = recipes
                            .iter()
                            .map(|r| resolve_all(&head, r).try_into().unwrap())
                            .collect();
                        let os = &os[..xs.len()];
                        let mut batch = vec![[0.0f32; $k]; xs.len()];
                        t.bayes_batch(&xs, Some(os), &mut batch).unwrap();
                        for ((x, &o), row) in xs.iter().zip(os).zip(&batch) {
                            let dynamic = bayes_detection(&d, x, o)?.unwrap();
                            let fast = t.bayes(x, o).unwrap().0;
                            let libm = t.bayes_with::<Libm>(x, o).unwrap().0;
                            // Table and DynTable: the same bits, either backend; the
                            // batch: the same bits as one call per row.
                            prop_assert_eq!(bits(&fast), bits(&dynamic));
                            prop_assert_eq!(bits(row), bits(&fast));
                            let mut out = [0.0f32; $k];
                            let mut scratch = [0.0f32; $c];
                            d.bayes_into::<Libm>(x, o, &mut out, &mut scratch).unwrap();
                            prop_assert_eq!(bits(&out), bits(&libm));
                        }
                    }

                    #[test]
                    fn bayes_without_evidence_gives_the_prior_shares(
                        (_, d, t) in fixed::<$k, $bm, $bp, $bb, $c>(),
                        far in proptest::array::uniform::<_, $k>(outside()),
                        os in objectness(),
                    ) {
                        let head = t.bayes_head().unwrap();
                        let x: [f32; $k] = resolve_all(&head, &far).try_into().unwrap();
                        for backend in [t.bayes(&x, os), t.bayes_with::<Libm>(&x, os)] {
                            let s = backend.unwrap().0;
                            holds(check_prior_share(&s, os, &head), || format!("x = {x:?}"))?;
                        }
                        prop_assert!(bayes_detection(&d, &x, os)?.is_ok());
                    }

                    #[test]
                    fn bayes_bad_inputs_are_errors(
                        (_, d, t) in fixed::<$k, $bm, $bp, $bb, $c>(),
                        recipe in proptest::array::uniform::<_, $k>(blogit()),
                        nan_at in proptest::array::uniform::<_, $k>(prop::bool::weighted(0.3)),
                        nan_bits in any::<u32>(),
                        bad_os in bad_objectness(),
                        at in 0usize..3,
                    ) {
                        let head = t.bayes_head().unwrap();
                        let x: [f32; $k] = resolve_all(&head, &recipe).try_into().unwrap();
                        let mut nan_at = nan_at;
                        nan_at[at % $k] = true;
                        bad_inputs(&d, &x, &nan_at, nan_bits, bad_os)?;
                        // The fixed table and its batch: the first bad row, rows before it
                        // written, the others untouched.
                        let mut bad = x;
                        bad[at % $k] = f32::NAN;
                        prop_assert_eq!(
                            t.bayes(&bad, 0.5).err(),
                            expected_error(&bad, 0.5)
                        );
                        prop_assert_eq!(t.bayes(&x, bad_os).err(), Some(InferError::Objectness));
                        let rows = [x, bad, x];
                        let mut out = [[-7.0f32; $k]; 3];
                        prop_assert_eq!(
                            t.bayes_batch(&rows, None, &mut out),
                            Err(BatchError::Row {
                                index: 1,
                                error: expected_error(&bad, 1.0).unwrap(),
                            })
                        );
                        prop_assert_eq!(bits(&out[0]), bits(&t.bayes(&x, 1.0).unwrap().0));
                        prop_assert_eq!(out[1], [-7.0f32; $k]);
                        prop_assert_eq!(out[2], [-7.0f32; $k]);
                    }
                }

                #[test]
                fn shape_is_as_declared() {
                    assert!(T::MAX_ENCODED_LEN > 0);
                }
            }
        )*};
    }

    /// The open head's parameters: temperatures across the allowed range (1 now and
    /// then), epsilons 0, tiny, moderate and huge.
    fn temperature() -> impl Strategy<Value = f32> {
        prop_oneof![
            1 => Just(1.0f32),
            1 => Just(mlmap::MIN_TEMPERATURE),
            1 => Just(mlmap::MAX_TEMPERATURE),
            6 => decades(-2.0, 2.0),
        ]
    }

    fn epsilon() -> impl Strategy<Value = f32> {
        prop_oneof![
            2 => Just(0.0f32),
            1 => Just(f32::MIN_POSITIVE),
            1 => Just(mlmap::MAX_EPSILON),
            6 => decades(-12.0, 6.0),
        ]
    }

    /// Scores one detection with the open head on `d` (which must have it) and checks
    /// DESIGN §1.8: errors for bad inputs; otherwise scores in `[0, OS]` summing to at
    /// most `OS`, the detector's decision, within `open_score_tolerance` of the `f64`
    /// formula; the backends agree within the Bayes bound widened by the softmax's.
    /// Returns the FastMath scores (or the error).
    fn open_detection(
        d: &DynTable,
        x: &[f32],
        os: f32,
    ) -> Result<Result<Vec<f32>, InferError>, TestCaseError> {
        let head = d.bayes_head().expect("the table has a Bayes head");
        let params = d.open_params().expect("the table has the open head");
        let (k, cats) = (head.logits(), head.categories());
        let ctx = || format!("x = {x:?}, OS = {os:e}, {params:?}");
        let mut fast = vec![0.0f32; k];
        let mut libm = vec![0.0f32; k];
        let mut scratch = vec![0.0f32; cats];
        let rf = d.open_into::<FastMath>(x, os, &mut fast, &mut scratch);
        let rl = d.open_into::<Libm>(x, os, &mut libm, &mut scratch);
        holds(check_error(x, os, rf.err()), || {
            format!("FastMath: {}", ctx())
        })?;
        holds(check_error(x, os, rl.err()), || format!("Libm: {}", ctx()))?;
        if let Err(e) = rf {
            return Ok(Err(e));
        }
        let mut want = vec![0.0f64; k];
        let mut s64 = vec![0.0f64; cats];
        prop_assert!(open_reference(&head, &params, x, os, &mut want, &mut s64).is_some());
        for (name, s) in [("FastMath", &fast), ("Libm", &libm)] {
            holds(check_scores(s, os, Sum::AtMost), || {
                format!("{name}: {s:?}, {}", ctx())
            })?;
            holds(check_open_decision(s, x), || {
                format!("{name}: {s:?}, {}", ctx())
            })?;
            prop_assert!(
                open_mismatch(&head, &params, x, s, &want, os).is_none(),
                "{name}: {s:?}, formula {want:?} (relative tolerance {:e}), {}",
                open_score_tolerance(&head, &params, x),
                ctx()
            );
        }
        Ok(Ok(fast))
    }

    proptest! {
        #[test]
        fn open_head_holds_every_invariant(
            (k, bins, background, (b, d), recipe, t, eps, os) in (2usize..=5, 1usize..=8, any::<bool>())
                .prop_flat_map(|(k, bins, background)| (
                    Just(k),
                    Just(bins),
                    Just(background),
                    dyn_table(k, bins, background),
                    prop::collection::vec(blogit(), k),
                    temperature(),
                    epsilon(),
                    objectness(),
                )),
        ) {
            let d = d.with_open(t, eps).expect("parameters in range");
            holds(check_dyn_table(&d), || format!("{b:?}"))?;
            // Through the bytes: the same table, written as version 3.
            let bytes = d.to_vec().unwrap();
            prop_assert_eq!(bytes[4], 3);
            prop_assert_eq!(&DynTable::from_bytes(&bytes).unwrap(), &d);
            let head = d.bayes_head().unwrap();
            prop_assert_eq!((head.logits(), head.bins(), head.has_background()), (k, bins, background));
            let x = resolve_all(&head, &recipe);
            prop_assert!(open_detection(&d, &x, os)?.is_ok());
        }

        /// Raising epsilon never raises a score, with either backend, not even by a
        /// rounding step; with epsilon 0 and no background the scores are the
        /// temperature layer's bit for bit (K = 3 here, the layer's const generic).
        #[test]
        fn open_head_is_monotone_in_epsilon_and_is_temperature_at_zero(
            (k, background, (_, d), recipe, t, e1, e2, os) in (2usize..=5, any::<bool>())
                .prop_flat_map(|(k, background)| (
                    Just(k),
                    Just(background),
                    dyn_table(k, 6, background),
                    prop::collection::vec(blogit(), k),
                    temperature(),
                    epsilon(),
                    epsilon(),
                    objectness(),
                )),
        ) {
            let (lo, hi) = if e1 <= e2 { (e1, e2) } else { (e2, e1) };
            let low = d.clone().with_open(t, lo).unwrap();
            let high = d.clone().with_open(t, hi).unwrap();
            let head = d.bayes_head().unwrap();
            let x = resolve_all(&head, &recipe);
            let cats = head.categories();
            let (mut a, mut b, mut scratch) = (vec![0.0f32; k], vec![0.0f32; k], vec![0.0f32; cats]);
            for libm in [false, true] {
                if libm {
                    low.open_into::<Libm>(&x, os, &mut a, &mut scratch).unwrap();
                    high.open_into::<Libm>(&x, os, &mut b, &mut scratch).unwrap();
                } else {
                    low.open_into::<FastMath>(&x, os, &mut a, &mut scratch).unwrap();
                    high.open_into::<FastMath>(&x, os, &mut b, &mut scratch).unwrap();
                }
                for (i, (&sa, &sb)) in a.iter().zip(&b).enumerate() {
                    prop_assert!(
                        sb <= sa,
                        "class {i}: epsilon {lo:e} gives {sa:e}, epsilon {hi:e} gives {sb:e} (libm: {libm}), x = {x:?}"
                    );
                }
            }
            if lo == 0.0 && !background && k == 3 {
                let x3: [f32; 3] = x.clone().try_into().unwrap();
                let want = mlmap::baseline::temperature::<FastMath, 3>(&x3, t, os).unwrap().0;
                low.open_into::<FastMath>(&x, os, &mut a, &mut scratch).unwrap();
                prop_assert_eq!(bits(&a), bits(&want));
            }
        }
    }

    bayes_properties! {
        k2_bayes_b1_background: 2, 1, 1, 1, 3;
        k3_bayes_b5: 3, 22, 17, 5, 3;
        k3_bayes_b22_background: 3, 22, 17, 22, 4;
        k5_bayes_b8_background: 5, 7, 30, 8, 6;
    }
}
