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

/// Applies `edit` to a valid directory and returns the error of reading it.
fn npy_error(edit: impl FnOnce(&Path)) -> DataError {
    let dir = npy_dir();
    edit(dir.path());
    let err = read_all(dir.path()).unwrap_err();
    assert!(err.is_bad_input(), "{err}");
    err
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

/// CSV inputs, valid and malformed (each refused with its position), strict quoting,
/// limits and pipes (DESIGN §2).
mod csv;
/// NPY directories written by numpy and npyz, labels of every integer dtype, every
/// malformed directory.
mod npy;
/// NPY rows across the reader's chunks: errors in later chunks, exact labels, sizes that
/// overflow.
mod npy_chunks;
