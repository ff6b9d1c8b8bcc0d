//! Random run-time shaped tables (K 2 to 5, random ML, MAP and Bayes heads, both tail
//! policies) and random quantization parameters: `DynQTable` equals `DynTable` on the
//! dequantized logits, bit for bit, for every int8 code of every class and for random
//! int16 codes, and the scores keep invariant 1.

use mlmap::host::{DynQTable, DynTable};
use mlmap::Head;
use proptest::prelude::*;

use super::*;
use crate::invariants::bayes_tables::dyn_table;

fn quantization(k: usize) -> impl Strategy<Value = (u8, Vec<f32>, Vec<i32>, u64)> {
    (prop_oneof![3 => Just(8u8), 1 => Just(16u8)], any::<u64>()).prop_flat_map(
        move |(bits, seed)| {
            let (lo, hi) = mlmap::code_range(bits);
            (
                Just(bits),
                prop::collection::vec((-4.0f64..1.0).prop_map(|e| 10f64.powf(e) as f32), k),
                prop::collection::vec(lo..=hi, k),
                Just(seed),
            )
        },
    )
}

fn check(
    t: &DynTable,
    q: &DynQTable<'_>,
    codes: &[i32],
    scales: &[f32],
    zps: &[i32],
) -> Result<(), TestCaseError> {
    let k = codes.len();
    let x: Vec<f32> = (0..k)
        .map(|i| dequantize(codes[i], scales[i], zps[i]))
        .collect();
    let heads: &[Head] = match (t.bayes_head().is_some(), t.open_params().is_some()) {
        (true, true) => &[Head::Ml, Head::Map, Head::Bayes, Head::Open],
        (true, false) => &[Head::Ml, Head::Map, Head::Bayes],
        _ => &[Head::Ml, Head::Map],
    };
    for &head in heads {
        for os in [1.0f32, 0.43] {
            let (mut got, mut want) = (vec![0.0f32; k], vec![0.0f32; k]);
            q.score_i32_into(head, codes, os, &mut got, &mut vec![0.0; q.scratch_len()])
                .unwrap();
            t.view()
                .score_into(head, &x, os, &mut want, &mut vec![0.0; k + 1])
                .unwrap();
            let (g, w): (Vec<u32>, Vec<u32>) = (
                got.iter().map(|v| v.to_bits()).collect(),
                want.iter().map(|v| v.to_bits()).collect(),
            );
            prop_assert_eq!(g, w, "{:?} codes {:?} x {:?}", head, codes, x);
            let background = t.bayes_head().is_some_and(|b| b.has_background());
            let sum = match head {
                Head::Open => Sum::AtMost,
                Head::Bayes if background => Sum::AtMost,
                _ => Sum::Equal,
            };
            check_scores(&got, os, sum).map_err(|v| TestCaseError::fail(v.to_string()))?;
            if head == Head::Open {
                check_open_decision(&got, &x).map_err(|v| TestCaseError::fail(v.to_string()))?;
            }
        }
    }
    Ok(())
}

/// The open head's parameters, or none (a version-2 table): temperatures across the
/// allowed range, epsilons 0, tiny, moderate and huge.
fn open() -> impl Strategy<Value = Option<(f32, f32)>> {
    let decades = |lo: f64, hi: f64| (lo..hi).prop_map(|e| 10f64.powf(e) as f32);
    let temperature = prop_oneof![
        1 => Just(1.0f32),
        1 => Just(mlmap::MIN_TEMPERATURE),
        1 => Just(mlmap::MAX_TEMPERATURE),
        4 => decades(-2.0, 2.0),
    ];
    let epsilon = prop_oneof![
        2 => Just(0.0f32),
        1 => Just(f32::MIN_POSITIVE),
        1 => Just(mlmap::MAX_EPSILON),
        4 => decades(-12.0, 6.0),
    ];
    prop::option::weighted(0.75, (temperature, epsilon))
}

fn case() -> impl Strategy<Value = (DynTable, (u8, Vec<f32>, Vec<i32>, u64))> {
    (2usize..=5, 1usize..=8, any::<bool>()).prop_flat_map(|(k, bins, background)| {
        (
            (dyn_table(k, bins, background), open()).prop_map(|((_, t), open)| match open {
                Some((temperature, epsilon)) => t
                    .with_open(temperature, epsilon)
                    .expect("parameters in range"),
                None => t,
            }),
            quantization(k),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
    #[test]
    fn dyn_qtable_equals_dyn_table((t, (bits, scales, zps, code_seed)) in case()) {
        let k = t.k();
        let p = QParams { bits, scales: &scales, zero_points: &zps, bayes: true };
        let n = quantized_len(&t.view(), &p).unwrap();
        let mut buf = vec![0u8; n];
        let bytes = quantize_into(&t.view(), &p, &mut buf).unwrap();
        let q = DynQTable::from_bytes(bytes).unwrap();
        prop_assert_eq!(q.k(), k);
        prop_assert_eq!(open_bits(q.open_params()), open_bits(t.open_params()));
        prop_assert_eq!(bytes[4], if t.open_params().is_some() { 2 } else { 1 });
        let (lo, hi) = mlmap::code_range(bits);
        let mut state = code_seed | 1;
        let mut next = move || { state ^= state << 13; state ^= state >> 7; state ^= state << 17; state };
        let mut random_code = || lo + (next() % (hi - lo + 1) as u64) as i32;
        if bits == 8 {
            for c in 0..k {
                for code in lo..=hi {
                    let mut codes: Vec<i32> = (0..k).map(|_| random_code()).collect();
                    codes[c] = code;
                    check(&t, &q, &codes, &scales, &zps)?;
                }
            }
        } else {
            for _ in 0..512 {
                let codes: Vec<i32> = (0..k).map(|_| random_code()).collect();
                check(&t, &q, &codes, &scales, &zps)?;
            }
            check(&t, &q, &vec![lo; k], &scales, &zps)?;
            check(&t, &q, &vec![hi; k], &scales, &zps)?;
        }
        // A code outside an int8 section's range is an error, not a lookup.
        if bits == 8 {
            let mut out = vec![0.0; k];
            let mut codes = vec![0; k];
            codes[k - 1] = 128;
            prop_assert_eq!(
                q.score_i32_into(Head::Ml, &codes, 1.0, &mut out, &mut vec![0.0; q.scratch_len()]),
                Err(mlmap::InferError::CodeRange { class: (k - 1) as u16 })
            );
        }
    }
}
