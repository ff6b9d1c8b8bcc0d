//! The quantized heads against the numpy goldens, and the shipped int8 file and its
//! embedded section.

use super::*;

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

/// `tables/default_q8.mlmap` is the shipped table followed by its int8 section for scale
/// 0.08 (what `mlmap quantize --scale 0.08` writes), and the section embedded at build
/// time (`mlmap::embedded::quantized`) scores exactly as the one read from the file.
#[test]
fn shipped_quantized_file_and_embedded_section() {
    let file = include_bytes!("../../tables/default_q8.mlmap");
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
