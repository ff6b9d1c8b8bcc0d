//! `mlmap::host::dataset`: CSV and NPY inputs, valid and malformed.

use std::path::{Path, PathBuf};

use mlmap::host::dataset::{DataError, DataErrorKind, DataSource, Label, Location, Row};
use npyz::WriterBuilder;

/// A row copied out of the callback.
#[derive(Debug, Clone, PartialEq)]
struct Owned {
    index: u64,
    line: Option<u64>,
    id: Option<String>,
    label: Label,
    objectness: f64,
    logits: Vec<f64>,
}

impl From<Row<'_>> for Owned {
    fn from(r: Row<'_>) -> Self {
        Self {
            index: r.index,
            line: r.line,
            id: r.id.map(str::to_string),
            label: r.label,
            objectness: r.objectness,
            logits: r.logits.to_vec(),
        }
    }
}

fn read_all(path: &Path) -> Result<(DataSource, Vec<Owned>), DataError> {
    let src = DataSource::open(path)?;
    let mut rows = Vec::new();
    src.for_each_row(|r| {
        rows.push(Owned::from(r));
        Ok::<(), DataError>(())
    })?;
    Ok((src, rows))
}

/// Writes `bytes` to `name` in a fresh temporary directory.
fn file(name: &str, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    (dir, path)
}

fn csv_error(text: &str) -> DataError {
    let (_dir, path) = file("data.csv", text.as_bytes());
    let err = read_all(&path).expect_err(text);
    assert_eq!(err.path(), path, "{err}");
    assert!(err.is_bad_input(), "{err}");
    err
}

fn row(index: u64, line: u64, id: Option<&str>, label: Label, os: f64, logits: &[f64]) -> Owned {
    Owned {
        index,
        line: Some(line),
        id: id.map(str::to_string),
        label,
        objectness: os,
        logits: logits.to_vec(),
    }
}

#[test]
fn csv_with_id_and_objectness() {
    let text = "id,label,objectness,car,cyclist,pedestrian\n\
                17,car,0.93,4.1,-2.3,-1.7\n\
                18,background,0.55,1.2,0.3,-0.4\n\
                a-19,,1,0,0,0\n\
                20,pedestrian,0,1e-3,-2E2,3\n";
    let (_dir, path) = file("d.csv", text.as_bytes());
    let (src, rows) = read_all(&path).unwrap();
    assert_eq!(src.classes(), ["car", "cyclist", "pedestrian"]);
    assert!(src.has_labels() && src.has_ids() && src.has_objectness());
    assert_eq!(src.path(), path);
    assert_eq!(src.row_count_hint(), None);
    let want = [
        row(0, 2, Some("17"), Label::Class(0), 0.93, &[4.1, -2.3, -1.7]),
        row(1, 3, Some("18"), Label::Background, 0.55, &[1.2, 0.3, -0.4]),
        row(2, 4, Some("a-19"), Label::Missing, 1.0, &[0.0, 0.0, 0.0]),
        row(
            3,
            5,
            Some("20"),
            Label::Class(2),
            0.0,
            &[0.001, -200.0, 3.0],
        ),
    ];
    assert_eq!(rows, want);
}

#[test]
fn csv_without_id_objectness_or_labels() {
    // Columns in any order; objectness defaults to 1; whitespace is trimmed; CRLF.
    let text = "b , label, a\r\n 1.5 , a ,-1\r\n\r\n2,b,0.25\r\n";
    let (_dir, path) = file("d.csv", text.as_bytes());
    let (src, rows) = read_all(&path).unwrap();
    assert_eq!(src.classes(), ["b", "a"]);
    assert!(src.has_labels() && !src.has_ids() && !src.has_objectness());
    assert_eq!(
        rows,
        [
            row(0, 2, None, Label::Class(1), 1.0, &[1.5, -1.0]),
            row(1, 4, None, Label::Class(0), 1.0, &[2.0, 0.25]),
        ]
    );
    // A bad field after a CRLF blank line reports its true line; a quoted last field
    // before CRLF is read without the CR.
    let (_dir, path) = file("d.csv", b"label,a,b\r\n\r\na,1,\"2\"\r\na,x,2\r\n");
    let err = read_all(&path).unwrap_err();
    assert_eq!(err.line(), Some(4), "{err}");
    assert_eq!(err.column(), Some("a"), "{err}");

    let (_dir, path) = file("d.csv", b"x,y\n1,2\n");
    let (src, rows) = read_all(&path).unwrap();
    assert!(!src.has_labels());
    assert_eq!(rows, [row(0, 2, None, Label::Missing, 1.0, &[1.0, 2.0])]);
}

#[test]
fn csv_header_only_has_no_rows_and_a_bom_is_ignored() {
    let (_dir, path) = file("d.csv", "\u{feff}label,a,b\n".as_bytes());
    let (src, rows) = read_all(&path).unwrap();
    assert!(src.has_labels());
    assert_eq!(src.classes(), ["a", "b"]);
    assert!(rows.is_empty());
}

#[test]
fn csv_rows_can_be_read_twice_and_callbacks_stop_the_stream() {
    let text = "label,a,b\na,1,2\nb,3,4\na,5,6\n";
    let (_dir, path) = file("d.csv", text.as_bytes());
    let (src, first) = read_all(&path).unwrap();
    let mut second = Vec::new();
    src.for_each_row(|r| {
        second.push(Owned::from(r));
        Ok::<(), DataError>(())
    })
    .unwrap();
    assert_eq!(first, second);

    #[derive(Debug, PartialEq)]
    enum E {
        Data,
        Stop(u64),
    }
    impl From<DataError> for E {
        fn from(_: DataError) -> Self {
            E::Data
        }
    }
    let mut seen = 0;
    let r = src.for_each_row(|r| {
        seen += 1;
        if r.index == 1 {
            Err(E::Stop(r.index))
        } else {
            Ok(())
        }
    });
    assert_eq!(r, Err(E::Stop(1)));
    assert_eq!(seen, 2);
}

#[test]
fn csv_error_display_names_file_line_and_column() {
    let text = "id,label,objectness,car,cyclist\n1,car,0.5,1.0,2.0\n2,car,0.5,1.0,abc\n";
    let (_dir, path) = file("x.csv", text.as_bytes());
    let err = read_all(&path).unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "{}:3: column \"cyclist\": \"abc\" is not a number",
            path.display()
        )
    );
}

#[test]
fn every_malformed_csv_is_refused_with_its_position() {
    let long = "n".repeat(32);
    let long_header = format!("label,a,{long}\n");
    // (input, kind, line, column)
    let cases: Vec<(&str, DataErrorKind, Option<u64>, Option<&str>)> = vec![
        (
            "label,a,b\na,1,2\nb,1\n",
            DataErrorKind::FieldCount {
                expected: 3,
                found: 2,
            },
            Some(3),
            None,
        ),
        (
            "label,a,b\na,1,2,3\n",
            DataErrorKind::FieldCount {
                expected: 3,
                found: 4,
            },
            Some(2),
            None,
        ),
        (
            "label,a,b\na,1,2x\n",
            DataErrorKind::NotANumber { text: "2x".into() },
            Some(2),
            Some("b"),
        ),
        (
            "label,a,b\ntruck,1,2\n",
            DataErrorKind::UnknownLabel {
                text: "truck".into(),
            },
            Some(2),
            Some("label"),
        ),
        (
            "label,a,b\nBackground,1,2\n",
            DataErrorKind::UnknownLabel {
                text: "Background".into(),
            },
            Some(2),
            Some("label"),
        ),
        (
            "label,a,b\na,NaN,2\n",
            DataErrorKind::NotFinite { text: "NaN".into() },
            Some(2),
            Some("a"),
        ),
        (
            "label,a,b\na,1,-inf\n",
            DataErrorKind::NotFinite {
                text: "-inf".into(),
            },
            Some(2),
            Some("b"),
        ),
        (
            "label,a,b\na,1,1e400\n",
            DataErrorKind::NotFinite {
                text: "1e400".into(),
            },
            Some(2),
            Some("b"),
        ),
        (
            "label,a,b\na,,2\n",
            DataErrorKind::MissingValue,
            Some(2),
            Some("a"),
        ),
        (
            "label,objectness,a,b\na,nan,1,2\n",
            DataErrorKind::ObjectnessRange { text: "nan".into() },
            Some(2),
            Some("objectness"),
        ),
        (
            "label,objectness,a,b\na,1.5,1,2\n",
            DataErrorKind::ObjectnessRange { text: "1.5".into() },
            Some(2),
            Some("objectness"),
        ),
        (
            "label,objectness,a,b\na,-0.01,1,2\n",
            DataErrorKind::ObjectnessRange {
                text: "-0.01".into(),
            },
            Some(2),
            Some("objectness"),
        ),
        (
            "label,objectness,a,b\na,,1,2\n",
            DataErrorKind::MissingValue,
            Some(2),
            Some("objectness"),
        ),
        (
            "label,objectness,a,b\na,high,1,2\n",
            DataErrorKind::NotANumber {
                text: "high".into(),
            },
            Some(2),
            Some("objectness"),
        ),
        (
            "id,label,objectness\n",
            DataErrorKind::ClassCount { found: 0 },
            Some(1),
            None,
        ),
        (
            "label,car\ncar,1\n",
            DataErrorKind::ClassCount { found: 1 },
            Some(1),
            None,
        ),
        (
            "label,car,cyclist,car\n",
            DataErrorKind::DuplicateColumn,
            Some(1),
            Some("car"),
        ),
        (
            "label,a,b,label\n",
            DataErrorKind::DuplicateColumn,
            Some(1),
            Some("label"),
        ),
        (
            "label,car,background\n",
            DataErrorKind::ReservedClassName,
            Some(1),
            Some("background"),
        ),
        (
            &long_header,
            DataErrorKind::ClassNameTooLong { len: 32 },
            Some(1),
            Some(long.as_str()),
        ),
        (
            "label,a,,b\n",
            DataErrorKind::EmptyColumnName { index: 3 },
            Some(1),
            None,
        ),
        // Blank lines, line breaks in quoted fields and a missing final line break do
        // not shift line numbers: the line is where the record starts.
        (
            "label,a,b\na,1,2\n\n\na,1,zz\n",
            DataErrorKind::NotANumber { text: "zz".into() },
            Some(5),
            Some("b"),
        ),
        (
            "id,label,a,b\n\"x\ny\",a,1,2\n7,a,1,q",
            DataErrorKind::NotANumber { text: "q".into() },
            Some(4),
            Some("b"),
        ),
        (
            "id,label,a,b\n\"x\n\ny\n\",a,1,q\n",
            DataErrorKind::NotANumber { text: "q".into() },
            Some(2),
            Some("b"),
        ),
        // Blank lines before the header do not shift its line number.
        (
            "\n\nlabel,a,a\n",
            DataErrorKind::DuplicateColumn,
            Some(3),
            Some("a"),
        ),
        ("", DataErrorKind::Empty, None, None),
        ("\n\n", DataErrorKind::Empty, None, None),
    ];
    for (text, kind, line, column) in cases {
        let err = csv_error(text);
        assert_eq!(err.kind(), &kind, "{text:?}: {err}");
        assert_eq!(err.line(), line, "{text:?}: {err}");
        assert_eq!(err.column(), column, "{text:?}: {err}");
    }
}

#[test]
fn a_31_byte_class_name_is_accepted() {
    let name = "n".repeat(31);
    let (_dir, path) = file("d.csv", format!("label,a,{name}\n{name},1,2\n").as_bytes());
    let (src, rows) = read_all(&path).unwrap();
    assert_eq!(src.classes()[1], name);
    assert_eq!(rows[0].label, Label::Class(1));
}

#[test]
fn invalid_utf8_is_refused_with_its_line() {
    let (_dir, path) = file("d.csv", b"label,a,b\na,1,2\n\xff\xfe,1,2\n");
    let err = read_all(&path).unwrap_err();
    assert_eq!(err.kind(), &DataErrorKind::NotUtf8, "{err}");
    assert_eq!(err.line(), Some(3), "{err}");
}

#[test]
fn missing_inputs_are_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.csv");
    let err = DataSource::open(&missing).unwrap_err();
    assert_eq!(err.kind(), &DataErrorKind::NotFound);
    assert_eq!(err.path(), missing);
    assert!(err.is_bad_input());
    assert!(err.to_string().contains("no such file"), "{err}");

    // An empty directory is an NPY directory without logits.npy.
    let err = DataSource::open(dir.path()).unwrap_err();
    assert_eq!(err.kind(), &DataErrorKind::NotFound);
    assert_eq!(err.path(), dir.path().join("logits.npy"));

    // An array that is a directory.
    let d2 = tempfile::tempdir().unwrap();
    std::fs::create_dir(d2.path().join("logits.npy")).unwrap();
    let err = DataSource::open(d2.path()).unwrap_err();
    assert!(
        matches!(err.kind(), DataErrorKind::Unreadable { .. }),
        "{err}"
    );
    assert!(err.is_bad_input());

    let (_d, npy) = file("logits.npy", b"\x93NUMPY");
    let err = DataSource::open(&npy).unwrap_err();
    assert_eq!(err.kind(), &DataErrorKind::NpyFileNotDirectory);
}

// ---- NPY ----

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn npy_row(index: u64, label: Label, os: f64, logits: [f32; 3]) -> Owned {
    Owned {
        index,
        line: None,
        id: None,
        label,
        objectness: os,
        logits: logits.iter().map(|&x| f64::from(x)).collect(),
    }
}

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

fn write_npy<T>(path: &Path, shape: &[u64], data: &[T])
where
    T: npyz::AutoSerialize + Clone,
{
    let mut out = std::fs::File::create(path).unwrap();
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(shape)
        .writer(&mut out)
        .begin_nd()
        .unwrap();
    w.extend(data.iter().cloned()).unwrap();
    w.finish().unwrap();
}

/// A valid 4 x 2 directory: logits f64, labels i64 [0, 1, -1, 1], objectness f32.
fn npy_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_npy(
        &d.join("logits.npy"),
        &[4, 2],
        &[1.0f64, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0],
    );
    write_npy(&d.join("labels.npy"), &[4], &[0i64, 1, -1, 1]);
    write_npy(&d.join("objectness.npy"), &[4], &[0.5f32, 1.0, 0.0, 0.25]);
    std::fs::write(d.join("classes.txt"), "car\ncyclist\n\n").unwrap();
    dir
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

/// Applies `edit` to a valid directory and returns the error of reading it.
fn npy_error(edit: impl FnOnce(&Path)) -> DataError {
    let dir = npy_dir();
    edit(dir.path());
    let err = read_all(dir.path()).unwrap_err();
    assert!(err.is_bad_input(), "{err}");
    err
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

/// Writes a version 1.0 NPY file by hand: `descr` (e.g. `>f4`), `shape`, raw data bytes.
fn write_raw_npy(path: &Path, descr: &str, shape: &str, data: &[u8]) {
    let dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    let mut header = dict.into_bytes();
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(b' ');
    }
    header.push(b'\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&u16::try_from(header.len()).unwrap().to_le_bytes());
    bytes.extend_from_slice(&header);
    bytes.extend_from_slice(data);
    std::fs::write(path, bytes).unwrap();
}

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

// ---------------------------------------------------------------------------------------
// Strict CSV, limits, pipes (DESIGN §2)
// ---------------------------------------------------------------------------------------

#[test]
fn csv_quoting_is_strict_and_errors_name_the_record_line() {
    use mlmap::host::dataset::MAX_RECORD_BYTES;
    // (input, kind, line)
    let long = format!("label,a,b\na,1,2\n\na,{},2\n", "1".repeat(MAX_RECORD_BYTES));
    let cases: Vec<(&[u8], DataErrorKind, u64)> = vec![
        // The file ends inside a quoted field: the record's line, not accepted as "3".
        (
            b"id,label,objectness,car,cyclist\n1,car,0.5,1,2\n2,car,0.5,1,\"3",
            DataErrorKind::UnterminatedQuote,
            3,
        ),
        // ... also when the quote opened lines earlier.
        (
            b"label,a,b\na,1,\"2\n\n\n",
            DataErrorKind::UnterminatedQuote,
            2,
        ),
        // Text after a closing quote.
        (
            b"label,a,b\na,1,2\na,\"1\"5,2\n",
            DataErrorKind::TextAfterQuote,
            3,
        ),
        // Invalid UTF-8 in a record whose quoted field spans lines: the line the record
        // starts on.
        (b"label,a,b\n\"a\n\xff\",1,2\n", DataErrorKind::NotUtf8, 2),
        // A record longer than the limit, refused while it is read.
        (
            long.as_bytes(),
            DataErrorKind::RecordTooLong {
                limit: MAX_RECORD_BYTES,
            },
            4,
        ),
    ];
    for (text, kind, line) in cases {
        let (_dir, path) = file("data.csv", text);
        let err = read_all(&path).expect_err("refused");
        assert_eq!(err.kind(), &kind, "{err}");
        assert_eq!(err.line(), Some(line), "{err}");
        assert!(err.to_string().len() < 300, "{err}");
    }
    // The first data row's error names line 2, not the header.
    let err = csv_error("label,a,b\na,x,2\n");
    assert_eq!(err.line(), Some(2), "{err}");
    // A doubled quote inside a quoted field is a quote; a bare one inside an unquoted
    // field is a character: both read.
    let (_dir, path) = file("d.csv", b"id,label,a,b\n\"x\"\"y\",a,1,2\nq\"r,b,3,4\n");
    let (_, rows) = read_all(&path).unwrap();
    assert_eq!(rows[0].id.as_deref(), Some("x\"y"));
    assert_eq!(rows[1].id.as_deref(), Some("q\"r"));
}

#[test]
fn a_long_field_is_echoed_truncated() {
    let field = "z".repeat(100_000);
    let err = csv_error(&format!("label,a,b\na,{field},2\n"));
    let msg = err.to_string();
    assert!(msg.len() < 300, "{} bytes", msg.len());
    assert!(msg.contains("100000 bytes"), "{msg}");
    assert_eq!(err.line(), Some(2));
    // The same for a label and a long column name.
    let err = csv_error(&format!("label,a,b\n{field},1,2\n"));
    assert!(err.to_string().len() < 300, "{err}");
    let err = csv_error(&format!("label,a,{field}\na,1,2\n"));
    assert!(err.to_string().len() < 300, "{err}");
}

#[test]
fn logits_beyond_f32_are_refused_with_their_position() {
    for text in ["1e39", "-3.5e38", "4e38"] {
        let err = csv_error(&format!("label,a,b\na,1,2\nb,{text},0\n"));
        assert_eq!(
            err.kind(),
            &DataErrorKind::OutOfF32 { text: text.into() },
            "{err}"
        );
        assert_eq!(err.line(), Some(3));
        assert_eq!(err.column(), Some("a"));
        assert!(err.to_string().contains("out of range"), "{err}");
    }
    // The largest f32 is a logit.
    let (_dir, path) = file("d.csv", b"label,a,b\na,3.4028234e38,0\n");
    read_all(&path).unwrap();
    // A float64 NPY logit beyond f32: row index and column.
    let dir = npy_dir();
    let mut logits = vec![0.0f64; 4 * 2];
    logits[2 * 2 + 1] = 1e39;
    write_npy(&dir.path().join("logits.npy"), &[4, 2], &logits);
    let err = read_all(dir.path()).unwrap_err();
    assert_eq!(
        err.kind(),
        &DataErrorKind::OutOfF32 {
            text: "1000000000000000000000000000000000000000".into()
        },
        "{err}"
    );
    assert_eq!(err.location(), Some(Location::Row(2)));
    assert_eq!(err.column(), Some("cyclist"));
}

#[test]
fn classes_txt_may_start_with_a_bom() {
    let dir = npy_dir();
    let classes = std::fs::read_to_string(dir.path().join("classes.txt")).unwrap();
    std::fs::write(dir.path().join("classes.txt"), format!("\u{feff}{classes}")).unwrap();
    let (src, _) = read_all(dir.path()).unwrap();
    assert_eq!(src.classes()[0], classes.lines().next().unwrap().trim());
}

#[test]
fn the_number_of_classes_is_capped() {
    use mlmap::host::dataset::MAX_CLASSES;
    let header: Vec<String> = (0..=MAX_CLASSES).map(|i| format!("c{i}")).collect();
    let zeros = vec!["0"; MAX_CLASSES + 1];
    let err = csv_error(&format!("{}\n{}\n", header.join(","), zeros.join(",")));
    assert_eq!(
        err.kind(),
        &DataErrorKind::ClassCount {
            found: MAX_CLASSES + 1
        }
    );
    assert!(err.to_string().contains("between 2 and 4096"), "{err}");
    assert!(err.to_string().len() < 300, "{err}");
    // MAX_CLASSES classes are fine.
    let (_dir, path) = file(
        "d.csv",
        format!(
            "{}\n{}\n",
            header[..MAX_CLASSES].join(","),
            zeros[..MAX_CLASSES].join(",")
        )
        .as_bytes(),
    );
    assert_eq!(read_all(&path).unwrap().0.classes().len(), MAX_CLASSES);
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

/// A FIFO fed by a writer thread; the reading must finish within a few seconds.
#[cfg(unix)]
#[test]
fn a_fifo_is_read_once_in_one_pass() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("in.csv");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let text = "label,a,b\na,1,2\n\nb,\"3\n\",4\nb,0,1";
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::write(fifo, text).unwrap())
    };
    let (done_tx, done_rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        let src = DataSource::open(&fifo).unwrap();
        assert!(!src.rereadable());
        let mut rows = Vec::new();
        src.for_each_row(|r| {
            rows.push(Owned::from(r));
            Ok::<(), DataError>(())
        })
        .unwrap();
        // A second pass is refused, naming the file.
        let again = src.for_each_row(|_| Ok::<(), DataError>(())).unwrap_err();
        done_tx.send((rows, again)).unwrap();
    });
    let (rows, again) = done_rx
        .recv_timeout(std::time::Duration::from_secs(20))
        .expect("reading the FIFO hangs");
    reader.join().unwrap();
    writer.join().unwrap();
    let lines: Vec<Option<u64>> = rows.iter().map(|r| r.line).collect();
    assert_eq!(lines, [Some(2), Some(4), Some(6)]);
    assert_eq!(rows[2].logits, [0.0, 1.0]);
    assert_eq!(again.kind(), &DataErrorKind::ReadOnce);
    assert!(again.to_string().contains("in.csv"), "{again}");
}
