//! NPY directories written by numpy and npyz, labels of every integer dtype, every
//! malformed directory.

use super::*;

#[test]
fn numpy_written_directory_f32_logits_i16_labels() {
    // tests/fixtures/npy_small, written by tools/make_npy_fixtures.py.
    let (src, rows) = read_all(&fixture("npy_small")).unwrap();
    assert_eq!(src.classes(), ["car", "cyclist", "pedestrian"]);
    assert!(src.has_labels() && src.has_objectness() && !src.has_ids());
    assert_eq!(src.row_count_hint(), Some(5));
    let want = [
        npy_row(0, Label::Class(0), 0.93, [4.1, -2.3, -1.7]),
        npy_row(1, Label::Background, 0.55, [1.2, 0.3, -0.4]),
        npy_row(2, Label::Class(1), 1.0, [-1.0, 2.5, 0.5]),
        npy_row(3, Label::Class(2), 0.0, [0.25, -0.5, 3.75]),
        npy_row(4, Label::Class(0), 0.5, [2.0, 2.0, 2.0]),
    ];
    assert_eq!(rows, want);
}

#[test]
fn numpy_written_directory_big_endian_f64_u8_labels_default_names() {
    let (src, rows) = read_all(&fixture("npy_bigendian")).unwrap();
    assert_eq!(src.classes(), ["class0", "class1", "class2"]);
    assert!(src.has_labels() && !src.has_objectness());
    let labels: Vec<Label> = rows.iter().map(|r| r.label).collect();
    assert_eq!(
        labels,
        [0, 1, 2, 1, 0].map(Label::Class),
        "labels of npy_bigendian"
    );
    assert_eq!(rows[0].logits, [4.1, -2.3, -1.7]);
    assert!(rows.iter().all(|r| r.objectness == 1.0));
}

#[test]
fn fortran_order_is_refused() {
    let err = DataSource::open(&fixture("npy_fortran")).unwrap_err();
    assert_eq!(err.kind(), &DataErrorKind::NpyFortranOrder);
    assert!(err.path().ends_with("logits.npy"));
    assert!(err.is_bad_input());
}

#[test]
fn npyz_written_directory() {
    let dir = npy_dir();
    let (src, rows) = read_all(dir.path()).unwrap();
    assert_eq!(src.classes(), ["car", "cyclist"]);
    let labels: Vec<Label> = rows.iter().map(|r| r.label).collect();
    assert_eq!(
        labels,
        [
            Label::Class(0),
            Label::Class(1),
            Label::Background,
            Label::Class(1)
        ]
    );
    let os: Vec<f64> = rows.iter().map(|r| r.objectness).collect();
    assert_eq!(os, [0.5, 1.0, 0.0, 0.25]);
    assert_eq!(rows[3].logits, [7.0, 8.0]);
    assert_eq!(rows[3].index, 3);
}

#[test]
fn labels_of_every_integer_dtype() {
    fn check<T: npyz::AutoSerialize + Clone>(labels: &[T]) {
        let dir = npy_dir();
        write_npy(&dir.path().join("labels.npy"), &[4], labels);
        let (_, rows) = read_all(dir.path()).unwrap();
        let got: Vec<Label> = rows.iter().map(|r| r.label).collect();
        assert_eq!(&got[..2], [Label::Class(1), Label::Class(0)]);
    }
    check(&[1i8, 0, 0, 0]);
    check(&[1i16, 0, 0, 0]);
    check(&[1i32, 0, 0, 0]);
    check(&[1i64, 0, 0, 0]);
    check(&[1u8, 0, 0, 0]);
    check(&[1u16, 0, 0, 0]);
    check(&[1u32, 0, 0, 0]);
    check(&[1u64, 0, 0, 0]);
}

#[test]
fn every_malformed_npy_directory_is_refused() {
    // (edit, kind, file, location, column)
    type Edit = Box<dyn FnOnce(&Path)>;
    type Case = (
        Edit,
        DataErrorKind,
        &'static str,
        Option<Location>,
        Option<&'static str>,
    );
    let cases: Vec<Case> = vec![
        (
            Box::new(|d: &Path| write_npy(&d.join("logits.npy"), &[8], &[0.0f64; 8])),
            DataErrorKind::NpyShape {
                found: vec![8],
                expected: "(N, K): N rows of K logits",
            },
            "logits.npy",
            None,
            None,
        ),
        (
            Box::new(|d: &Path| write_npy(&d.join("logits.npy"), &[4, 2], &[1i32; 8])),
            DataErrorKind::NpyDtype {
                found: "<i4".into(),
                expected: "float32 or float64",
            },
            "logits.npy",
            None,
            None,
        ),
        (
            Box::new(|d: &Path| write_npy(&d.join("logits.npy"), &[4, 1], &[1.0f64; 4])),
            DataErrorKind::ClassCount { found: 1 },
            "logits.npy",
            None,
            None,
        ),
        (
            Box::new(|d: &Path| write_npy(&d.join("labels.npy"), &[4], &[0.0f32; 4])),
            DataErrorKind::NpyDtype {
                found: "<f4".into(),
                expected: "an integer type",
            },
            "labels.npy",
            None,
            None,
        ),
        (
            Box::new(|d: &Path| write_npy(&d.join("labels.npy"), &[3], &[0i64; 3])),
            DataErrorKind::RowCount {
                expected: 4,
                found: 3,
            },
            "labels.npy",
            None,
            None,
        ),
        (
            Box::new(|d: &Path| write_npy(&d.join("labels.npy"), &[4, 1], &[0i64; 4])),
            DataErrorKind::NpyShape {
                found: vec![4, 1],
                expected: "(N,): one value per row",
            },
            "labels.npy",
            None,
            None,
        ),
        (
            Box::new(|d: &Path| write_npy(&d.join("objectness.npy"), &[5], &[0.5f64; 5])),
            DataErrorKind::RowCount {
                expected: 4,
                found: 5,
            },
            "objectness.npy",
            None,
            None,
        ),
        (
            Box::new(|d: &Path| write_npy(&d.join("labels.npy"), &[4], &[0i64, 1, 2, 0])),
            DataErrorKind::LabelIndex {
                value: 2,
                classes: 2,
            },
            "labels.npy",
            Some(Location::Row(2)),
            None,
        ),
        (
            Box::new(|d: &Path| write_npy(&d.join("labels.npy"), &[4], &[-2i8, 1, 1, 0])),
            DataErrorKind::LabelIndex {
                value: -2,
                classes: 2,
            },
            "labels.npy",
            Some(Location::Row(0)),
            None,
        ),
        (
            Box::new(|d: &Path| {
                write_npy(
                    &d.join("objectness.npy"),
                    &[4],
                    &[0.5f64, f64::NAN, 0.0, 0.0],
                )
            }),
            DataErrorKind::ObjectnessRange { text: "NaN".into() },
            "objectness.npy",
            Some(Location::Row(1)),
            None,
        ),
        (
            Box::new(|d: &Path| {
                write_npy(&d.join("objectness.npy"), &[4], &[0.5f64, 1.0, 1.25, 0.0])
            }),
            DataErrorKind::ObjectnessRange {
                text: "1.25".into(),
            },
            "objectness.npy",
            Some(Location::Row(2)),
            None,
        ),
        (
            Box::new(|d: &Path| {
                let mut v = [1.0f32; 8];
                v[5] = f32::INFINITY;
                write_npy(&d.join("logits.npy"), &[4, 2], &v)
            }),
            DataErrorKind::NotFinite { text: "inf".into() },
            "logits.npy",
            Some(Location::Row(2)),
            Some("cyclist"),
        ),
        (
            Box::new(|d: &Path| {
                let mut v = [1.0f64; 8];
                v[6] = f64::NAN;
                write_npy(&d.join("logits.npy"), &[4, 2], &v)
            }),
            DataErrorKind::NotFinite { text: "NaN".into() },
            "logits.npy",
            Some(Location::Row(3)),
            Some("car"),
        ),
        (
            Box::new(|d: &Path| {
                let p = d.join("logits.npy");
                let bytes = std::fs::read(&p).unwrap();
                std::fs::write(&p, &bytes[..bytes.len() - 3]).unwrap();
            }),
            DataErrorKind::NpySize {
                expected: 64,
                found: 61,
            },
            "logits.npy",
            None,
            None,
        ),
        (
            Box::new(|d: &Path| {
                let p = d.join("labels.npy");
                let mut bytes = std::fs::read(&p).unwrap();
                bytes.extend_from_slice(&[0; 8]);
                std::fs::write(&p, &bytes).unwrap();
            }),
            DataErrorKind::NpySize {
                expected: 32,
                found: 40,
            },
            "labels.npy",
            None,
            None,
        ),
        (
            Box::new(|d: &Path| std::fs::write(d.join("classes.txt"), "car\n").unwrap()),
            DataErrorKind::ClassListLength {
                expected: 2,
                found: 1,
            },
            "classes.txt",
            None,
            None,
        ),
        (
            Box::new(|d: &Path| {
                std::fs::write(d.join("classes.txt"), "car\nbackground\n").unwrap()
            }),
            DataErrorKind::ReservedClassName,
            "classes.txt",
            Some(Location::Line(2)),
            None,
        ),
        (
            Box::new(|d: &Path| std::fs::write(d.join("classes.txt"), "car\ncar\n").unwrap()),
            DataErrorKind::DuplicateColumn,
            "classes.txt",
            Some(Location::Line(2)),
            None,
        ),
        (
            Box::new(|d: &Path| std::fs::write(d.join("classes.txt"), "\ncar\n").unwrap()),
            DataErrorKind::EmptyColumnName { index: 1 },
            "classes.txt",
            Some(Location::Line(1)),
            None,
        ),
        (
            Box::new(|d: &Path| std::fs::write(d.join("classes.txt"), b"car\n\xff\n").unwrap()),
            DataErrorKind::NotUtf8,
            "classes.txt",
            None,
            None,
        ),
    ];
    for (i, (edit, kind, name, location, column)) in cases.into_iter().enumerate() {
        let err = npy_error(edit);
        assert_eq!(err.kind(), &kind, "case {i}: {err}");
        assert!(err.path().ends_with(name), "case {i}: {err}");
        assert_eq!(err.location(), location, "case {i}: {err}");
        assert_eq!(err.column(), column, "case {i}: {err}");
    }
}

#[test]
fn a_file_that_is_not_npy_is_refused() {
    for bytes in [
        &b""[..],
        b"id,label\n1,car\n",
        b"\x93NUMPY\x01\x00\x10\x00{'descr': ",
    ] {
        let err = npy_error(|d| std::fs::write(d.join("logits.npy"), bytes).unwrap());
        assert!(
            matches!(err.kind(), DataErrorKind::NpyFormat { .. }),
            "{bytes:?}: {err}"
        );
    }
}

#[test]
fn npy_error_display_says_row_index() {
    let err = npy_error(|d| write_npy(&d.join("labels.npy"), &[4], &[0i64, 1, 7, 0]));
    let shown = err.to_string();
    assert!(
        shown.ends_with(
            "labels.npy: row index 2: label 7 is not a class index (0 to 1) or -1 (background)"
        ),
        "{shown}"
    );
}
