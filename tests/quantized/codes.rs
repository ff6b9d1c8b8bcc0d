//! Every int8 code (and sampled int16 codes) scores as the `f32` layer on its dequantized
//! logit: every head, maps, the objectness feature, the open head.

use super::*;

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
        "../golden/layer/small_maps.mlmap"
    ))
    .unwrap();
    int8_everywhere(&t);
    let t = Table::<3, 4, 2, 0, 0, { mlmap::MAX_KNOTS }>::from_bytes(include_bytes!(
        "../golden/layer/small_maps_nobayes.mlmap"
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
        Table::<3, 4, 2, 4, 4, 0, 1>::from_bytes(include_bytes!("../golden/layer/small_osf.mlmap"))
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
        "../golden/layer/small_maps.mlmap"
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
