//! The quantized section: int8 codes scored by its three heads, read at run time and
//! embedded at build time.

use super::*;

/// The quantized cases with the three heads of `q`: the codes dequantize to the host's
/// float32 logits bit for bit, and the scores match the host's float64 values.
pub(crate) fn check_quantized(r: &mut Report, name: &str, q: &EmbeddedQTable) {
    for qc in QCASES {
        let codes = black_box(qc.codes);
        let os = black_box(qc.case.objectness);
        let same = (0..K).all(|c| {
            q.params(c) == Some((Q_SCALES[c], Q_ZERO_POINTS[c]))
                && dequantize(codes[c].into(), Q_SCALES[c], Q_ZERO_POINTS[c]).to_bits()
                    == qc.case.logits[c].to_bits()
        });
        r.check(
            same,
            qc.case.label,
            format_args!("{name}: the codes do not dequantize to the host's logits"),
        );
        let e = check_head(r, name, "int8 ML", &qc.case, q.ml(&codes, os), &qc.case.ml);
        r.max_err_ml = r.max_err_ml.max(e);
        let e = check_head(
            r,
            name,
            "int8 MAP",
            &qc.case,
            q.map(&codes, os),
            &qc.case.map,
        );
        r.max_err_map = r.max_err_map.max(e);
        let got = q.bayes(&codes, os);
        let e = check_head(r, name, "int8 Bayes", &qc.case, got, &qc.case.bayes);
        r.max_err_bayes = r.max_err_bayes.max(e);
        let got = q.open(&codes, os);
        let e = check_open(r, name, "int8 open", &qc.case, got, &qc.case.open);
        r.max_err_open = r.max_err_open.max(e);
        // Bit for bit the f32 table's scores on the dequantized logits.
        let x = qc.case.logits;
        let exact = q.ml(&codes, os) == TABLE.ml(&x, os)
            && q.map(&codes, os) == TABLE.map(&x, os)
            && q.bayes(&codes, os) == TABLE.bayes(&x, os)
            && q.open(&codes, os) == TABLE.open(&x, os);
        r.check(
            exact,
            qc.case.label,
            format_args!("{name}: not the f32 table's scores on the dequantized logits"),
        );
    }
    r.check(
        q.ml(&[0; K], 1.5) == Err(InferError::Objectness),
        "quantized objectness",
        format_args!("{name}: an objectness of 1.5 is not refused"),
    );
}

/// The quantized section read at run time from its bytes in flash; a damaged copy is
/// refused.
pub(crate) fn decode_quantized(r: &mut Report) -> Option<EmbeddedQTable> {
    let bytes: &'static [u8] = black_box(&QUANTIZED_SECTION[..]);
    let q = match EmbeddedQTable::from_bytes(bytes) {
        Ok(q) => q,
        Err(e) => {
            r.check(false, "quantized decode", format_args!("{e:?}"));
            return None;
        }
    };
    r.check(
        q == QUANTIZED,
        "quantized embeddings agree",
        format_args!("the section read at run time differs from the one embedded"),
    );
    let mut copy = [0u8; QUANTIZED_SECTION.len()];
    copy.copy_from_slice(bytes);
    copy[QUANTIZED_SECTION.len() / 2] ^= 0x01;
    let damaged = mlmap::QTable::<K, i8>::from_bytes(black_box(&copy)).err();
    r.check(
        damaged == Some(QTableError::Corrupted),
        "damaged quantized section",
        format_args!("got {damaged:?}, want Corrupted"),
    );
    Some(q)
}
