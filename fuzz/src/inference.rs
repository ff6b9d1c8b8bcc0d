//! Inference invariants (DESIGN §1.3, invariants 1, 2 and 4): logits from fuzz input, the
//! scores of the ML and MAP heads against the formula, one detection and in batches.

use super::*;

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
                let h = t.map_histograms().get(i).expect("class exists");
                h.edge(k % (B_MAP + 1))
            } else {
                let h = t.ml_histograms().get(i).expect("class exists");
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
        let ml = t.ml_histograms().get(i).expect("class exists");
        let map = t.map_histograms().get(i).expect("class exists");
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
        let h = t.map_histograms().get(i).expect("class exists");
        let l = h.likelihood(x[i], tail);
        if l > 0.0 {
            l * t.priors().get(i).expect("class exists").pdf::<M>(x[i])
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
    if let (Ok(ml), Ok(map), Ok(fast)) = (&ml, &map, &fast) {
        let l: [f32; K] = core::array::from_fn(|i| {
            let h = t.ml_histograms().get(i).expect("class exists");
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
    }
    // Every other front gives the same bits, or the same error.
    let what = format_args!("x = {x:?}, OS = {objectness:e}");
    let ml_batch =
        |xs: &[[f32; K]], os: Option<&[f32]>, out: &mut [[f32; K]]| t.ml_batch(xs, os, out);
    let map_batch =
        |xs: &[[f32; K]], os: Option<&[f32]>, out: &mut [[f32; K]]| t.map_batch(xs, os, out);
    let fast_batch = |xs: &[[f32; K]], os: Option<&[f32]>, out: &mut [[f32; K]]| {
        t.map_batch_with::<FastMath>(xs, os, out)
    };
    check_fronts::<Libm, K, B_ML, B_MAP, BB, C>(
        t,
        dynt,
        Head::Ml,
        x,
        objectness,
        &ml,
        &ml,
        &ml_batch,
        None,
        what,
    );
    check_fronts::<FastMath, K, B_ML, B_MAP, BB, C>(
        t,
        dynt,
        Head::Map,
        x,
        objectness,
        &map,
        &fast,
        &map_batch,
        Some(&fast_batch),
        what,
    );
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
pub(crate) fn for_detections<
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
