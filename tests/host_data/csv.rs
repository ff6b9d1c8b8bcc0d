//! CSV inputs, valid and malformed (each refused with its position), strict quoting,
//! limits and pipes (DESIGN §2).

use super::*;

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
