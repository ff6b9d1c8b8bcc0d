//! The conformal section: kept with the table and the other sections, every check of its
//! bytes, and the errors of the sets.

use super::*;
use crate::support::resealed;

#[test]
fn the_section_keeps_the_table_and_the_other_sections() {
    let (table, bytes) = default_table();
    let f = fitted(
        Head::Open,
        0.1,
        vec![100, 5, 40],
        vec![0.5, f32::NEG_INFINITY, 0.2],
    );
    let params = MonitorParams {
        window: 50,
        alpha: 0.0,
        thresholds: Thresholds::NONE,
    };
    let with_both = with_conformal(&with_monitor(&bytes, &table, &params).unwrap(), &f).unwrap();
    assert_eq!(table_of(&with_both), &bytes[..]);
    assert_eq!(
        with_both.len(),
        bytes.len() + mlmap::monitor_section_len(3, 22) + conformal_section_len(3)
    );
    // Every table decoder reads the file; the monitor still reads; a monitor written
    // later keeps the conformal section.
    DynTable::from_bytes(&with_both).unwrap();
    Table::<3, 22, 17, 22, 4>::from_bytes(&with_both).unwrap();
    MonitorSpec::from_bytes(&with_both, &table.view()).unwrap();
    let again = with_monitor(&with_both, &table, &params).unwrap();
    let spec = ConformalSpec::from_bytes(&again, &table.view()).unwrap();
    assert_eq!(spec.threshold(1), Some(f32::NEG_INFINITY));
    assert_eq!(spec.calibration_rows(2), Some(40));
    // A table without the section: absent, and it decodes as before.
    assert_eq!(
        ConformalSpec::from_bytes(&bytes, &table.view()).unwrap_err(),
        ConformalError::Absent
    );
    // The section alone reads against the table by shape.
    let alone = section_of(&with_both, CONFORMAL_MAGIC).unwrap();
    ConformalSpec::from_bytes(alone, &table.view()).unwrap();
}

#[test]
fn every_check_of_the_section() {
    let (table, bytes) = default_table();
    let v = table.view();
    let f = fitted(
        Head::Map,
        0.1,
        vec![100, 5, 40],
        vec![0.5, f32::NEG_INFINITY, 0.2],
    );
    let file = with_conformal(&bytes, &f).unwrap();
    let sec = section_of(&file, CONFORMAL_MAGIC).unwrap().to_vec();
    let err = |s: &[u8]| ConformalSpec::from_bytes(s, &v).unwrap_err();
    assert_eq!(
        err(&resealed(&sec, 4, &[2])),
        ConformalError::UnsupportedVersion { found: 2 }
    );
    assert_eq!(err(&resealed(&sec, 5, &[4])), ConformalError::Malformed);
    assert_eq!(err(&resealed(&sec, 6, &[1])), ConformalError::Malformed);
    assert_eq!(err(&resealed(&sec, 10, &[1])), ConformalError::Malformed);
    assert_eq!(
        err(&resealed(&sec, 8, &4u16.to_le_bytes())),
        ConformalError::ShapeMismatch {
            expected: 3,
            found: 4
        }
    );
    for a in [0.0f32, 1.0, -0.1, f32::NAN] {
        assert_eq!(
            err(&resealed(&sec, 16, &a.to_le_bytes())),
            ConformalError::Alpha
        );
    }
    // Thresholds: NaN, above 1, -inf where the rows give a rank, finite where they
    // give none.
    for (at, t) in [
        (24, f32::NAN),
        (24, 1.5),
        (24, f32::NEG_INFINITY),
        (24, -0.1),
        (32, 0.3),
    ] {
        let class = ((at - 24) / 8) as u16;
        assert_eq!(
            err(&resealed(&sec, at, &t.to_le_bytes())),
            ConformalError::Threshold {
                class: class.max(if at == 32 { 1 } else { 0 })
            }
        );
    }
    // Rows of class 1 raised to 9: rank floor(10 * 0.1) = 1, so -inf no longer fits.
    assert_eq!(
        err(&resealed(&sec, 28, &9u32.to_le_bytes())),
        ConformalError::Threshold { class: 1 }
    );
    // A flipped byte: the CRC; the section after another table: TableMismatch.
    let mut bad = file.clone();
    let n = bad.len();
    bad[n - 12] ^= 1;
    assert_eq!(
        ConformalSpec::from_bytes(&bad, &v).unwrap_err(),
        ConformalError::Corrupted
    );
    let mut other = bytes.clone();
    other.extend_from_slice(&resealed(&sec, 12, &0u32.to_le_bytes()));
    assert_eq!(
        ConformalSpec::from_bytes(&other, &v).unwrap_err(),
        ConformalError::TableMismatch
    );
    // Every truncation is refused or reads as no section; none panics.
    for cut in 0..file.len() {
        let _ = ConformalSpec::from_bytes(&file[..cut], &v);
    }
    // A head the table lacks.
    let no_bayes = wide_table(&["a".into(), "b".into(), "c".into()]);
    let nb = no_bayes.to_vec().unwrap();
    let f = fitted(
        Head::Open,
        0.1,
        vec![100, 5, 40],
        vec![0.5, f32::NEG_INFINITY, 0.2],
    );
    let file = with_conformal(&nb, &f).unwrap();
    assert_eq!(
        ConformalSpec::from_bytes(&file, &no_bayes.view()).unwrap_err(),
        ConformalError::MissingHead { head: Head::Open }
    );
    // The writer refuses a buffer of another size and mismatched lengths.
    let mut buf = vec![0u8; conformal_section_len(3) - 1];
    assert_eq!(
        write_conformal_section(&mut buf, 0, Head::Ml, 0.1, &[1, 2, 3], &[0.0; 3]),
        Err(ConformalError::BufferTooSmall)
    );
    assert_eq!(
        write_conformal_section(&mut buf, 0, Head::Ml, 0.1, &[1, 2], &[0.0; 3]),
        Err(ConformalError::Malformed)
    );
}

#[test]
fn set_errors_and_the_u64_form() {
    let (table, bytes) = default_table();
    let f = fitted(
        Head::Map,
        0.1,
        vec![100, 5, 40],
        vec![0.5, f32::NEG_INFINITY, 0.2],
    );
    let file = with_conformal(&bytes, &f).unwrap();
    let spec = ConformalSpec::from_bytes(&file, &table.view()).unwrap();
    let mut mask = [7u32; 2];
    assert_eq!(spec.set_of(&[0.5, 0.0, 0.19], &mut mask), Ok(2));
    assert_eq!(mask, [0b011, 7], "only the first word is written");
    assert_eq!(
        spec.set_of(&[0.5, f32::NAN, 0.19], &mut mask),
        Err(InferError::NanScore { class: 1 })
    );
    assert_eq!(spec.set_of(&[0.5, 0.1], &mut mask), Err(InferError::Length));
    assert_eq!(
        spec.set_of(&[0.5, 0.1, 0.3], &mut []),
        Err(InferError::Length)
    );
    let v = table.view();
    let (mut s, mut scratch) = ([0.0f32; 3], [0.0f32; 4]);
    let set = spec
        .set64(&v, &[6.0, -3.0, -3.0], 1.0, &mut s, &mut scratch)
        .unwrap();
    let mut want = 0u64;
    for (c, &score) in s.iter().enumerate() {
        if score >= spec.threshold(c).unwrap() {
            want |= 1 << c;
        }
    }
    assert_eq!(set, want);
    assert_eq!(
        spec.set64(&v, &[f32::NAN, 0.0, 0.0], 1.0, &mut s, &mut scratch),
        Err(InferError::NanLogit { class: 0 })
    );
    assert_eq!(
        spec.set64(&v, &[0.0, 0.0, 0.0], 1.5, &mut s, &mut scratch),
        Err(InferError::Objectness)
    );
}
