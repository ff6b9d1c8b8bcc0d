//! NPY rows across the reader's chunks: errors in later chunks, exact labels, sizes that
//! overflow.

use super::*;

/// Rows that span several read chunks (the reader works on a few thousand rows at a
/// time): f32 logits, i32 labels, f64 objectness.
const MANY: usize = 20_011;

fn many_logits() -> Vec<f32> {
    (0..MANY * 3)
        .map(|i| (i % 977) as f32 * 0.25 - 100.0)
        .collect()
}

fn many_labels() -> Vec<i32> {
    (0..MANY).map(|i| (i % 4) as i32 - 1).collect()
}

fn many_objectness() -> Vec<f64> {
    (0..MANY).map(|i| (i % 101) as f64 / 100.0).collect()
}

fn many_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_npy(&d.join("logits.npy"), &[MANY as u64, 3], &many_logits());
    write_npy(&d.join("labels.npy"), &[MANY as u64], &many_labels());
    write_npy(
        &d.join("objectness.npy"),
        &[MANY as u64],
        &many_objectness(),
    );
    dir
}

/// Reads `dir` and returns the rows produced before the error, and the error.
fn rows_before_error(dir: &Path) -> (usize, DataError) {
    let src = DataSource::open(dir).unwrap();
    let mut n = 0;
    let err = src
        .for_each_row(|r| {
            assert_eq!(r.index, n as u64);
            n += 1;
            Ok::<(), DataError>(())
        })
        .unwrap_err();
    (n, err)
}

#[test]
fn many_rows_across_read_chunks() {
    let dir = many_dir();
    let (src, rows) = read_all(dir.path()).unwrap();
    assert_eq!(src.row_count_hint(), Some(MANY as u64));
    assert_eq!(rows.len(), MANY);
    let (x, labels, os) = (many_logits(), many_labels(), many_objectness());
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r.index, i as u64);
        let want: Vec<f64> = x[3 * i..3 * i + 3].iter().map(|&v| f64::from(v)).collect();
        assert_eq!(r.logits, want, "row {i}");
        let label = match labels[i] {
            -1 => Label::Background,
            c => Label::Class(c as usize),
        };
        assert_eq!((r.label, r.objectness), (label, os[i]), "row {i}");
    }
}

#[test]
fn an_error_in_a_later_chunk_comes_after_every_row_before_it() {
    let at = 17_003;
    type Edit = Box<dyn Fn(&Path)>;
    let cases: Vec<(Edit, DataErrorKind, &str, Option<&str>)> = vec![
        (
            Box::new(move |d: &Path| {
                let mut x = many_logits();
                x[3 * at + 2] = f32::NEG_INFINITY;
                x[3 * at + 5] = f32::NAN; // a later row: not reported
                write_npy(&d.join("logits.npy"), &[MANY as u64, 3], &x);
            }),
            DataErrorKind::NotFinite {
                text: "-inf".into(),
            },
            "logits.npy",
            Some("class2"),
        ),
        (
            Box::new(move |d: &Path| {
                let mut l = many_labels();
                l[at] = 3;
                write_npy(&d.join("labels.npy"), &[MANY as u64], &l);
            }),
            DataErrorKind::LabelIndex {
                value: 3,
                classes: 3,
            },
            "labels.npy",
            None,
        ),
        (
            Box::new(move |d: &Path| {
                let mut o = many_objectness();
                o[at] = -0.5;
                write_npy(&d.join("objectness.npy"), &[MANY as u64], &o);
            }),
            DataErrorKind::ObjectnessRange {
                text: "-0.5".into(),
            },
            "objectness.npy",
            None,
        ),
        (
            // In one row, the logits are checked before the label and the objectness.
            Box::new(move |d: &Path| {
                let mut x = many_logits();
                x[3 * at + 1] = f32::INFINITY;
                write_npy(&d.join("logits.npy"), &[MANY as u64, 3], &x);
                let mut l = many_labels();
                l[at] = 9;
                write_npy(&d.join("labels.npy"), &[MANY as u64], &l);
            }),
            DataErrorKind::NotFinite { text: "inf".into() },
            "logits.npy",
            Some("class1"),
        ),
    ];
    for (i, (edit, kind, name, column)) in cases.into_iter().enumerate() {
        let dir = many_dir();
        edit(dir.path());
        let (produced, err) = rows_before_error(dir.path());
        assert_eq!(produced, at, "case {i}: {err}");
        assert_eq!(err.kind(), &kind, "case {i}: {err}");
        assert!(err.path().ends_with(name), "case {i}: {err}");
        assert_eq!(err.location(), Some(Location::Row(at as u64)), "case {i}");
        assert_eq!(err.column(), column, "case {i}: {err}");
    }
}

#[test]
fn a_u64_label_beyond_i64_is_reported_exactly() {
    let dir = npy_dir();
    let big = u64::MAX - 6;
    write_npy(&dir.path().join("labels.npy"), &[4], &[0u64, 1, big, 1]);
    let (produced, err) = rows_before_error(dir.path());
    assert_eq!(produced, 2);
    assert_eq!(
        err.kind(),
        &DataErrorKind::LabelIndex {
            value: i128::from(big),
            classes: 2,
        }
    );
}

#[test]
fn big_endian_float32_and_int32() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let x = [4.1f32, -2.3, 1.2e-30, 0.25];
    let data: Vec<u8> = x.iter().flat_map(|v| v.to_be_bytes()).collect();
    write_raw_npy(&d.join("logits.npy"), ">f4", "(2, 2)", &data);
    let data: Vec<u8> = [-1i32, 1].iter().flat_map(|v| v.to_be_bytes()).collect();
    write_raw_npy(&d.join("labels.npy"), ">i4", "(2,)", &data);
    let data: Vec<u8> = [0.75f32, 1.0]
        .iter()
        .flat_map(|v| v.to_be_bytes())
        .collect();
    write_raw_npy(&d.join("objectness.npy"), ">f4", "(2,)", &data);
    let (_, rows) = read_all(d).unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0].logits, [f64::from(4.1f32), f64::from(-2.3f32)]);
    assert_eq!(rows[1].logits, [f64::from(1.2e-30f32), 0.25]);
    assert_eq!(rows[0].label, Label::Background);
    assert_eq!(rows[1].label, Label::Class(1));
    assert_eq!((rows[0].objectness, rows[1].objectness), (0.75, 1.0));
}

#[test]
fn an_npy_shape_whose_size_overflows_is_too_large() {
    let dir = npy_dir();
    write_raw_npy(
        &dir.path().join("logits.npy"),
        "<f4",
        "(4611686018427387904, 3)",
        &[],
    );
    let err = read_all(dir.path()).unwrap_err();
    assert_eq!(
        err.kind(),
        &DataErrorKind::NpyTooLarge {
            shape: vec![4611686018427387904, 3]
        }
    );
    let msg = err.to_string();
    assert!(msg.contains("too large"), "{msg}");
    assert!(!msg.contains("18446744073709551615"), "{msg}");
}
