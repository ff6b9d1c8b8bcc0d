//! The property of each invariant, on one table and one input: the checks the
//! proptest cases of `mod.rs` run.

use super::*;

pub(super) fn scores_in_range_and_sum_to_os<const K: usize, const BM: usize, const BP: usize>(
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
pub(super) fn outside<const K: usize, const BM: usize, const BP: usize>(
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
pub(super) fn out_of_support_is_os_over_k<const K: usize, const BM: usize, const BP: usize>(
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
pub(super) fn ml_score_follows_likelihood<const K: usize, const BM: usize, const BP: usize>(
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
pub(super) fn raised_bin_never_lowers_score<const K: usize, const BM: usize, const BP: usize>(
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
pub(super) fn evidence_never_lowers_score<const K: usize, const BM: usize, const BP: usize>(
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
pub(super) fn bad_inputs_are_errors<const K: usize, const BM: usize, const BP: usize>(
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

pub(super) fn bad_objectness() -> impl Strategy<Value = f32> {
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
pub(super) fn assert_table_invariants<const K: usize, const BM: usize, const BP: usize>(
    t: &Table<K, BM, BP>,
) -> Result<(), TestCaseError> {
    holds(check_table(t), || format!("{t:?}"))
}

/// Invariant 5: decoding `bytes` either fails or yields a table that satisfies every
/// invariant and survives an encode/decode round trip. (The re-encoding need not be
/// `bytes` itself: the decoder also accepts over-long varints and `-0.0` for `0.0`,
/// which the encoder never writes.)
pub(super) fn decode_is_safe<const K: usize, const BM: usize, const BP: usize>(
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
pub(super) enum Mutation {
    Xor(usize, u8),
    Set(usize, u8),
    /// Overwrite four bytes with an `f32` (a plausible or hostile float field).
    Float(usize, f32),
    Insert(usize, u8),
    Remove(usize),
    Truncate(usize),
}

pub(super) fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        3 => (any::<usize>(), 1..=255u8).prop_map(|(p, m)| Mutation::Xor(p, m)),
        1 => (any::<usize>(), any::<u8>()).prop_map(|(p, v)| Mutation::Set(p, v)),
        3 => (any::<usize>(), any::<f32>()).prop_map(|(p, v)| Mutation::Float(p, v)),
        1 => (any::<usize>(), any::<u8>()).prop_map(|(p, v)| Mutation::Insert(p, v)),
        1 => any::<usize>().prop_map(Mutation::Remove),
        1 => any::<usize>().prop_map(Mutation::Truncate),
    ]
}

pub(super) fn mutate(bytes: &mut Vec<u8>, edits: &[Mutation]) {
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
pub(super) fn mutated_encoding_is_safe<const K: usize, const BM: usize, const BP: usize>(
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
