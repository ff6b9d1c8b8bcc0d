//! The quantized table (`QTable`, docs/FORMAT.md "The quantized section"): its heads,
//! the open head included, equal the `f32` heads on the dequantized logits bit for bit
//! (every int8 code of every class; int16 codes sampled and at the range ends; random
//! tables and parameters), the section's size and layout (version 1 without the open
//! head, version 2 with it), the table file with a section appended, and every malformed
//! section refused with its error and never a panic.

use mlmap::invariants::{check_open_decision, check_scores, Sum};
use mlmap::{
    dequantize, quantize_into, quantized_len, Code, Head, InferError, OpenParams, QField, QParams,
    QTable, QTableError, QuantizeError, Scores, Table,
};

use crate::support::{
    crc32, fix_crc, resealed, shipped, small_bayes, small_bayes_nobg, small_clamp, SmallBayes,
    SmallBayesNoBg, GOLDEN_ABS_TOL, SHIPPED_MLMAP,
};

/// Golden scores of quantized codes from the numpy reference (tools/mlmap_ref.py).
const QUANTIZED_CSV: &str = include_str!("../golden/layer/quantized.csv");

/// The open head's golden table with a background category: K = 3, Bayes 4 bins, 4
/// categories, T = 1.75, epsilon = 0.05.
const SMALL_OPEN_MLMAP: &[u8] = include_bytes!("../golden/layer/small_open.mlmap");
/// The same without background, epsilon 0.
const SMALL_OPEN_NOBG_MLMAP: &[u8] = include_bytes!("../golden/layer/small_open_nobg.mlmap");

fn small_open() -> SmallBayes {
    SmallBayes::from_bytes(SMALL_OPEN_MLMAP).expect("golden table")
}

fn small_open_nobg() -> SmallBayesNoBg {
    SmallBayesNoBg::from_bytes(SMALL_OPEN_NOBG_MLMAP).expect("golden table")
}

/// The bits of the open head's parameters, so that equality is exact (and `-inf`, the
/// unknown's log-score for epsilon 0, compares as itself).
fn open_bits(o: Option<OpenParams>) -> Option<[u32; 3]> {
    o.map(|o| [o.temperature(), o.epsilon(), o.log_unknown()].map(f32::to_bits))
}

/// The quantized section of `t` for `params`.
fn section<
    const BM: usize,
    const BP: usize,
    const BB: usize,
    const C: usize,
    const N: usize,
    const F: usize,
>(
    t: &Table<3, BM, BP, BB, C, N, F>,
    params: &QParams<'_>,
) -> Vec<u8> {
    let n = quantized_len(&t.view(), params).expect("valid parameters");
    let mut buf = vec![0u8; n];
    let written = quantize_into(&t.view(), params, &mut buf).expect("valid parameters");
    assert_eq!(written.len(), n);
    buf
}

fn bits<const K: usize>(s: Result<Scores<K>, mlmap::InferError>) -> [u32; K] {
    s.expect("valid detection").0.map(f32::to_bits)
}

/// Every head of `q` against the `f32` table on the dequantized logits, for codes that
/// run through every value of `all` for one class at a time, the others taking values
/// from `others`.
fn agree<
    const BM: usize,
    const BP: usize,
    const BB: usize,
    const C: usize,
    const N: usize,
    const F: usize,
    Q: Code + Copy,
>(
    t: &Table<3, BM, BP, BB, C, N, F>,
    q: &QTable<'_, 3, Q>,
    (scales, zps): ([f32; 3], [i32; 3]),
    all: &[Q],
    others: &[Q],
) -> usize {
    let mut n = 0;
    for c in 0..3 {
        for &code in all {
            for &a in others {
                for &b in others {
                    let mut codes = [a, b, a];
                    codes[c] = code;
                    let x: [f32; 3] =
                        std::array::from_fn(|i| dequantize(codes[i].value(), scales[i], zps[i]));
                    for os in [1.0f32, 0.37] {
                        let what =
                            || format!("codes {:?} x {x:?} os {os}", codes.map(|q| q.value()));
                        assert_eq!(bits(q.ml(&codes, os)), bits(t.ml(&x, os)), "ML {}", what());
                        assert_eq!(
                            bits(q.map(&codes, os)),
                            bits(t.map(&x, os)),
                            "MAP {}",
                            what()
                        );
                        if BB > 0 {
                            let s = q.bayes(&codes, os);
                            let mut want = [0.0f32; 3];
                            t.view()
                                .bayes_into::<mlmap::FastMath>(&x, os, &mut want, &mut [0.0; C])
                                .unwrap();
                            assert_eq!(bits(s), want.map(f32::to_bits), "Bayes {}", what());
                        }
                        if q.open_params().is_some() {
                            // `Table::open` and `open_with` (through the view: the table
                            // type may have no Bayes head at all).
                            let f32_open = |libm: bool| {
                                let mut want = [0.0f32; 3];
                                let v = t.view();
                                let r = if libm {
                                    v.open_into::<mlmap::Libm>(&x, os, &mut want, &mut [0.0; C])
                                } else {
                                    v.open_into::<mlmap::FastMath>(&x, os, &mut want, &mut [0.0; C])
                                };
                                r.expect("valid detection");
                                want.map(f32::to_bits)
                            };
                            let s = q.open(&codes, os).expect("valid detection");
                            assert_eq!(bits(Ok(s)), f32_open(false), "open {}", what());
                            assert_eq!(
                                bits(q.open_with::<mlmap::Libm>(&codes, os)),
                                f32_open(true),
                                "open (Libm) {}",
                                what()
                            );
                            // DESIGN §1.8 without the f32 layer: within [0, OS], summing
                            // to at most OS, and the detector's decision (a map keeps
                            // the decision, and makes the top score g(top)).
                            if N == 0 {
                                check_scores(&s.0, os, Sum::AtMost).unwrap();
                            }
                            check_open_decision(&s.0, &x).unwrap();
                        } else {
                            assert_eq!(q.open(&codes, os), Err(InferError::NoOpenHead));
                        }
                        n += 1;
                    }
                }
            }
        }
    }
    n
}

fn shipped_section(bits: u8) -> Vec<u8> {
    section(
        &shipped(),
        &QParams {
            bits,
            scales: &[0.08; 3],
            zero_points: &[0; 3],
            bayes: true,
        },
    )
}

/// Every int8 code (and sampled int16 codes) scores as the `f32` layer on its dequantized
/// logit: every head, maps, the objectness feature, the open head.
mod codes;
/// The section's size formula and the open record's layout, the invariants of its scores,
/// refused quantization parameters, and a table file with its section.
mod layout;
/// Malformed sections refused with their error, the open record's ranges, and mutated
/// sections that never panic.
mod malformed;
/// Random run-time shaped tables (K 2 to 5, random ML, MAP and Bayes heads, both tail
/// policies) and random quantization parameters: `DynQTable` equals `DynTable` on the
/// dequantized logits, bit for bit, for every int8 code of every class and for random
/// int16 codes, and the scores keep invariant 1.
#[cfg(feature = "std")]
mod random;
/// The quantized heads against the numpy goldens, and the shipped int8 file and its
/// embedded section.
mod reference;
