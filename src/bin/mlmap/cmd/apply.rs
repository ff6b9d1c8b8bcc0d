//! `mlmap apply`: score every row through the layer, write CSV or an NPY directory
//! (DESIGN §4). With `--quantized`, the logits are integer codes scored through the table
//! file's quantized section; the output is what `apply` writes for the dequantized
//! logits. `--heads` scores and writes only the heads it names.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::Path;

use mlmap::host::conformal::has_conformal;
use mlmap::host::data::{self, at, check_classes};
use mlmap::host::dataset::{DataSource, Label, Row};
use mlmap::host::metrics::decision;
use mlmap::host::names::Named as _;
use mlmap::host::DynQTable;
use mlmap::{code_range, dequantize, set_words, ConformalSpec, Head, TableView};
use npyz::WriterBuilder as _;

use crate::args::{ApplyArgs, ApplyFormat};
use crate::error::{CliError, Result};
use crate::output;
use crate::shared::read_table;

/// The files of an NPY output directory (besides `classes.txt`, `ids.txt` and
/// `labels.npy`): `<head>.npy` and `<head>_pred.npy` for every head, `sets.npy`.
fn is_npy_output_file(name: &str) -> bool {
    if matches!(name, "classes.txt" | "ids.txt" | "labels.npy" | "sets.npy") {
        return true;
    }
    let stem = name.strip_suffix(".npy").unwrap_or("");
    let head = stem.strip_suffix("_pred").unwrap_or(stem);
    Head::NAMES.iter().any(|n| n.name == head)
}

/// The output's format: `--format`, else an NPY directory when `--output` ends in `/`,
/// else CSV.
fn format_of(args: &ApplyArgs) -> Result<ApplyFormat> {
    let slash = args.output.as_os_str().as_encoded_bytes().ends_with(b"/");
    match args.format {
        Some(ApplyFormat::Csv) if slash => Err(CliError::input(
            &args.output,
            "ends in `/`, a directory; --format csv writes a file",
        )),
        Some(f) => Ok(f),
        None if slash => Ok(ApplyFormat::Npy),
        None => Ok(ApplyFormat::Csv),
    }
}

/// The heads to score, in column order: those of `--heads`, each of which the table
/// (and its quantized section) must have, or every head it has.
fn select_heads(args: &ApplyArgs, table_heads: &[Head], available: &[Head]) -> Result<Vec<Head>> {
    let Some(asked) = &args.heads else {
        return Ok(available.to_vec());
    };
    let list = |heads: &[Head]| {
        heads
            .iter()
            .map(|h| h.name())
            .collect::<Vec<_>>()
            .join(", ")
    };
    for (i, h) in asked.iter().enumerate() {
        if asked.iter().take(i).any(|a| a == h) {
            return Err(CliError::Input(format!(
                "--heads names the {} head twice",
                h.name()
            )));
        }
        if !available.contains(h) {
            let msg = if table_heads.contains(h) {
                format!(
                    "its quantized section has no {} head (it has {}); --heads may name only those",
                    h.name(),
                    list(available)
                )
            } else {
                format!(
                    "the table has no {} head (it has {}); --heads may name only those",
                    h.name(),
                    list(available)
                )
            };
            return Err(CliError::input(&args.table, msg));
        }
    }
    Ok(available
        .iter()
        .copied()
        .filter(|h| asked.contains(h))
        .collect())
}

pub fn run(args: &ApplyArgs) -> Result<()> {
    let format = format_of(args)?;
    let inputs = [args.table.as_path(), args.input.as_path()];
    match format {
        ApplyFormat::Csv => output::check_outputs(&args.output, &inputs)?,
        ApplyFormat::Npy => output::check_dir_outputs(&args.output, is_npy_output_file, &inputs)?,
    }
    let (table, bytes) = read_table(&args.table)?;
    let quantized = if args.quantized {
        let q = DynQTable::from_bytes(&bytes).map_err(|e| {
            CliError::input(
                &args.table,
                format!("{e} (--quantized needs a table written by `mlmap quantize`)"),
            )
        })?;
        Some(q)
    } else {
        None
    };
    // The heads the table has, and those its quantized section (when scoring codes) has,
    // in column order: ML and MAP always, Bayes and open when present (the open head is
    // built on the Bayes head).
    let mut table_heads = vec![Head::Ml, Head::Map];
    if table.bayes_head().is_some() {
        table_heads.push(Head::Bayes);
        if table.open_params().is_some() {
            table_heads.push(Head::Open);
        }
    }
    let section_has = |h: Head| match (&quantized, h) {
        (None, _) | (_, Head::Ml | Head::Map) => true,
        (Some(q), Head::Bayes) => q.has_bayes(),
        (Some(q), Head::Open) => q.has_bayes() && q.open_params().is_some(),
    };
    let available: Vec<Head> = table_heads
        .iter()
        .copied()
        .filter(|&h| section_has(h))
        .collect();
    let heads = select_heads(args, &table_heads, &available)?;
    let src = if args.quantized {
        data::open_codes(&args.input)?
    } else {
        data::open(&args.input)?
    };
    check_classes(&args.input, src.classes(), table.class_names())?;
    let names: Vec<&str> = table.class_names().collect();
    let view = table.view();
    // Conformal sets (DESIGN §8) when the table file holds the section and its head is
    // scored: that head's scores, as computed above, thresholded by the layer's spec.
    let conformal = if has_conformal(&bytes) {
        let spec = ConformalSpec::from_bytes(&bytes, &view)
            .map_err(|e| CliError::input(&args.table, e))?;
        match heads.iter().position(|&h| h == spec.head()) {
            Some(at) => Some((spec, at)),
            // Not asked for: no sets.
            None if args.heads.is_some() => None,
            None => {
                return Err(CliError::input(
                    &args.table,
                    format!(
                        "its conformal sets threshold the {} head, which its quantized section \
                         lacks",
                        spec.head()
                    ),
                ))
            }
        }
    } else {
        None
    };
    let scorer = Scorer {
        args,
        src: &src,
        view,
        quantized: quantized.as_ref(),
        heads: &heads,
        names: &names,
        conformal: conformal.as_ref().map(|(s, at)| (s, *at)),
        bayes_categories: table.bayes_head().map_or(0, |b| b.categories()),
    };
    match format {
        ApplyFormat::Csv => write_csv(&scorer),
        ApplyFormat::Npy => write_npy(&scorer),
    }
}

/// Everything the scoring of the rows needs.
struct Scorer<'a> {
    args: &'a ApplyArgs,
    src: &'a DataSource,
    view: TableView<'a, Vec<f32>, Vec<f32>>,
    quantized: Option<&'a DynQTable<'a>>,
    heads: &'a [Head],
    names: &'a [&'a str],
    /// The conformal spec and the index in `heads` of the head it thresholds.
    conformal: Option<(&'a ConformalSpec<'a>, usize)>,
    bayes_categories: usize,
}

/// What one row gives: its K scores per head (in `heads` order), the decision of each
/// head, and the conformal set's bit mask when there are sets.
struct Scored<'r> {
    scores: &'r [f32],
    preds: &'r [usize],
    set: Option<&'r [u32]>,
}

impl Scorer<'_> {
    /// Scores every row of the input in order and hands each to `f`.
    fn for_each(&self, mut f: impl FnMut(&Row<'_>, Scored<'_>) -> Result<()>) -> Result<()> {
        let k = self.names.len();
        let heads = self.heads;
        let input = &self.args.input;
        let mut mask = vec![0u32; set_words(k)];
        let mut codes = vec![0i32; k];
        let mut x = vec![0.0f32; k];
        // One row of K scores per head, in `heads` order; scratch for the largest head
        // (one float per Bayes category, and K more for a quantized open head).
        let mut scores = vec![0.0f32; k * heads.len()];
        let mut preds = vec![0usize; heads.len()];
        let mut scratch = vec![0.0f32; k + self.bayes_categories.max(k)];
        self.src.for_each_row(|row| -> Result<()> {
            let os = row.objectness as f32;
            let at = |e: mlmap::InferError| {
                CliError::Input(format!("{}: {e}", at(input, row.location())))
            };
            if let Some(q) = self.quantized {
                let (lo, hi) = code_range(q.bits());
                for (i, (c, &v)) in codes.iter_mut().zip(row.logits).enumerate() {
                    if !(v.fract() == 0.0 && (f64::from(lo)..=f64::from(hi)).contains(&v)) {
                        return Err(CliError::Input(format!(
                            "{}: logit of class {} is {v}, not an integer code in [{lo}, {hi}] \
                             ({}-bit quantized logits)",
                            data::at(input, row.location()),
                            self.names.get(i).copied().unwrap_or(""),
                            q.bits()
                        )));
                    }
                    *c = v as i32;
                }
                // The dequantized logits, for the tie-safe decision.
                for ((d, &c), i) in x.iter_mut().zip(&codes).zip(0..) {
                    let (s, z) = q.params(i).unwrap_or((1.0, 0));
                    *d = dequantize(c, s, z);
                }
                for (&head, out) in heads.iter().zip(scores.chunks_exact_mut(k)) {
                    q.score_i32_into(head, &codes, os, out, &mut scratch)
                        .map_err(at)?;
                }
            } else {
                for (d, &s) in x.iter_mut().zip(row.logits) {
                    *d = s as f32;
                }
                // Each head with the device's default backend (`Table::ml`, `map`,
                // `bayes`, `open`).
                for (&head, out) in heads.iter().zip(scores.chunks_exact_mut(k)) {
                    self.view
                        .score_into(head, &x, os, out, &mut scratch)
                        .map_err(at)?;
                }
            }
            for (p, head_scores) in preds.iter_mut().zip(scores.chunks_exact(k)) {
                *p = decision(head_scores, &x);
            }
            let set = match self.conformal {
                Some((spec, at_head)) => {
                    let s = scores
                        .get(at_head * k..(at_head + 1) * k)
                        .unwrap_or_default();
                    spec.set_of(s, &mut mask).map_err(at)?;
                    Some(&mask[..])
                }
                None => None,
            };
            f(
                &row,
                Scored {
                    scores: &scores,
                    preds: &preds,
                    set,
                },
            )
        })
    }
}

/// Whether class `c` is in the set of bit mask `mask`.
fn in_set(mask: &[u32], c: usize) -> bool {
    mask.get(c / 32).is_some_and(|w| w >> (c % 32) & 1 == 1)
}

/// The CSV output: one line per row.
fn write_csv(s: &Scorer<'_>) -> Result<()> {
    let out_path = &s.args.output;
    let names = s.names;
    let k = names.len();
    let csv_err = |e: csv::Error| CliError::internal(out_path, format!("cannot write: {e}"));
    output::write_atomic(out_path, |w| {
        let mut csv = csv::Writer::from_writer(w);
        let mut header: Vec<String> = Vec::new();
        if s.src.has_ids() {
            header.push("id".into());
        }
        if s.src.has_labels() {
            header.push("label".into());
        }
        for &head in s.heads {
            let prefix = head.name();
            header.extend(names.iter().map(|n| format!("{prefix}_{n}")));
        }
        for &head in s.heads {
            header.push(format!("{}_pred", head.name()));
        }
        if s.conformal.is_some() {
            header.extend(names.iter().map(|n| format!("set_{n}")));
        }
        csv.write_record(&header).map_err(csv_err)?;
        // Fields are written one by one, numbers through one reused buffer: no
        // allocation per row.
        let mut number = String::new();
        s.for_each(|row, out| {
            if s.src.has_ids() {
                csv.write_field(row.id.unwrap_or("")).map_err(csv_err)?;
            }
            if s.src.has_labels() {
                let label = match row.label {
                    Label::Class(c) => names.get(c).copied().unwrap_or(""),
                    Label::Background => "background",
                    Label::Missing => "",
                };
                csv.write_field(label).map_err(csv_err)?;
            }
            for v in out.scores {
                number.clear();
                let _ = write!(number, "{v}");
                csv.write_field(&number).map_err(csv_err)?;
            }
            for &p in out.preds {
                csv.write_field(names.get(p).copied().unwrap_or(""))
                    .map_err(csv_err)?;
            }
            if let Some(mask) = out.set {
                for c in 0..k {
                    csv.write_field(if in_set(mask, c) { "1" } else { "0" })
                        .map_err(csv_err)?;
                }
            }
            csv.write_record(None::<&[u8]>).map_err(csv_err)
        })?;
        csv.flush()
            .map_err(|e| CliError::internal(out_path, format!("cannot write: {e}")))
    })
}

/// The label codes of `labels.npy`: the class index, -1 for background (as in an NPY
/// input), -2 for a row without a label.
const BACKGROUND: i32 = -1;
const NO_LABEL: i32 = -2;

/// An array of the NPY output whose row count is known only at the end: its elements
/// are spooled, little-endian, into an unnamed temporary file, then copied behind the
/// header `npyz` writes for the final shape.
struct Spool {
    name: String,
    /// Elements per row (1 for a vector).
    width: usize,
    file: BufWriter<File>,
}

impl Spool {
    fn new(dir: &Path, name: String, width: usize) -> io::Result<Self> {
        Ok(Self {
            name,
            width,
            file: BufWriter::new(tempfile::tempfile_in(dir)?),
        })
    }

    /// Writes `dir/name` holding the `rows` rows spooled, as elements of type `T`
    /// (`size` bytes each, decoded from little-endian by `decode`).
    fn finish<T: npyz::AutoSerialize, const SIZE: usize>(
        self,
        dir: &Path,
        rows: u64,
        decode: impl Fn([u8; SIZE]) -> T,
    ) -> io::Result<()> {
        let mut spool = self
            .file
            .into_inner()
            .map_err(io::IntoInnerError::into_error)?;
        spool.seek(SeekFrom::Start(0))?;
        let mut spool = BufReader::with_capacity(1 << 16, spool);
        let shape: Vec<u64> = if self.width == 1 {
            vec![rows]
        } else {
            vec![rows, self.width as u64]
        };
        let file = File::create(dir.join(&self.name))?;
        let mut writer = npyz::WriteOptions::<T>::new()
            .default_dtype()
            .shape(&shape)
            .writer(BufWriter::with_capacity(1 << 16, &file))
            .begin_nd()?;
        let mut element = [0u8; SIZE];
        for _ in 0..rows * self.width as u64 {
            spool.read_exact(&mut element)?;
            writer.push(&decode(element))?;
        }
        writer.finish()?;
        file.sync_all()
    }
}

/// The NPY directory output (DESIGN §4): `<head>.npy` (N x K float32) and
/// `<head>_pred.npy` (N int32 class indices) for every head, `sets.npy` (N x K uint8),
/// `labels.npy` (N int32) and `ids.txt` when the input has them, and `classes.txt`.
fn write_npy(s: &Scorer<'_>) -> Result<()> {
    let out = &s.args.output;
    let k = s.names.len();
    let input = &s.args.input;
    output::write_dir_atomic(out, is_npy_output_file, |dir| {
        let io_err = |e: io::Error| CliError::internal(out, format!("cannot write: {e}"));
        let mut classes = String::new();
        for n in s.names {
            classes.push_str(n);
            classes.push('\n');
        }
        std::fs::write(dir.join("classes.txt"), classes).map_err(io_err)?;
        let mut score_spools = Vec::new();
        let mut pred_spools = Vec::new();
        for &head in s.heads {
            score_spools.push(Spool::new(dir, format!("{}.npy", head.name()), k).map_err(io_err)?);
            pred_spools
                .push(Spool::new(dir, format!("{}_pred.npy", head.name()), 1).map_err(io_err)?);
        }
        let mut sets = match s.conformal {
            Some(_) => Some(Spool::new(dir, "sets.npy".into(), k).map_err(io_err)?),
            None => None,
        };
        let mut labels = if s.src.has_labels() {
            Some(Spool::new(dir, "labels.npy".into(), 1).map_err(io_err)?)
        } else {
            None
        };
        let mut ids = if s.src.has_ids() {
            let f = File::create(dir.join("ids.txt")).map_err(io_err)?;
            Some(BufWriter::new(f))
        } else {
            None
        };
        let mut rows = 0u64;
        s.for_each(|row, scored| {
            rows += 1;
            if let Some(ids) = &mut ids {
                let id = row.id.unwrap_or("");
                if id.contains(['\n', '\r']) {
                    return Err(CliError::Input(format!(
                        "{}: the id holds a line break; an NPY output writes one id per line \
                         of ids.txt (write CSV output instead)",
                        at(input, row.location())
                    )));
                }
                ids.write_all(id.as_bytes()).map_err(io_err)?;
                ids.write_all(b"\n").map_err(io_err)?;
            }
            if let Some(labels) = &mut labels {
                let code = match row.label {
                    Label::Class(c) => i32::try_from(c).unwrap_or(NO_LABEL),
                    Label::Background => BACKGROUND,
                    Label::Missing => NO_LABEL,
                };
                labels.file.write_all(&code.to_le_bytes()).map_err(io_err)?;
            }
            for (spool, head_scores) in score_spools.iter_mut().zip(scored.scores.chunks_exact(k)) {
                for v in head_scores {
                    spool.file.write_all(&v.to_le_bytes()).map_err(io_err)?;
                }
            }
            for (spool, &p) in pred_spools.iter_mut().zip(scored.preds) {
                let p = if p < k {
                    i32::try_from(p).unwrap_or(-1)
                } else {
                    -1
                };
                spool.file.write_all(&p.to_le_bytes()).map_err(io_err)?;
            }
            if let (Some(spool), Some(mask)) = (&mut sets, scored.set) {
                for c in 0..k {
                    spool
                        .file
                        .write_all(&[u8::from(in_set(mask, c))])
                        .map_err(io_err)?;
                }
            }
            Ok(())
        })?;
        if let Some(mut ids) = ids {
            ids.flush().map_err(io_err)?;
            ids.get_ref().sync_all().map_err(io_err)?;
        }
        for spool in score_spools {
            spool
                .finish(dir, rows, f32::from_le_bytes)
                .map_err(io_err)?;
        }
        for spool in pred_spools {
            spool
                .finish(dir, rows, i32::from_le_bytes)
                .map_err(io_err)?;
        }
        if let Some(spool) = labels {
            spool
                .finish(dir, rows, i32::from_le_bytes)
                .map_err(io_err)?;
        }
        if let Some(spool) = sets {
            spool.finish(dir, rows, |[b]: [u8; 1]| b).map_err(io_err)?;
        }
        Ok(())
    })
}
