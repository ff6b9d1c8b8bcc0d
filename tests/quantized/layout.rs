//! The section's size formula and the open record's layout, the invariants of its scores,
//! refused quantization parameters, and a table file with its section.

use super::*;

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
