use mlmap::host::DynTable;
use mlmap::invariants::{
    bayes_mismatch, bayes_reference, bayes_score_tolerance, bayes_sum, check_dyn_table,
    check_open_decision, check_prior_share, open_mismatch, open_reference, open_score_tolerance,
    SUBNORMAL_STEP,
};
use mlmap::{fast_math_max_score_error, BayesView, FastMath, Libm};

use super::bayes_tables::*;
use super::*;

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
