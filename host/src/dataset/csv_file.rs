//! CSV input (DESIGN §2), through the `csv` crate.
//!
//! The bytes reach the `csv` parser through [`Guarded`], which follows the same
//! quoting rules and so knows, before the parser, where each record starts (its line),
//! whether the file ends inside a quoted field, whether text follows a closing quote,
//! and how long the record being read is: a record longer than
//! [`MAX_RECORD_BYTES`](super::MAX_RECORD_BYTES) is refused as soon as it is, without
//! being held in memory.

use std::collections::{HashMap, VecDeque};
use std::fmt;
use std::fs::File;
use std::io::{self, Read};
use std::path::Path;
use std::sync::{Arc, Mutex, PoisonError};

use super::{
    check_class_names, echo, DataError, DataErrorKind, Label, Location, Row, MAX_RECORD_BYTES,
};

/// Where the quoting state machine is (the `csv` crate's, for `"` quotes doubled inside
/// quoted fields, `,` delimiters and `\n` terminators).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Quoting {
    /// Between records: a `\n` here is a blank line, which the parser skips.
    StartRecord,
    /// At the start of a field.
    StartField,
    /// Inside an unquoted field.
    InField,
    /// Inside a quoted field.
    InQuoted,
    /// After a quote inside a quoted field: the closing quote, or the first of two.
    QuoteSeen,
    /// After the closing quote and blanks (spaces, tabs, the `\r` of a CRLF).
    Closed,
}

/// A malformed record found by [`Guarded`], carried through the `csv` parser as an I/O
/// error.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Malformed {
    line: u64,
    kind: DataErrorKind,
}

impl fmt::Display for Malformed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.kind)
    }
}

impl std::error::Error for Malformed {}

/// A reader that checks the quoting and the record length of a CSV file as its bytes
/// pass, and records the first line of every record (see the module docs).
#[derive(Debug)]
struct Guarded<R> {
    inner: R,
    state: Quoting,
    /// The line of the next byte (1-based).
    line: u64,
    /// Bytes of the record being read so far.
    record_bytes: usize,
    /// The first line of every record started and not yet claimed by [`Guarded::next_line`].
    starts: VecDeque<u64>,
    /// The problem found, returned by every later read.
    failed: Option<Malformed>,
}

impl<R: Read> Guarded<R> {
    fn new(inner: R) -> Self {
        Self {
            inner,
            state: Quoting::StartRecord,
            line: 1,
            record_bytes: 0,
            starts: VecDeque::new(),
            failed: None,
        }
    }

    /// The first line of the next record the parser gives.
    fn next_line(&mut self) -> Option<u64> {
        self.starts.pop_front()
    }

    /// The line of the record being read (for an error the parser reports about it).
    fn current_line(&self) -> u64 {
        self.starts.front().copied().unwrap_or(self.line)
    }

    fn error(m: &Malformed) -> io::Error {
        io::Error::new(io::ErrorKind::InvalidData, m.clone())
    }

    /// Moves the state machine over one byte.
    fn step(&mut self, b: u8) -> Result<(), Malformed> {
        if self.state == Quoting::StartRecord {
            if b == b'\n' {
                self.line += 1;
                return Ok(());
            }
            self.starts.push_back(self.line);
            self.record_bytes = 0;
            self.state = Quoting::StartField;
        }
        self.record_bytes += 1;
        let line = self.starts.back().copied().unwrap_or(self.line);
        if self.record_bytes > MAX_RECORD_BYTES {
            return Err(Malformed {
                line,
                kind: DataErrorKind::RecordTooLong {
                    limit: MAX_RECORD_BYTES,
                },
            });
        }
        self.state = match (self.state, b) {
            (Quoting::StartField, b'"') => Quoting::InQuoted,
            (Quoting::InQuoted, b'"') => Quoting::QuoteSeen,
            (Quoting::QuoteSeen, b'"') | (Quoting::InQuoted, _) => Quoting::InQuoted,
            (_, b',') => Quoting::StartField,
            (_, b'\n') => Quoting::StartRecord,
            (Quoting::QuoteSeen | Quoting::Closed, b' ' | b'\t' | b'\r') => Quoting::Closed,
            (Quoting::QuoteSeen | Quoting::Closed, _) => {
                return Err(Malformed {
                    line,
                    kind: DataErrorKind::TextAfterQuote,
                })
            }
            _ => Quoting::InField,
        };
        if b == b'\n' {
            self.line += 1;
        }
        Ok(())
    }
}

impl<R: Read> Read for Guarded<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if let Some(m) = &self.failed {
            return Err(Self::error(m));
        }
        let n = loop {
            match self.inner.read(buf) {
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                r => break r?,
            }
        };
        if n == 0 && self.state == Quoting::InQuoted {
            let m = Malformed {
                line: self.starts.back().copied().unwrap_or(self.line),
                kind: DataErrorKind::UnterminatedQuote,
            };
            let e = Self::error(&m);
            self.failed = Some(m);
            return Err(e);
        }
        for (i, &b) in buf.get(..n).unwrap_or_default().iter().enumerate() {
            if let Err(m) = self.step(b) {
                // The bytes before the problem go to the parser first, so the records
                // before it are checked (and reported) first.
                let e = Self::error(&m);
                self.failed = Some(m);
                return if i == 0 { Err(e) } else { Ok(i) };
            }
        }
        Ok(n)
    }
}

/// The `csv` reader of one pass.
type CsvReader = csv::Reader<Guarded<File>>;

/// A reader that has read the header and not yet any row: kept from
/// [`Schema::open`] for the first pass over an input that can be read only once.
#[derive(Default)]
struct Pending(Option<CsvReader>);

impl fmt::Debug for Pending {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(if self.0.is_some() {
            "Pending(reader)"
        } else {
            "Pending(none)"
        })
    }
}

/// Which field holds what, read from the header.
#[derive(Debug, Clone)]
pub(super) struct Schema {
    fields: usize,
    label: Option<usize>,
    objectness: Option<usize>,
    id: Option<usize>,
    /// The column declared not a class ([`DataSource::open_with_column`](super::DataSource::open_with_column)),
    /// when the header has it.
    extra: Option<usize>,
    /// Field index of each class's logit, in class order.
    logits: Vec<usize>,
    /// Class name to class index.
    index: HashMap<String, usize>,
    /// `false` for a file that is not a regular file (a pipe, a FIFO, a device): it is
    /// read once, through the reader kept in `pending`.
    rereadable: bool,
    pending: Arc<Mutex<Pending>>,
}

/// Opens `path` for reading; records end at `\n` only; a `\r` before it stays in the
/// last field and is trimmed with the other whitespace (fields are trimmed by the
/// callers). Returns the reader and whether `path` is a regular file.
fn reader(path: &Path) -> Result<(CsvReader, bool), DataError> {
    let file = File::open(path).map_err(|e| DataError::open(path, &e))?;
    let regular = file
        .metadata()
        .map_err(|e| DataError::io(path, &e))?
        .is_file();
    let rdr = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::None)
        .terminator(csv::Terminator::Any(b'\n'))
        .buffer_capacity(1 << 16)
        .from_reader(Guarded::new(file));
    Ok((rdr, regular))
}

/// Maps a `csv` error met while reading a record.
fn csv_error(path: &Path, e: &csv::Error, rdr: &CsvReader) -> DataError {
    let line = rdr.get_ref().current_line();
    match e.kind() {
        csv::ErrorKind::Io(io) => match io.get_ref().and_then(|e| e.downcast_ref::<Malformed>()) {
            Some(m) => DataError::new(path, m.kind.clone()).at(Location::Line(m.line)),
            None => DataError::io(path, io),
        },
        csv::ErrorKind::Utf8 { .. } => {
            DataError::new(path, DataErrorKind::NotUtf8).at(Location::Line(line))
        }
        other => DataError::new(
            path,
            DataErrorKind::Io {
                reason: format!("{other:?}"),
            },
        ),
    }
}

/// Reads the header of `rdr`; returns it and its line.
fn read_header(path: &Path, rdr: &mut CsvReader) -> Result<(csv::StringRecord, u64), DataError> {
    let header = match rdr.headers() {
        Ok(h) => h.clone(),
        Err(e) => return Err(csv_error(path, &e, rdr)),
    };
    let line = rdr.get_mut().next_line().unwrap_or(1);
    Ok((header, line))
}

impl Schema {
    /// Reads and checks the header; returns the class names and the schema. A column
    /// named `extra` is not a class: its text is given to
    /// [`for_each_row_with_column`](Self::for_each_row_with_column).
    pub(super) fn open(path: &Path, extra: Option<&str>) -> Result<(Vec<String>, Self), DataError> {
        let (mut rdr, rereadable) = reader(path)?;
        let (header, header_line) = read_header(path, &mut rdr)?;
        let at_header = |e: DataError| e.at(Location::Line(header_line));
        let names_in_header: Vec<&str> = header.iter().map(str::trim).collect();
        if names_in_header.iter().all(|n| n.is_empty()) && names_in_header.len() <= 1 {
            return Err(DataError::new(path, DataErrorKind::Empty));
        }
        let mut schema = Self {
            fields: names_in_header.len(),
            label: None,
            objectness: None,
            id: None,
            extra: None,
            logits: Vec::new(),
            index: HashMap::new(),
            rereadable,
            pending: Arc::default(),
        };
        let mut names = Vec::new();
        let mut seen = HashMap::new();
        for (i, &name) in names_in_header.iter().enumerate() {
            if name.is_empty() {
                return Err(at_header(DataError::new(
                    path,
                    DataErrorKind::EmptyColumnName { index: i + 1 },
                )));
            }
            if seen.insert(name, i).is_some() {
                return Err(at_header(
                    DataError::new(path, DataErrorKind::DuplicateColumn).in_column(name),
                ));
            }
            match name {
                "label" => schema.label = Some(i),
                "objectness" => schema.objectness = Some(i),
                "id" => schema.id = Some(i),
                _ if Some(name) == extra => schema.extra = Some(i),
                _ => {
                    schema.logits.push(i);
                    names.push(name.to_string());
                }
            }
        }
        schema.index = check_class_names(&names, |i, kind| {
            let e = at_header(DataError::new(path, kind));
            match names.get(i) {
                Some(n) => e.in_column(n.as_str()),
                None => e,
            }
        })?;
        if !rereadable {
            schema.pending = Arc::new(Mutex::new(Pending(Some(rdr))));
        }
        Ok((names, schema))
    }

    pub(super) fn has_labels(&self) -> bool {
        self.label.is_some()
    }

    pub(super) fn has_ids(&self) -> bool {
        self.id.is_some()
    }

    pub(super) fn has_objectness(&self) -> bool {
        self.objectness.is_some()
    }

    pub(super) fn has_extra(&self) -> bool {
        self.extra.is_some()
    }

    pub(super) fn rereadable(&self) -> bool {
        self.rereadable
    }

    /// The reader of a pass, past the header: the one kept by [`Schema::open`] for an
    /// input read once, a new one otherwise.
    fn pass(&self, path: &Path) -> Result<CsvReader, DataError> {
        if !self.rereadable {
            let mut pending = self.pending.lock().unwrap_or_else(PoisonError::into_inner);
            return pending
                .0
                .take()
                .ok_or_else(|| DataError::new(path, DataErrorKind::ReadOnce));
        }
        let (mut rdr, _) = reader(path)?;
        read_header(path, &mut rdr)?;
        Ok(rdr)
    }

    pub(super) fn for_each_row<E, F>(
        &self,
        path: &Path,
        classes: &[String],
        mut f: F,
    ) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>) -> Result<(), E>,
    {
        self.for_each_row_with_column(path, classes, |row, _| f(row))
    }

    /// As [`for_each_row`](Self::for_each_row), with the trimmed text of the declared
    /// column (`None` when the header does not have it).
    pub(super) fn for_each_row_with_column<E, F>(
        &self,
        path: &Path,
        classes: &[String],
        mut f: F,
    ) -> Result<(), E>
    where
        E: From<DataError>,
        F: FnMut(Row<'_>, Option<&str>) -> Result<(), E>,
    {
        let mut rdr = self.pass(path)?;
        let mut record = csv::StringRecord::new();
        let mut logits = vec![0.0f64; self.logits.len()];
        let mut index = 0u64;
        loop {
            match rdr.read_record(&mut record) {
                Ok(true) => {}
                Ok(false) => break,
                Err(e) => return Err(csv_error(path, &e, &rdr).into()),
            }
            let line = rdr.get_mut().next_line().unwrap_or(0);
            if record.len() == 1 && record.get(0).is_some_and(|f| f.trim().is_empty()) {
                continue; // a blank line (only whitespace, e.g. a CRLF)
            }
            let here = |kind: DataErrorKind| DataError::new(path, kind).at(Location::Line(line));
            let field = |i: usize| record.get(i).map_or("", str::trim);
            if record.len() != self.fields {
                return Err(here(DataErrorKind::FieldCount {
                    expected: self.fields,
                    found: record.len(),
                })
                .into());
            }
            for ((slot, &column), name) in logits.iter_mut().zip(&self.logits).zip(classes) {
                *slot = parse_logit(field(column)).map_err(|k| here(k).in_column(name.as_str()))?;
            }
            let objectness = match self.objectness {
                None => 1.0,
                Some(column) => {
                    parse_objectness(field(column)).map_err(|k| here(k).in_column("objectness"))?
                }
            };
            let label = match self.label.map(field) {
                None | Some("") => Label::Missing,
                Some("background") => Label::Background,
                Some(text) => match self.index.get(text) {
                    Some(&c) => Label::Class(c),
                    None => {
                        return Err(here(DataErrorKind::UnknownLabel { text: echo(text) })
                            .in_column("label")
                            .into())
                    }
                },
            };
            f(
                Row {
                    index,
                    line: Some(line),
                    id: self.id.map(field),
                    label,
                    objectness,
                    logits: &logits,
                },
                self.extra.map(field),
            )?;
            index += 1;
        }
        Ok(())
    }
}

fn parse_number(text: &str) -> Result<f64, DataErrorKind> {
    if text.is_empty() {
        return Err(DataErrorKind::MissingValue);
    }
    text.parse::<f64>()
        .map_err(|_| DataErrorKind::NotANumber { text: echo(text) })
}

/// A number finite in the layer's `f32` (DESIGN §6.16): NaN and infinities are not
/// finite, and a finite `f64` beyond `f32::MAX` would become infinite in the layer.
fn parse_logit(text: &str) -> Result<f64, DataErrorKind> {
    let v = parse_number(text)?;
    super::check_logit(v, || echo(text))
}

/// A number in `[0, 1]`.
fn parse_objectness(text: &str) -> Result<f64, DataErrorKind> {
    let v = parse_number(text)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(DataErrorKind::ObjectnessRange { text: echo(text) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers() {
        assert_eq!(parse_logit("4.1"), Ok(4.1));
        assert_eq!(parse_logit("-2e-3"), Ok(-0.002));
        assert_eq!(parse_logit(""), Err(DataErrorKind::MissingValue));
        assert_eq!(
            parse_logit("abc"),
            Err(DataErrorKind::NotANumber { text: "abc".into() })
        );
        for t in ["nan", "NaN", "inf", "-inf", "infinity", "1e999"] {
            assert_eq!(
                parse_logit(t),
                Err(DataErrorKind::NotFinite { text: t.into() }),
                "{t}"
            );
        }
        for t in ["1e39", "-3.5e38"] {
            assert_eq!(
                parse_logit(t),
                Err(DataErrorKind::OutOfF32 { text: t.into() }),
                "{t}"
            );
        }
        assert_eq!(parse_logit("3.4e38"), Ok(3.4e38));
        assert_eq!(parse_objectness("0"), Ok(0.0));
        assert_eq!(parse_objectness("1"), Ok(1.0));
        for t in ["nan", "1.0001", "-0.1", "inf"] {
            assert_eq!(
                parse_objectness(t),
                Err(DataErrorKind::ObjectnessRange { text: t.into() }),
                "{t}"
            );
        }
    }

    /// Runs the guard over `text` in chunks of `chunk` bytes; returns the record start
    /// lines and the problem.
    fn guard(text: &str, chunk: usize) -> (Vec<u64>, Option<Malformed>) {
        let mut g = Guarded::new(text.as_bytes());
        let mut buf = vec![0u8; chunk];
        let mut problem = None;
        loop {
            match g.read(&mut buf) {
                Ok(0) => break,
                Ok(_) => {}
                Err(e) => {
                    problem = e
                        .get_ref()
                        .and_then(|e| e.downcast_ref::<Malformed>())
                        .cloned();
                    break;
                }
            }
        }
        (g.starts.iter().copied().collect(), problem)
    }

    #[test]
    fn the_guard_follows_quotes_and_lines() {
        for chunk in [1, 3, 64] {
            let (starts, problem) = guard("a,b\n\n\"x\ny\",2\n\n\n3,\"\"\"q\"\n4,5", chunk);
            assert_eq!(starts, [1, 3, 7, 8], "chunk {chunk}");
            assert_eq!(problem, None);
            let (_, problem) = guard("a,b\n1,\"2\n3", chunk);
            assert_eq!(
                problem,
                Some(Malformed {
                    line: 2,
                    kind: DataErrorKind::UnterminatedQuote
                })
            );
            let (_, problem) = guard("a,b\n1,2\n\"1\"x,2\n", chunk);
            assert_eq!(
                problem,
                Some(Malformed {
                    line: 3,
                    kind: DataErrorKind::TextAfterQuote
                })
            );
            // A quote inside an unquoted field is a character of the field; blanks and
            // a CRLF may follow a closing quote.
            assert_eq!(guard("a,b\n1\"2,3\n", chunk).1, None);
            assert_eq!(guard("a,b\r\n\"1\" ,\"2\"\r\n", chunk).1, None);
        }
    }
}
