//! CSV input (DESIGN §2), through the `csv` crate.

use std::collections::HashMap;
use std::fs::File;
use std::io::{self, BufReader, Read, Seek, SeekFrom};
use std::path::Path;
use std::string::{String, ToString};
use std::vec::Vec;

use super::{check_class_names, DataError, DataErrorKind, Label, Location, Row};

/// Which field holds what, read from the header.
#[derive(Debug, Clone)]
pub(super) struct Schema {
    fields: usize,
    label: Option<usize>,
    objectness: Option<usize>,
    id: Option<usize>,
    /// Field index of each class's logit, in class order.
    logits: Vec<usize>,
    /// Class name to class index.
    index: HashMap<String, usize>,
}

/// Where records start, computed from where they end.
///
/// `csv` stamps a record with the position where reading began, which is before any
/// blank lines it skips; the position after a record is exact. A record's first line
/// is therefore its last line minus the line breaks inside its (quoted) fields, and
/// its last line is the line count after it, minus one when a line break ended it.
#[derive(Debug, Clone, Copy)]
struct Lines {
    /// Length of the file in bytes.
    len: u64,
    /// Whether the last byte of the file is a line break.
    ends_with_newline: bool,
}

impl Lines {
    fn of(file: &mut File) -> io::Result<Self> {
        let len = file.metadata()?.len();
        let mut last = [0u8; 1];
        if len > 0 {
            file.seek(SeekFrom::End(-1))?;
            file.read_exact(&mut last)?;
            file.seek(SeekFrom::Start(0))?;
        }
        Ok(Self {
            len,
            ends_with_newline: last == [b'\n'],
        })
    }

    /// The first line of a record that ends at `end` (the reader's position after it)
    /// and holds `embedded` line breaks inside its fields.
    fn start(&self, end: &csv::Position, embedded: u64) -> u64 {
        let terminated = end.byte() < self.len || self.ends_with_newline;
        end.line()
            .saturating_sub(embedded + u64::from(terminated))
            .max(1)
    }

    fn start_of(&self, end: &csv::Position, record: &csv::StringRecord) -> u64 {
        let embedded = record
            .iter()
            .map(|f| f.bytes().filter(|&b| b == b'\n').count() as u64)
            .sum();
        self.start(end, embedded)
    }
}

/// A reader of `path`. Records end at `\n` only; a `\r` before it stays in the last
/// field and is trimmed with the other whitespace (fields are trimmed by the callers,
/// after line breaks inside quoted fields are counted).
fn reader(path: &Path) -> Result<(csv::Reader<BufReader<File>>, Lines), DataError> {
    let mut file = File::open(path).map_err(|e| DataError::open(path, &e))?;
    let lines = Lines::of(&mut file).map_err(|e| DataError::io(path, &e))?;
    let rdr = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::None)
        .terminator(csv::Terminator::Any(b'\n'))
        .from_reader(BufReader::with_capacity(1 << 16, file));
    Ok((rdr, lines))
}

/// Maps a `csv` error met while reading the record that ended at `end`.
fn csv_error(path: &Path, e: &csv::Error, lines: Lines, end: &csv::Position) -> DataError {
    match e.kind() {
        csv::ErrorKind::Io(io) => DataError::io(path, io),
        csv::ErrorKind::Utf8 { .. } => {
            DataError::new(path, DataErrorKind::NotUtf8).at(Location::Line(lines.start(end, 0)))
        }
        other => DataError::new(
            path,
            DataErrorKind::Io {
                reason: std::format!("{other:?}"),
            },
        ),
    }
}

impl Schema {
    /// Reads and checks the header; returns the class names and the schema.
    pub(super) fn open(path: &Path) -> Result<(Vec<String>, Self), DataError> {
        let (mut rdr, lines) = reader(path)?;
        let header = match rdr.headers() {
            Ok(h) => h.clone(),
            Err(e) => return Err(csv_error(path, &e, lines, rdr.position())),
        };
        let header_line = lines.start_of(rdr.position(), &header);
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
            logits: Vec::new(),
            index: HashMap::new(),
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
        let (mut rdr, lines) = reader(path)?;
        let mut record = csv::StringRecord::new();
        let mut logits = std::vec![0.0f64; self.logits.len()];
        let mut index = 0u64;
        // `read_record` skips the header row (`has_headers(true)`).
        loop {
            match rdr.read_record(&mut record) {
                Ok(true) => {}
                Ok(false) => break,
                Err(e) => return Err(csv_error(path, &e, lines, rdr.position()).into()),
            }
            if record.len() == 1 && record.get(0).is_some_and(|f| f.trim().is_empty()) {
                continue; // a blank line (only whitespace, e.g. a CRLF)
            }
            let line = lines.start_of(rdr.position(), &record);
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
                        return Err(here(DataErrorKind::UnknownLabel {
                            text: text.to_string(),
                        })
                        .in_column("label")
                        .into())
                    }
                },
            };
            f(Row {
                index,
                line: Some(line),
                id: self.id.map(field),
                label,
                objectness,
                logits: &logits,
            })?;
            index += 1;
        }
        Ok(())
    }
}

fn parse_number(text: &str) -> Result<f64, DataErrorKind> {
    if text.is_empty() {
        return Err(DataErrorKind::MissingValue);
    }
    text.parse::<f64>().map_err(|_| DataErrorKind::NotANumber {
        text: text.to_string(),
    })
}

/// A finite number.
fn parse_logit(text: &str) -> Result<f64, DataErrorKind> {
    let v = parse_number(text)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(DataErrorKind::NotFinite {
            text: text.to_string(),
        })
    }
}

/// A number in `[0, 1]`.
fn parse_objectness(text: &str) -> Result<f64, DataErrorKind> {
    let v = parse_number(text)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(DataErrorKind::ObjectnessRange {
            text: text.to_string(),
        })
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
}
