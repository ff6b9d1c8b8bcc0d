//! `mlmap apply`: score every row through the layer, write CSV (DESIGN §4). With
//! `--quantized`, the logits are integer codes scored through the table file's
//! quantized section; the output is what `apply` writes for the dequantized logits.

use std::fmt::Write as _;

use mlmap::host::conformal::has_conformal;
use mlmap::host::data::{self, at, check_classes};
use mlmap::host::dataset::Label;
use mlmap::host::metrics::decision;
use mlmap::host::names::Named as _;
use mlmap::host::DynQTable;
use mlmap::{code_range, dequantize, set_words, ConformalSpec, Head};

use crate::args::ApplyArgs;
use crate::error::{CliError, Result};
use crate::output;
use crate::shared::read_table;

pub fn run(args: &ApplyArgs) -> Result<()> {
    output::check_outputs(&args.output, &[&args.table, &args.input])?;
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
    let src = if args.quantized {
        data::open_codes(&args.input)?
    } else {
        data::open(&args.input)?
    };
    check_classes(&args.input, src.classes(), table.class_names())?;
    let names: Vec<&str> = table.class_names().collect();
    let k = names.len();
    // The heads the table (or its quantized section) has, in column order: ML and MAP
    // always, Bayes and open when present (the open head is built on the Bayes head).
    let mut heads = vec![Head::Ml, Head::Map];
    let section_has_bayes = quantized.as_ref().is_none_or(DynQTable::has_bayes);
    let section_has_open = quantized.as_ref().is_none_or(|q| q.open_params().is_some());
    if table.bayes().is_some() && section_has_bayes {
        heads.push(Head::Bayes);
        if table.open().is_some() && section_has_open {
            heads.push(Head::Open);
        }
    }
    let view = table.view();
    // Conformal sets (DESIGN §8) when the table file holds the section: their head's
    // scores, as computed above, thresholded by the layer's spec.
    let conformal = if has_conformal(&bytes) {
        let spec = ConformalSpec::from_bytes(&bytes, &view)
            .map_err(|e| CliError::input(&args.table, e))?;
        let at = heads
            .iter()
            .position(|&h| h == spec.head())
            .ok_or_else(|| {
                CliError::input(
                    &args.table,
                    format!(
                    "its conformal sets threshold the {} head, which its quantized section lacks",
                    spec.head()
                ),
                )
            })?;
        Some((spec, at))
    } else {
        None
    };
    let mut mask = vec![0u32; set_words(k)];
    let mut codes = vec![0i32; k];
    let out_path = &args.output;
    let csv_err = |e: csv::Error| CliError::internal(out_path, format!("cannot write: {e}"));
    output::write_atomic(out_path, |w| {
        let mut csv = csv::Writer::from_writer(w);
        let mut header: Vec<String> = Vec::new();
        if src.has_ids() {
            header.push("id".into());
        }
        if src.has_labels() {
            header.push("label".into());
        }
        for &head in &heads {
            let prefix = head.name();
            header.extend(names.iter().map(|n| format!("{prefix}_{n}")));
        }
        for &head in &heads {
            header.push(format!("{}_pred", head.name()));
        }
        if conformal.is_some() {
            header.extend(names.iter().map(|n| format!("set_{n}")));
        }
        csv.write_record(&header).map_err(csv_err)?;
        let mut x = vec![0.0f32; k];
        // One row of K scores per head, in `heads` order; scratch for the largest head
        // (one float per Bayes category).
        let mut scores = vec![0.0f32; k * heads.len()];
        let cats = table.bayes().map_or(k, |b| b.categories());
        let mut scratch = vec![0.0f32; cats.max(k)];
        // Fields are written one by one, numbers through one reused buffer: no
        // allocation per row.
        let mut number = String::new();
        src.for_each_row(|row| -> Result<()> {
            let os = row.objectness as f32;
            let at = |e: mlmap::InferError| {
                CliError::Input(format!("{}: {e}", at(&args.input, row.location())))
            };
            if let Some(q) = &quantized {
                let (lo, hi) = code_range(q.bits());
                for (i, (c, &v)) in codes.iter_mut().zip(row.logits).enumerate() {
                    if !(v.fract() == 0.0 && (f64::from(lo)..=f64::from(hi)).contains(&v)) {
                        return Err(CliError::Input(format!(
                            "{}: logit of class {} is {v}, not an integer code in [{lo}, {hi}] \
                             ({}-bit quantized logits)",
                            data::at(&args.input, row.location()),
                            names.get(i).copied().unwrap_or(""),
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
                    q.score_into(head, &codes, os, out).map_err(at)?;
                }
            } else {
                for (d, &s) in x.iter_mut().zip(row.logits) {
                    *d = s as f32;
                }
                // Each head with the device's default backend (`Table::ml`, `map`,
                // `bayes`, `open`).
                for (&head, out) in heads.iter().zip(scores.chunks_exact_mut(k)) {
                    view.score_into(head, &x, os, out, &mut scratch)
                        .map_err(at)?;
                }
            }
            if src.has_ids() {
                csv.write_field(row.id.unwrap_or("")).map_err(csv_err)?;
            }
            if src.has_labels() {
                let label = match row.label {
                    Label::Class(c) => names.get(c).copied().unwrap_or(""),
                    Label::Background => "background",
                    Label::Missing => "",
                };
                csv.write_field(label).map_err(csv_err)?;
            }
            for v in &scores {
                number.clear();
                let _ = write!(number, "{v}");
                csv.write_field(&number).map_err(csv_err)?;
            }
            for head_scores in scores.chunks_exact(k) {
                let pred = names.get(decision(head_scores, &x)).copied().unwrap_or("");
                csv.write_field(pred).map_err(csv_err)?;
            }
            if let Some((spec, at_head)) = &conformal {
                let s = scores
                    .get(at_head * k..(at_head + 1) * k)
                    .unwrap_or_default();
                spec.set_of(s, &mut mask).map_err(at)?;
                for c in 0..k {
                    let inside = mask.get(c / 32).is_some_and(|w| w >> (c % 32) & 1 == 1);
                    csv.write_field(if inside { "1" } else { "0" })
                        .map_err(csv_err)?;
                }
            }
            csv.write_record(None::<&[u8]>).map_err(csv_err)?;
            Ok(())
        })?;
        csv.flush()
            .map_err(|e| CliError::internal(out_path, format!("cannot write: {e}")))
    })
}
