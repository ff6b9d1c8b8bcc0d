//! `mlmap apply`: score every row through the layer, write CSV (DESIGN §4).

use std::fmt::Write as _;

use mlmap::host::data::{self, at, check_classes};
use mlmap::host::dataset::Label;
use mlmap::host::metrics::decision;
use mlmap::{FastMath, Libm};

use crate::args::ApplyArgs;
use crate::error::{CliError, Result};
use crate::output;
use crate::shared::read_table;

pub fn run(args: &ApplyArgs) -> Result<()> {
    output::check_outputs(&args.output, &[&args.table, &args.input])?;
    let (table, _) = read_table(&args.table)?;
    let src = data::open(&args.input)?;
    check_classes(&args.input, src.classes(), table.class_names())?;
    let names: Vec<&str> = table.class_names().collect();
    let k = names.len();
    // The Bayes head's columns only when the table has it; its scratch holds one
    // float per category.
    let bayes_cats = table.bayes().map(|b| b.categories());
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
        header.extend(names.iter().map(|n| format!("ml_{n}")));
        header.extend(names.iter().map(|n| format!("map_{n}")));
        if bayes_cats.is_some() {
            header.extend(names.iter().map(|n| format!("bayes_{n}")));
        }
        header.push("ml_pred".into());
        header.push("map_pred".into());
        if bayes_cats.is_some() {
            header.push("bayes_pred".into());
        }
        csv.write_record(&header).map_err(csv_err)?;
        let mut x = vec![0.0f32; k];
        let mut ml = vec![0.0f32; k];
        let mut map = vec![0.0f32; k];
        let mut scratch = vec![0.0f32; k];
        let mut bayes = vec![0.0f32; if bayes_cats.is_some() { k } else { 0 }];
        let mut bayes_scratch = vec![0.0f32; bayes_cats.unwrap_or(0)];
        // Fields are written one by one, numbers through one reused buffer: no
        // allocation per row.
        let mut number = String::new();
        src.for_each_row(|row| -> Result<()> {
            for (d, &s) in x.iter_mut().zip(row.logits) {
                *d = s as f32;
            }
            let os = row.objectness as f32;
            let at = |e: mlmap::InferError| {
                CliError::Input(format!("{}: {e}", at(&args.input, row.location())))
            };
            table.ml_into(&x, os, &mut ml, &mut scratch).map_err(at)?;
            table
                .map_into::<Libm>(&x, os, &mut map, &mut scratch)
                .map_err(at)?;
            if bayes_cats.is_some() {
                // The device's default backend for this head (`Table::bayes`).
                table
                    .bayes_into::<FastMath>(&x, os, &mut bayes, &mut bayes_scratch)
                    .map_err(at)?;
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
            for v in ml.iter().chain(&map).chain(&bayes) {
                number.clear();
                let _ = write!(number, "{v}");
                csv.write_field(&number).map_err(csv_err)?;
            }
            let heads: &[&Vec<f32>] = if bayes_cats.is_some() {
                &[&ml, &map, &bayes]
            } else {
                &[&ml, &map]
            };
            for scores in heads {
                let pred = names.get(decision(scores, &x)).copied().unwrap_or("");
                csv.write_field(pred).map_err(csv_err)?;
            }
            csv.write_record(None::<&[u8]>).map_err(csv_err)?;
            Ok(())
        })?;
        csv.flush()
            .map_err(|e| CliError::internal(out_path, format!("cannot write: {e}")))
    })
}
