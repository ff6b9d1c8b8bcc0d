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
    crc32, fix_crc, shipped, small_bayes, small_bayes_nobg, small_clamp, SmallBayes,
    SmallBayesNoBg, GOLDEN_ABS_TOL, SHIPPED_MLMAP,
};

/// Golden scores of quantized codes from the numpy reference (tools/mlmap_ref.py).
const QUANTIZED_CSV: &str = include_str!("golden/layer/quantized.csv");

/// The open head's golden table with a background category: K = 3, Bayes 4 bins, 4
/// categories, T = 1.75, epsilon = 0.05.
const SMALL_OPEN_MLMAP: &[u8] = include_bytes!("golden/layer/small_open.mlmap");
/// The same without background, epsilon 0.
const SMALL_OPEN_NOBG_MLMAP: &[u8] = include_bytes!("golden/layer/small_open_nobg.mlmap");

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

/// One row of `quantized.csv`: parameters, codes, objectness and the expected scores of
/// each head (`None` for a head the table does not have).
struct QGolden {
    table: String,
    bits: u8,
    scales: [f32; 3],
    zero_points: [i32; 3],
    codes: [i32; 3],
    objectness: f32,
    heads: [Option<[f64; 3]>; 4],
}

fn quantized_goldens() -> Vec<QGolden> {
    let mut lines = QUANTIZED_CSV.lines().filter(|l| !l.starts_with('#'));
    assert_eq!(
        lines.next(),
        Some(
            "table,bits,scale0,scale1,scale2,zp0,zp1,zp2,q0,q1,q2,objectness,ml0,ml1,ml2,\
             map0,map1,map2,bayes0,bayes1,bayes2,open0,open1,open2"
        )
    );
    lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), 24, "{line}");
            let three = |i: usize| -> [&str; 3] { [f[i], f[i + 1], f[i + 2]] };
            let head =
                |i: usize| (!f[i].is_empty()).then(|| three(i).map(|v| v.parse::<f64>().unwrap()));
            QGolden {
                table: f[0].to_owned(),
                bits: f[1].parse().unwrap(),
                scales: three(2).map(|v| v.parse().unwrap()),
                zero_points: three(5).map(|v| v.parse().unwrap()),
                codes: three(8).map(|v| v.parse().unwrap()),
                objectness: f[11].parse().unwrap(),
                heads: [head(12), head(15), head(18), head(21)],
            }
        })
        .collect()
}

/// The quantized heads of `t` against the numpy reference's scores of the dequantized
/// logits, for the golden rows of table `name`; returns the rows checked and the worst
/// error of ML / MAP and of Bayes / open.
fn quantized_matches_reference<
    const BM: usize,
    const BP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<3, BM, BP, BB, C>,
    name: &str,
    rows: &[QGolden],
) -> (usize, f64, f64) {
    let (mut n, mut worst_exact, mut worst_fast) = (0, 0.0f64, 0.0f64);
    for g in rows.iter().filter(|g| g.table == name) {
        let p = QParams {
            bits: g.bits,
            scales: &g.scales,
            zero_points: &g.zero_points,
            bayes: BB > 0,
        };
        let bytes = section(t, &p);
        let got: [Result<Scores<3>, InferError>; 4] = if g.bits == 8 {
            let q = QTable::<3, i8>::from_bytes(&bytes).expect("a built section is valid");
            let c = g.codes.map(|v| i8::try_from(v).unwrap());
            let o = g.objectness;
            [q.ml(&c, o), q.map(&c, o), q.bayes(&c, o), q.open(&c, o)]
        } else {
            let q = QTable::<3, i16>::from_bytes(&bytes).expect("a built section is valid");
            let c = g.codes.map(|v| i16::try_from(v).unwrap());
            let o = g.objectness;
            [q.ml(&c, o), q.map(&c, o), q.bayes(&c, o), q.open(&c, o)]
        };
        let what = format!(
            "{name} {} bits, codes {:?}, os {}",
            g.bits, g.codes, g.objectness
        );
        for (h, (got, want)) in got.into_iter().zip(&g.heads).enumerate() {
            let head = ["ML", "MAP", "Bayes", "open"][h];
            let Some(want) = want else {
                assert!(got.is_err(), "{head}: {what}: the table has no such head");
                continue;
            };
            let got = got.unwrap_or_else(|e| panic!("{head}: {what}: {e:?}")).0;
            for (&s, &w) in got.iter().zip(want) {
                let err = (f64::from(s) - w).abs();
                assert!(
                    err <= GOLDEN_ABS_TOL,
                    "{head}: {what}: got {got:?}, want {want:?}"
                );
                if h < 2 {
                    worst_exact = worst_exact.max(err);
                } else {
                    worst_fast = worst_fast.max(err);
                }
            }
        }
        n += 1;
    }
    (n, worst_exact, worst_fast)
}

/// Every head of the quantized table against the independent numpy reference (not the
/// `f32` layer): int8 and int16 codes at the range ends and at random, four parameter
/// sets, the shipped table and three small ones (clamp; open head with and without
/// background and unknown).
#[test]
fn quantized_heads_match_the_numpy_reference() {
    let rows = quantized_goldens();
    let results = [
        quantized_matches_reference(&shipped(), "default", &rows),
        quantized_matches_reference(&small_clamp(), "small_clamp", &rows),
        quantized_matches_reference(&small_open(), "small_open", &rows),
        quantized_matches_reference(&small_open_nobg(), "small_open_nobg", &rows),
    ];
    let n: usize = results.iter().map(|r| r.0).sum();
    assert_eq!(n, rows.len());
    assert!(
        results.iter().all(|r| r.0 >= 80),
        "{:?}",
        results.map(|r| r.0)
    );
    let exact = results.iter().map(|r| r.1).fold(0.0, f64::max);
    let fast = results.iter().map(|r| r.2).fold(0.0, f64::max);
    eprintln!(
        "quantized: {n} golden rows, worst score error ML/MAP {exact:e}, Bayes/open {fast:e}"
    );
}

/// Quantization parameters worth trying on tables whose logits span about -9 to 9: one
/// scale covering them, per-class scales and zero points, a coarse scale whose codes
/// mostly fall outside every histogram, and a fine one covering a sliver.
fn param_sets() -> Vec<([f32; 3], [i32; 3])> {
    vec![
        ([0.08; 3], [0; 3]),
        ([0.05, 0.04, 0.06], [3, -7, 0]),
        ([0.5; 3], [-100, 20, 127]),
        ([0.001, 0.003, 0.0007], [127, -128, 0]),
    ]
}

fn int8_everywhere<
    const BM: usize,
    const BP: usize,
    const BB: usize,
    const C: usize,
    const N: usize,
    const F: usize,
>(
    t: &Table<3, BM, BP, BB, C, N, F>,
) {
    let all: Vec<i8> = (i8::MIN..=i8::MAX).collect();
    let others = [-128i8, -40, -1, 0, 37, 127];
    for (scales, zps) in param_sets() {
        let p = QParams {
            bits: 8,
            scales: &scales,
            zero_points: &zps,
            bayes: BB > 0,
        };
        let bytes = section(t, &p);
        let q = QTable::<3, i8>::from_bytes(&bytes).expect("a built section is valid");
        assert_eq!(q.has_bayes(), BB > 0);
        // The open head comes with the Bayes head when the table has it, with the very
        // parameters (the unknown's log-score derived to the same bits).
        assert_eq!(open_bits(q.open_params()), open_bits(t.open_params()));
        let maps = [Head::Ml, Head::Map, Head::Bayes, Head::Open]
            .iter()
            .any(|&h| t.recal_map(h).is_some());
        let version = match (maps || F > 0, t.open_params().is_some()) {
            (true, _) => 3,
            (false, true) => 2,
            (false, false) => 1,
        };
        assert_eq!(bytes[4], version);
        let n = agree(t, &q, (scales, zps), &all, &others);
        assert_eq!(n, 3 * 256 * 36 * 2);
    }
}

#[test]
fn int8_equals_f32_layer_for_every_code_shipped() {
    int8_everywhere(&shipped());
}

#[test]
fn int8_equals_f32_layer_for_every_code_small_tables() {
    // The clamp policy (windows reaching the top code) and Bayes heads with and without
    // background.
    int8_everywhere(&small_clamp());
    int8_everywhere(&small_bayes());
    int8_everywhere(&small_bayes_nobg());
}

/// DESIGN §1.9: the maps of every head, in the section (version 3) and applied by the
/// quantized heads bit for bit as by the f32 layer; the table without a Bayes head
/// keeps its ML and MAP maps.
#[test]
fn int8_maps_equal_f32_layer_for_every_code() {
    let t = Table::<3, 4, 2, 4, 4, { mlmap::MAX_KNOTS }>::from_bytes(include_bytes!(
        "golden/layer/small_maps.mlmap"
    ))
    .unwrap();
    int8_everywhere(&t);
    let t = Table::<3, 4, 2, 0, 0, { mlmap::MAX_KNOTS }>::from_bytes(include_bytes!(
        "golden/layer/small_maps_nobayes.mlmap"
    ))
    .unwrap();
    int8_everywhere(&t);
}

/// The objectness feature (DESIGN §1.6) in the section (version 3, flag bit 2): the
/// quantized Bayes and open heads look up the objectness logit's bin at run time, bit
/// for bit as the f32 heads.
#[test]
fn int8_objectness_feature_equals_f32_layer_for_every_code() {
    let t =
        Table::<3, 4, 2, 4, 4, 0, 1>::from_bytes(include_bytes!("golden/layer/small_osf.mlmap"))
            .unwrap();
    int8_everywhere(&t);
    // Every objectness bin, both ends and the clamp.
    let (scales, zps) = ([0.05f32; 3], [0i32; 3]);
    let p = QParams {
        bits: 8,
        scales: &scales,
        zero_points: &zps,
        bayes: true,
    };
    let bytes = section(&t, &p);
    let q = QTable::<3, i8>::from_bytes(&bytes).unwrap();
    let codes = [60i8, -30, -70];
    let x: [f32; 3] = std::array::from_fn(|i| dequantize(i32::from(codes[i]), 0.05, 0));
    for os in [0.0f32, 1e-30, 0.02, 0.1, 0.3, 0.5, 0.75, 0.9, 0.999, 1.0] {
        assert_eq!(bits(q.bayes(&codes, os)), bits(t.bayes(&x, os)), "{os}");
        assert_eq!(bits(q.open(&codes, os)), bits(t.open(&x, os)), "{os}");
    }
}

/// A section built without the Bayes head from a table with maps on every head keeps the
/// ML and MAP maps only; a corrupted knot is refused as `QField::Map`.
#[test]
fn section_maps_follow_the_heads_and_their_rule() {
    let t = Table::<3, 4, 2, 4, 4, { mlmap::MAX_KNOTS }>::from_bytes(include_bytes!(
        "golden/layer/small_maps.mlmap"
    ))
    .unwrap();
    let (scales, zps) = ([0.05f32; 3], [0i32; 3]);
    let p = QParams {
        bits: 8,
        scales: &scales,
        zero_points: &zps,
        bayes: false,
    };
    let bytes = section(&t, &p);
    assert_eq!(bytes[4], 3);
    let q = QTable::<3, i8>::from_bytes(&bytes).unwrap();
    let codes = [60i8, -30, -70];
    let x: [f32; 3] = std::array::from_fn(|i| dequantize(i32::from(codes[i]), 0.05, 0));
    assert_eq!(bits(q.ml(&codes, 0.8)), bits(t.ml(&x, 0.8)));
    assert_eq!(bits(q.map(&codes, 0.8)), bits(t.map(&x, 0.8)));
    assert_eq!(q.bayes(&codes, 0.8), Err(InferError::NoBayesHead));
    // The last knot of the last map (the MAP head's: x = 1, y = 1) sits before the
    // 8-byte trailer; x = 0.5 breaks the rule (the last knot is not at 1).
    let mut bad = bytes.clone();
    let n = bad.len();
    let at = n - 8 - 8;
    assert_eq!(bad[at..at + 4], 1.0f32.to_le_bytes());
    bad[at..at + 4].copy_from_slice(&0.5f32.to_le_bytes());
    let crc = crc32(&bad[..n - 4]);
    bad[n - 4..].copy_from_slice(&crc.to_le_bytes());
    assert_eq!(
        QTable::<3, i8>::from_bytes(&bad).err(),
        Some(QTableError::Invalid {
            field: QField::Map,
            class: 1
        })
    );
}

#[test]
fn int8_open_head_equals_f32_layer_for_every_code() {
    // A non-zero epsilon with background (T = 1.75, epsilon = 0.05), and epsilon 0
    // without background (the temperature layer). The shipped table (epsilon 0 with
    // background) is in `int8_equals_f32_layer_for_every_code_shipped`.
    let t = small_open();
    let o = t.open_params().unwrap();
    assert_eq!((o.temperature(), o.epsilon()), (1.75, 0.05));
    int8_everywhere(&t);
    int8_everywhere(&small_open_nobg());
}

/// A scale so large that most dequantized logits overflow to infinity: the open head's
/// softmax takes them as its limit, and the quantized head still equals the `f32` one.
#[test]
fn int8_open_head_with_infinite_dequantized_logits() {
    let t = small_open();
    let (scales, zps) = ([3e38f32, 1e38, 2e37], [0i32, -1, 5]);
    let p = QParams {
        bits: 8,
        scales: &scales,
        zero_points: &zps,
        bayes: true,
    };
    let bytes = section(&t, &p);
    let q = QTable::<3, i8>::from_bytes(&bytes).unwrap();
    assert_eq!(
        q.logits(&[2, -128, 127])[..2],
        [f32::INFINITY, f32::NEG_INFINITY]
    );
    let all: Vec<i8> = (i8::MIN..=i8::MAX).collect();
    agree(&t, &q, (scales, zps), &all, &[-128, -1, 0, 1, 127]);
}

/// With epsilon 0 and no background, the quantized open head is the temperature layer
/// of DESIGN §1.4 on the dequantized logits, bit for bit (DESIGN §1.8's invariant); with
/// epsilon > 0 every score is below it.
#[test]
fn int8_open_head_is_the_temperature_layer_at_epsilon_zero() {
    let nobg = small_open_nobg();
    let with = small_open();
    let p = |bits| QParams {
        bits,
        scales: &[0.05, 0.04, 0.06],
        zero_points: &[3, -7, 0],
        bayes: true,
    };
    let (a, b) = (section(&nobg, &p(8)), section(&with, &p(8)));
    let (qa, qb) = (
        QTable::<3, i8>::from_bytes(&a).unwrap(),
        QTable::<3, i8>::from_bytes(&b).unwrap(),
    );
    let temperature = |t: f32, x: &[f32; 3], os| {
        mlmap::baseline::temperature::<mlmap::FastMath, 3>(x, t, os)
            .unwrap()
            .0
    };
    let (ta, tb) = (
        qa.open_params().unwrap().temperature(),
        qb.open_params().unwrap().temperature(),
    );
    for c0 in (-128..=127).step_by(3) {
        for c1 in (-128..=127).step_by(11) {
            let codes = [c0 as i8, c1 as i8, (c0 ^ c1) as i8];
            let (xa, xb) = (qa.logits(&codes), qb.logits(&codes));
            let os = 0.83;
            assert_eq!(qa.open(&codes, os).unwrap().0, temperature(ta, &xa, os));
            let s = qb.open(&codes, os).unwrap().0;
            for (s, w) in s.iter().zip(temperature(tb, &xb, os)) {
                assert!(*s <= w, "{codes:?}: {s} above the temperature layer's {w}");
            }
        }
    }
}

#[test]
fn int16_equals_f32_layer_on_sampled_codes_and_range_ends() {
    let t = shipped();
    let mut sample: Vec<i16> = (i16::MIN..=i16::MAX).step_by(97).collect();
    sample.extend([i16::MIN, i16::MIN + 1, -1, 0, 1, i16::MAX - 1, i16::MAX]);
    let others = [i16::MIN, -9000, 0, 4000, i16::MAX];
    for (scales, zps) in [
        ([0.001f32; 3], [0i32; 3]),
        ([0.0005, 0.0004, 0.0006], [-300, 1000, i16::MAX as i32]),
    ] {
        let p = QParams {
            bits: 16,
            scales: &scales,
            zero_points: &zps,
            bayes: true,
        };
        let bytes = section(&t, &p);
        let q = QTable::<3, i16>::from_bytes(&bytes).unwrap();
        agree(&t, &q, (scales, zps), &sample, &others);
        // Codes around every class's zero point and the support edges.
        let near: Vec<i16> = (-40..40)
            .map(|d| (zps[0] + d).clamp(-32768, 32767) as i16)
            .collect();
        agree(&t, &q, (scales, zps), &near, &[0]);
    }
    // The open head with a non-zero epsilon and background.
    let t = small_open();
    let (scales, zps) = ([0.0004f32, 0.0002, 0.0003], [-50i32, 0, 2000]);
    let p = QParams {
        bits: 16,
        scales: &scales,
        zero_points: &zps,
        bayes: true,
    };
    let bytes = section(&t, &p);
    let q = QTable::<3, i16>::from_bytes(&bytes).unwrap();
    assert!(q.open_params().is_some());
    agree(&t, &q, (scales, zps), &sample, &others);
}

/// The size formula of docs/FORMAT.md, with the windows counted from the `f32` tables'
/// public histograms (the codes whose likelihood is in a bin of non-zero mass).
#[test]
fn shipped_int8_section_size() {
    let t = shipped();
    let (scales, zps) = ([0.08f32; 3], [0i32; 3]);
    let window = |keep: &dyn Fn(i32) -> bool| {
        let codes: Vec<i32> = (-128..=127).filter(|&q| keep(q)).collect();
        codes.last().map_or(0, |l| (l - codes[0] + 1) as usize)
    };
    let mut size = 32 + 8;
    for c in 0..3 {
        let x = |q: i32| dequantize(q, scales[c], zps[c]);
        let ml = t.ml_histograms().get(c).unwrap();
        let map = t.map_histograms().get(c).unwrap();
        let g = t.priors().get(c).unwrap();
        let (lm, lp) = (t.settings().lambda_ml, t.settings().lambda_map);
        let n_ml = window(&|q| ml.bin(x(q)).is_some_and(|b| ml.frequencies()[b] + lm != lm));
        let n_map = window(&|q| {
            map.bin(x(q)).is_some_and(|b| {
                let f = map.frequencies()[b];
                f > 0.0 && f * g.pdf::<mlmap::Libm>(x(q)) + lp != lp
            })
        });
        size += 8 + 8 + n_ml + 4 * 22 + 8 + 4 * n_map;
    }
    let p = QParams {
        bits: 8,
        scales: &scales,
        zero_points: &zps,
        bayes: false,
    };
    let n = quantized_len(&t.view(), &p).unwrap();
    assert_eq!(n, size);
    assert!(
        n <= 3 * 1024,
        "ML and MAP int8 section of the shipped table: {n} bytes"
    );
    let with_bayes = quantized_len(&t.view(), &QParams { bayes: true, ..p }).unwrap();
    assert!(with_bayes > n);
    // The shipped table has the open head: it comes with the Bayes head, 12 bytes.
    let without_open = mlmap::host::DynTable::from_table(&t).without_open();
    let bayes_only = quantized_len(&without_open.view(), &QParams { bayes: true, ..p }).unwrap();
    assert_eq!(with_bayes, bayes_only + 12);
    println!(
        "shipped table, int8, scale 0.08: {n} bytes (ML, MAP), {bayes_only} with Bayes, \
         {with_bayes} with Bayes and open"
    );
}

/// The layout of docs/FORMAT.md: a table with the open head gets a version-2 section,
/// which is the version-1 section of the same table without the open head (the table
/// CRC it names aside), with the version byte 2 and the open record (temperature,
/// epsilon, the unknown log-score: `f32` LE each) between the log priors and the
/// trailer.
#[cfg(feature = "std")]
#[test]
fn open_record_layout() {
    let with = mlmap::host::DynTable::from_table(&small_open());
    let without = with.clone().without_open();
    for bits in [8u8, 16] {
        let p = QParams {
            bits,
            scales: &[0.05, 0.04, 0.06],
            zero_points: &[3, -7, 0],
            bayes: true,
        };
        let build = |t: &mlmap::host::DynTable| {
            let mut buf = vec![0u8; quantized_len(&t.view(), &p).unwrap()];
            quantize_into(&t.view(), &p, &mut buf).unwrap();
            buf
        };
        let (v2, v1) = (build(&with), build(&without));
        assert_eq!((v1[4], v2[4]), (1, 2));
        assert_eq!(v2.len(), v1.len() + 12);
        // The header: the same, but the version and the table CRC (each table's last
        // four bytes).
        assert_eq!(v1[..4], v2[..4]);
        assert_eq!(v1[5..16], v2[5..16]);
        assert_eq!(v2[16..20], SMALL_OPEN_MLMAP[SMALL_OPEN_MLMAP.len() - 4..]);
        let plain = without.to_vec().unwrap();
        assert_eq!(v1[16..20], plain[plain.len() - 4..]);
        // The body, then the open record.
        let body = v1.len() - 8;
        assert_eq!(v1[20..body], v2[20..body]);
        // The unknown's log-score: ln(0.05) + 3 ln(1/4 + lambda) in f64 (the table's
        // f32 value within a few rounding steps).
        let lambda = f64::from(with.bayes_head().unwrap().lambda());
        let log_unknown = with.open_params().unwrap().log_unknown();
        let want = 0.05f64.ln() + 3.0 * (0.25 + lambda).ln();
        assert!(
            (f64::from(log_unknown) - want).abs() < 1e-5,
            "{log_unknown} vs {want}"
        );
        let record: Vec<u8> = [1.75f32, 0.05, log_unknown]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        assert_eq!(v2[body..body + 12], record[..]);
        // The trailer: the length, then the CRC of everything before it.
        let n = v2.len();
        assert_eq!(v2[n - 8..n - 4], (n as u32).to_le_bytes());
        assert_eq!(v2[n - 4..], crc32(&v2[..n - 4]).to_le_bytes());
        // Both read; only version 2 has the open head.
        let (q1, q2) = (
            mlmap::host::DynQTable::from_bytes(&v1).unwrap(),
            mlmap::host::DynQTable::from_bytes(&v2).unwrap(),
        );
        assert_eq!(q1.open_params(), None);
        assert_eq!(open_bits(q2.open_params()), open_bits(with.open_params()));
        let mut out = [0.0f32; 3];
        assert_eq!(
            q1.score_i32_into(mlmap::Head::Open, &[0, 1, 2], 1.0, &mut out, &mut [0.0; 7]),
            Err(InferError::NoOpenHead)
        );
        // Without the Bayes head there is no open head, and the section is version 1.
        let no_bayes = QParams { bayes: false, ..p };
        let mut buf = vec![0u8; quantized_len(&with.view(), &no_bayes).unwrap()];
        let b = quantize_into(&with.view(), &no_bayes, &mut buf).unwrap();
        assert_eq!(b[4], 1);
        let q = mlmap::host::DynQTable::from_bytes(b).unwrap();
        assert_eq!(
            q.score_i32_into(mlmap::Head::Open, &[0, 1, 2], 1.0, &mut out, &mut [0.0; 7]),
            Err(InferError::NoOpenHead)
        );
    }
}

#[test]
fn scores_keep_the_invariants() {
    let t = shipped();
    let bytes = section(
        &t,
        &QParams {
            bits: 8,
            scales: &[0.08; 3],
            zero_points: &[0; 3],
            bayes: true,
        },
    );
    let q = QTable::<3, i8>::from_bytes(&bytes).unwrap();
    for a in (-128..=127).step_by(5) {
        for b in (-128..=127).step_by(7) {
            let codes = [a as i8, b as i8, (a ^ b) as i8];
            for os in [0.0f32, 1.0, 0.61] {
                for s in [q.ml(&codes, os), q.map(&codes, os)] {
                    check_scores(&s.unwrap().0, os, Sum::Equal).unwrap();
                }
                // Background takes a share: the class scores sum to at most OS.
                check_scores(&q.bayes(&codes, os).unwrap().0, os, Sum::AtMost).unwrap();
                let open = q.open(&codes, os).unwrap().0;
                check_scores(&open, os, Sum::AtMost).unwrap();
                check_open_decision(&open, &q.logits(&codes)).unwrap();
            }
        }
    }
    // Codes outside every window: "I don't know", exactly OS / K.
    let far = [-128i8; 3];
    assert_eq!(q.ml(&far, 0.9).unwrap().0, [0.9f32 / 3.0; 3]);
    assert_eq!(q.map(&far, 0.9).unwrap().0, [0.9f32 / 3.0; 3]);
    for os in [f32::NAN, -0.1, 1.5] {
        assert_eq!(q.ml(&far, os), Err(mlmap::InferError::Objectness));
        assert_eq!(q.map(&far, os), Err(mlmap::InferError::Objectness));
        assert_eq!(q.bayes(&far, os), Err(mlmap::InferError::Objectness));
        assert_eq!(q.open(&far, os), Err(mlmap::InferError::Objectness));
    }
    let no_bayes = section(
        &t,
        &QParams {
            bits: 8,
            scales: &[0.08; 3],
            zero_points: &[0; 3],
            bayes: false,
        },
    );
    let q = QTable::<3, i8>::from_bytes(&no_bayes).unwrap();
    assert_eq!(q.bayes(&far, 0.5), Err(mlmap::InferError::NoBayesHead));
    assert_eq!(q.open(&far, 0.5), Err(mlmap::InferError::NoOpenHead));
}

#[test]
fn quantize_rejects_bad_parameters() {
    let t = shipped();
    let v = t.view();
    let p = |bits, scales: &'static [f32], zero_points: &'static [i32]| QParams {
        bits,
        scales,
        zero_points,
        bayes: false,
    };
    let cases: [(QParams<'_>, QuantizeError); 7] = [
        (p(4, &[0.1; 3], &[0; 3]), QuantizeError::Bits),
        (p(8, &[0.1; 2], &[0; 3]), QuantizeError::Length),
        (p(8, &[0.1; 3], &[0; 4]), QuantizeError::Length),
        (
            p(8, &[0.1, 0.0, 0.1], &[0; 3]),
            QuantizeError::Scale { class: 1 },
        ),
        (
            p(8, &[0.1, 0.1, f32::NAN], &[0; 3]),
            QuantizeError::Scale { class: 2 },
        ),
        (
            p(8, &[0.1; 3], &[0, 128, 0]),
            QuantizeError::ZeroPoint { class: 1 },
        ),
        (
            p(16, &[0.1; 3], &[-32769, 0, 0]),
            QuantizeError::ZeroPoint { class: 0 },
        ),
    ];
    for (params, want) in cases {
        assert_eq!(quantized_len(&v, &params), Err(want), "{params:?}");
        assert_eq!(quantize_into(&v, &params, &mut [0u8; 8192]), Err(want));
    }
    let ok = p(8, &[0.1; 3], &[0; 3]);
    let n = quantized_len(&v, &ok).unwrap();
    let mut buf = vec![0u8; n - 1];
    assert_eq!(
        quantize_into(&v, &ok, &mut buf),
        Err(QuantizeError::BufferTooSmall)
    );
    let bayes = QParams { bayes: true, ..ok };
    let v1 = crate::support::small();
    assert_eq!(
        quantized_len(&v1.view(), &bayes),
        Err(QuantizeError::NoBayesHead)
    );
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

#[test]
fn table_file_with_a_section_appended() {
    let sec = shipped_section(8);
    let mut file = SHIPPED_MLMAP.to_vec();
    file.extend_from_slice(&sec);
    // The table decoders read the table part; the section reads the same from both.
    assert_eq!(
        crate::support::Shipped::from_bytes(&file).unwrap(),
        shipped()
    );
    let a = QTable::<3, i8>::from_bytes(&file).unwrap();
    let b = QTable::<3, i8>::from_bytes(&sec).unwrap();
    let codes = [12i8, -5, 60];
    assert_eq!(a.map(&codes, 1.0), b.map(&codes, 1.0));
    assert_eq!(
        a.table_crc(),
        u32::from_le_bytes(SHIPPED_MLMAP[SHIPPED_MLMAP.len() - 4..].try_into().unwrap())
    );
    // A section computed from another table does not follow this one.
    let other = section(
        &small_bayes(),
        &QParams {
            bits: 8,
            scales: &[0.08; 3],
            zero_points: &[0; 3],
            bayes: true,
        },
    );
    let mut wrong = SHIPPED_MLMAP.to_vec();
    wrong.extend_from_slice(&other);
    assert_eq!(
        QTable::<3, i8>::from_bytes(&wrong),
        Err(QTableError::TableMismatch)
    );
    // A bare section is not a table; a table alone holds no section.
    assert_eq!(
        crate::support::Shipped::from_bytes(&sec),
        Err(mlmap::DecodeError::NotATable)
    );
    assert_eq!(
        QTable::<3, i8>::from_bytes(SHIPPED_MLMAP),
        Err(QTableError::NotQuantized)
    );
}

/// `section` with the little-endian bytes `v` written at `at`, the CRC fixed.
fn patched(section: &[u8], at: usize, v: &[u8]) -> Vec<u8> {
    let mut b = section.to_vec();
    b[at..at + v.len()].copy_from_slice(v);
    fix_crc(&b)
}

#[test]
fn malformed_sections_are_refused_with_their_error() {
    let sec = shipped_section(8);
    let read = |b: &[u8]| QTable::<3, i8>::from_bytes(b).map(|_| ());
    assert_eq!(read(&sec), Ok(()));
    let invalid = |field, class| Err(QTableError::Invalid { field, class });
    // Class 0's record starts after the 32-byte header: scale, zero point, ML window.
    let cases: Vec<(Vec<u8>, Result<(), QTableError>)> = vec![
        (patched(&sec, 0, b"MLMX"), Err(QTableError::NotQuantized)),
        (
            {
                let mut b = sec.clone();
                b[40] ^= 1;
                b
            },
            Err(QTableError::Corrupted),
        ),
        (
            patched(&sec, 4, &[4]),
            Err(QTableError::UnsupportedVersion { found: 4 }),
        ),
        // Version 3 announces maps after the last record: there are none here.
        (patched(&sec, 4, &[3]), Err(QTableError::Malformed)),
        (
            patched(&sec, 4, &[0]),
            Err(QTableError::UnsupportedVersion { found: 0 }),
        ),
        // Version 1 has no open record: its 12 bytes are left over.
        (patched(&sec, 4, &[1]), Err(QTableError::Malformed)),
        (
            patched(&sec, 5, &[16]),
            Err(QTableError::ShapeMismatch {
                expected: (3, 8),
                found: (3, 16),
            }),
        ),
        (
            patched(&sec, 8, &4u16.to_le_bytes()),
            Err(QTableError::ShapeMismatch {
                expected: (3, 8),
                found: (4, 8),
            }),
        ),
        (patched(&sec, 6, &[2]), Err(QTableError::Malformed)),
        (patched(&sec, 7, &[1]), Err(QTableError::Malformed)),
        (
            patched(&sec, 14, &9u16.to_le_bytes()),
            invalid(QField::Shape, 0),
        ),
        (
            patched(&sec, 20, &0f32.to_le_bytes()),
            invalid(QField::Lambda, 0),
        ),
        (
            patched(&sec, 24, &f32::INFINITY.to_le_bytes()),
            invalid(QField::Lambda, 0),
        ),
        (
            patched(&sec, 28, &f32::NAN.to_le_bytes()),
            invalid(QField::LogTerm, 0),
        ),
        (
            patched(&sec, 32, &(-0.5f32).to_le_bytes()),
            invalid(QField::Scale, 0),
        ),
        (
            patched(&sec, 36, &128i32.to_le_bytes()),
            invalid(QField::ZeroPoint, 0),
        ),
        (
            patched(&sec, 40, &100i32.to_le_bytes()),
            invalid(QField::Window, 0),
        ),
        (
            patched(&sec, 40, &(-129i32).to_le_bytes()),
            invalid(QField::Window, 0),
        ),
        (patched(&sec, 48, &[22]), invalid(QField::Index, 0)),
    ];
    for (i, (bytes, want)) in cases.into_iter().enumerate() {
        assert_eq!(read(&bytes), want, "case {i}");
    }
    // A mass of 0 and a log-term of infinity, found by value.
    let ml_masses_at = {
        let n = u32::from_le_bytes(sec[44..48].try_into().unwrap()) as usize;
        48 + n
    };
    assert_eq!(
        read(&patched(&sec, ml_masses_at, &0f32.to_le_bytes())),
        invalid(QField::Mass, 0)
    );
    let open_at = sec.len() - 8 - 12;
    let prior_at = open_at - 16;
    assert_eq!(
        read(&patched(&sec, prior_at + 12, &f32::INFINITY.to_le_bytes())),
        invalid(QField::LogTerm, 3)
    );
    // The open record: temperature, epsilon, the unknown log-score (the shipped table:
    // epsilon 0, so -inf).
    let record =
        |at: usize| f32::from_le_bytes(sec[open_at + at..open_at + at + 4].try_into().unwrap());
    assert_eq!(
        (record(0), record(4), record(8)),
        (1.0, 0.0, f32::NEG_INFINITY)
    );
    let open_cases: Vec<(usize, f32, QField)> = vec![
        (0, 0.0, QField::Temperature),
        (0, -1.0, QField::Temperature),
        (0, f32::NAN, QField::Temperature),
        (0, 2e6, QField::Temperature),
        (0, 5e-7, QField::Temperature),
        (4, -0.0, QField::Epsilon),
        (4, -1e-3, QField::Epsilon),
        (4, f32::from_bits(1), QField::Epsilon),
        (4, 2e30, QField::Epsilon),
        (4, f32::INFINITY, QField::Epsilon),
        (4, f32::NAN, QField::Epsilon),
        // An unknown category with epsilon 0, or none with epsilon > 0.
        (8, 0.0, QField::LogUnknown),
        (8, -1e30, QField::LogUnknown),
        (8, f32::NAN, QField::LogUnknown),
        (8, f32::INFINITY, QField::LogUnknown),
        (4, 0.01, QField::LogUnknown),
    ];
    for (at, v, field) in open_cases {
        assert_eq!(
            read(&patched(&sec, open_at + at, &v.to_le_bytes())),
            invalid(field, 0),
            "offset {at}: {v:e}"
        );
    }
    // Values in range are read as they are: the smallest and largest temperature and
    // epsilon, each epsilon > 0 with a finite log-score (the values `quantize` writes
    // are compared with the table's in `int8_open_head_equals_f32_layer_for_every_code`).
    let read_open = |t: f32, e: f32, l: f32| {
        let mut rec = Vec::new();
        for v in [t, e, l] {
            rec.extend_from_slice(&v.to_le_bytes());
        }
        QTable::<3, i8>::from_bytes(&patched(&sec, open_at, &rec))
            .map(|q| open_bits(q.open_params()))
    };
    for (t, e, l) in [
        (1e-6f32, 0.0, f32::NEG_INFINITY),
        (1e6, 0.0, f32::NEG_INFINITY),
        (1.0, f32::MIN_POSITIVE, -100.0),
        (1.0, 1e30, 60.0),
        (2.5, 0.3, -1e30),
    ] {
        assert_eq!(
            read_open(t, e, l),
            Ok(Some([t.to_bits(), e.to_bits(), l.to_bits()]))
        );
    }
    // Version 2 needs the Bayes head: a section without it, marked version 2.
    let no_bayes = section(
        &shipped(),
        &QParams {
            bits: 8,
            scales: &[0.08; 3],
            zero_points: &[0; 3],
            bayes: false,
        },
    );
    assert_eq!(no_bayes[4], 1);
    assert_eq!(
        read(&patched(&no_bayes, 4, &[2])),
        Err(QTableError::Malformed)
    );
    // Every truncation, and a byte added before the trailer.
    for n in 0..sec.len() {
        assert!(read(&sec[..n]).is_err(), "prefix of {n} bytes");
        assert!(
            read(&fix_crc(&sec[..n])).is_err(),
            "prefix of {n} bytes, CRC fixed"
        );
    }
    let mut longer = sec[..sec.len() - 8].to_vec();
    longer.push(0);
    let len = (longer.len() + 8) as u32;
    longer.extend_from_slice(&len.to_le_bytes());
    longer.extend_from_slice(&[0; 4]);
    assert_eq!(read(&fix_crc(&longer)), Err(QTableError::Malformed));
}

/// The open record's temperature and epsilon are accepted exactly where the table
/// accepts them (`DynTable::with_open`, the table decoder's rule): at, just inside and
/// just outside every bound, and NaN, infinities and -0.
#[cfg(feature = "std")]
#[test]
fn open_record_ranges_are_the_tables() {
    let sec = shipped_section(8);
    let open_at = sec.len() - 8 - 12;
    let table = mlmap::host::DynTable::from_table(&shipped());
    let up = |v: f32| f32::from_bits(v.to_bits() + 1);
    let down = |v: f32| f32::from_bits(v.to_bits() - 1);
    let (tmin, tmax, emax) = (
        mlmap::MIN_TEMPERATURE,
        mlmap::MAX_TEMPERATURE,
        mlmap::MAX_EPSILON,
    );
    let odd = [
        0.0f32,
        -0.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -1.0,
        f32::from_bits(1),
    ];
    let temperatures = [tmin, up(tmin), down(tmin), 1.0, tmax, up(tmax), down(tmax)];
    let epsilons = [
        f32::MIN_POSITIVE,
        down(f32::MIN_POSITIVE),
        0.5,
        emax,
        up(emax),
        down(emax),
    ];
    let record = |t: f32, e: f32| {
        // -inf with epsilon 0 (of either sign), a finite log-score otherwise.
        let l = if e == 0.0 { f32::NEG_INFINITY } else { -1.0 };
        let mut rec = Vec::new();
        for v in [t, e, l] {
            rec.extend_from_slice(&v.to_le_bytes());
        }
        QTable::<3, i8>::from_bytes(&patched(&sec, open_at, &rec)).is_ok()
    };
    for t in temperatures.iter().chain(&odd) {
        let want = table.clone().with_open(*t, 0.0).is_ok();
        assert_eq!(record(*t, 0.0), want, "temperature {t:e}");
    }
    for e in epsilons.iter().chain(&odd) {
        let want = table.clone().with_open(1.0, *e).is_ok();
        assert_eq!(record(1.0, *e), want, "epsilon {e:e} ({:#x})", e.to_bits());
    }
}

/// Every byte of the section set to a few values, the CRC fixed: no panic, and any
/// section that is accepted scores within the invariants.
#[test]
fn mutated_sections_never_panic() {
    for (bits, open) in [(8u8, false), (16, false), (8, true), (16, true)] {
        let p = QParams {
            bits,
            scales: &[0.1; 3],
            zero_points: &[0; 3],
            bayes: true,
        };
        let sec = if open {
            section(&small_open(), &p)
        } else {
            section(&small_bayes(), &p)
        };
        let mut accepted = 0;
        for i in 0..sec.len() - 4 {
            for v in [0x00u8, 0x01, 0x7f, 0x80, 0xff, sec[i] ^ 0x10] {
                let b = patched(&sec, i, &[v]);
                let (a, b) = (
                    QTable::<3, i8>::from_bytes(&b),
                    QTable::<3, i16>::from_bytes(&b),
                );
                if let Ok(q) = a {
                    accepted += 1;
                    for codes in [[0i8; 3], [127, -128, 5], [-3, 40, -90]] {
                        check_scores(&q.ml(&codes, 1.0).unwrap().0, 1.0, Sum::Equal).unwrap();
                        check_scores(&q.map(&codes, 1.0).unwrap().0, 1.0, Sum::Equal).unwrap();
                        check_scores(&q.bayes(&codes, 1.0).unwrap().0, 1.0, Sum::AtMost).unwrap();
                        check_open(&q.open(&codes, 1.0), open, &q.logits(&codes));
                    }
                }
                if let Ok(q) = b {
                    accepted += 1;
                    for codes in [[0i16; 3], [32767, -32768, 5]] {
                        check_scores(&q.ml(&codes, 1.0).unwrap().0, 1.0, Sum::Equal).unwrap();
                        check_scores(&q.map(&codes, 1.0).unwrap().0, 1.0, Sum::Equal).unwrap();
                        check_scores(&q.bayes(&codes, 1.0).unwrap().0, 1.0, Sum::AtMost).unwrap();
                        check_open(&q.open(&codes, 1.0), open, &q.logits(&codes));
                    }
                }
            }
        }
        assert!(accepted > 0);
    }
}

/// An accepted mutated section scores the open head within DESIGN §1.8's invariants, or
/// says it has none (a mutation cannot add the open head to a section without it: the
/// version byte of a version-1 section set to 2 leaves the record missing).
fn check_open(s: &Result<Scores<3>, InferError>, open: bool, x: &[f32; 3]) {
    match s {
        Ok(s) => {
            assert!(open, "an open head in a section built without one");
            check_scores(&s.0, 1.0, Sum::AtMost).unwrap();
            check_open_decision(&s.0, x).unwrap();
        }
        Err(e) => assert_eq!((*e, open), (InferError::NoOpenHead, false)),
    }
}

/// Random run-time shaped tables (K 2 to 5, random ML, MAP and Bayes heads, both tail
/// policies) and random quantization parameters: `DynQTable` equals `DynTable` on the
/// dequantized logits, bit for bit, for every int8 code of every class and for random
/// int16 codes, and the scores keep invariant 1.
#[cfg(feature = "std")]
mod random {
    use mlmap::host::{DynQTable, DynTable};
    use mlmap::Head;
    use proptest::prelude::*;

    use super::*;
    use crate::invariants::bayes::dyn_table;

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
                    check_open_decision(&got, &x)
                        .map_err(|v| TestCaseError::fail(v.to_string()))?;
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
}

/// `tables/default_q8.mlmap` is the shipped table followed by its int8 section for scale
/// 0.08 (what `mlmap quantize --scale 0.08` writes), and the section embedded at build
/// time (`mlmap::embedded::quantized`) scores exactly as the one read from the file.
#[test]
fn shipped_quantized_file_and_embedded_section() {
    let file = include_bytes!("../tables/default_q8.mlmap");
    let mut want = SHIPPED_MLMAP.to_vec();
    want.extend_from_slice(&shipped_section(8));
    assert_eq!(&file[..], &want[..]);
    use mlmap::embedded::quantized::{QUANTIZED, QUANTIZED_BITS, QUANTIZED_K, QUANTIZED_SECTION};
    assert_eq!((QUANTIZED_K, QUANTIZED_BITS), (3, 8));
    assert_eq!(&QUANTIZED_SECTION[..], &file[SHIPPED_MLMAP.len()..]);
    let read = QTable::<3, i8>::from_bytes(file).unwrap();
    assert_eq!(QUANTIZED, read);
    // The shipped table's open head (T = 1, epsilon = 0), in the file and embedded.
    assert_eq!(file[SHIPPED_MLMAP.len() + 4], 2, "a version-2 section");
    assert_eq!(
        open_bits(QUANTIZED.open_params()),
        open_bits(shipped().open_params())
    );
    for codes in [[0i8, 0, 0], [50, -20, 10], [127, -128, 3]] {
        assert_eq!(QUANTIZED.bayes(&codes, 0.8), read.bayes(&codes, 0.8));
        let x = read.logits(&codes);
        assert_eq!(QUANTIZED.open(&codes, 0.8), read.open(&codes, 0.8));
        assert_eq!(QUANTIZED.open(&codes, 0.8), shipped().open(&x, 0.8));
    }
}
