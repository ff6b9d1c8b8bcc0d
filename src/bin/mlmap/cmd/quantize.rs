//! `mlmap quantize --table T --scale S --zero-point Z --output Q`: the table with a
//! quantized section appended (docs/FORMAT.md), for detectors whose heads emit int8 or
//! int16 logits. `mlmap apply --quantized --table Q` scores integer logits with it;
//! `QTable::from_bytes` reads it on the device.

use std::path::PathBuf;

use clap::Args;
use mlmap::host::{DynQTable, DynTable};
use mlmap::{quantize_into, quantized_len, QParams};

use crate::error::{CliError, Result};
use crate::output;
use crate::shared::read_table;

/// Flags of `quantize`.
#[derive(Debug, Args)]
pub struct QuantizeArgs {
    /// The table.
    #[arg(long, value_name = "TABLE")]
    pub table: PathBuf,
    /// Scale of the quantized logits: one value for every class, or one per class in
    /// table order, comma-separated. The logit of code q is (q - zero_point) * scale.
    #[arg(
        long,
        value_name = "S[,S...]",
        value_delimiter = ',',
        value_parser = crate::args::f32_value,
        required = true,
        allow_negative_numbers = true
    )]
    pub scale: Vec<f32>,
    /// Zero point of the quantized logits: one value, or one per class, comma-separated.
    #[arg(
        long,
        value_name = "Z[,Z...]",
        value_delimiter = ',',
        default_value = "0",
        allow_negative_numbers = true
    )]
    pub zero_point: Vec<i32>,
    /// Bits per code: 8 (int8) or 16 (int16).
    #[arg(long, default_value_t = 8, value_name = "8|16")]
    pub bits: u8,
    /// Leave the Bayes head, and with it the open head, out of the section (smaller;
    /// `apply --quantized` then writes no Bayes columns). Without this flag the section
    /// holds every head the table has.
    #[arg(long)]
    pub no_bayes: bool,
    /// The file to write: the table, then its quantized section.
    #[arg(long, short, value_name = "FILE")]
    pub output: PathBuf,
}

/// One value per class from a flag's list: one value for all, or exactly K.
fn per_class<T: Copy>(flag: &str, values: &[T], k: usize) -> Result<Vec<T>> {
    match values {
        [v] => Ok(vec![*v; k]),
        v if v.len() == k => Ok(v.to_vec()),
        v => Err(CliError::Input(format!(
            "--{flag} has {} values; give one, or one per class ({k})",
            v.len()
        ))),
    }
}

pub fn run(args: &QuantizeArgs) -> Result<()> {
    output::check_outputs(&args.output, &[&args.table])?;
    let (table, bytes) = read_table(&args.table)?;
    // A table that already carries sections is quantized from its table part; its
    // monitor and conformal sections (DESIGN §7, §8) follow the new quantized section.
    let table_len = mlmap::table_of(&bytes).len();
    let k = table.k();
    let scales = per_class("scale", &args.scale, k)?;
    let zero_points = per_class("zero-point", &args.zero_point, k)?;
    let params = QParams {
        bits: args.bits,
        scales: &scales,
        zero_points: &zero_points,
        bayes: table.bayes_head().is_some() && !args.no_bayes,
    };
    let view = table.view();
    let bad = |e| CliError::Input(format!("cannot quantize {}: {e}", args.table.display()));
    let n = quantized_len(&view, &params).map_err(bad)?;
    let mut out = bytes.get(..table_len).unwrap_or_default().to_vec();
    out.resize(table_len + n, 0);
    quantize_into(&view, &params, out.get_mut(table_len..).unwrap_or_default()).map_err(bad)?;
    for magic in [mlmap::MONITOR_MAGIC, *b"MLMS"] {
        if let Some(section) = mlmap::section_of(&bytes, magic) {
            out.extend_from_slice(section);
        }
    }
    // What was written reads back (the same checks as the device's).
    let q = DynQTable::from_bytes(&out).map_err(|e| {
        CliError::internal(&args.output, format!("section does not read back: {e}"))
    })?;
    let heads = match (q.has_bayes(), q.open_params().is_some()) {
        (true, true) => "ML, MAP, Bayes, open",
        (true, false) => "ML, MAP, Bayes",
        _ => "ML, MAP",
    };
    output::write_bytes_atomic(&args.output, &out)?;
    output::print(&summary(args, &table, table_len, n, heads))
}

fn summary(
    args: &QuantizeArgs,
    table: &DynTable,
    table_len: usize,
    n: usize,
    heads: &str,
) -> String {
    format!(
        "wrote {}: table {table_len} bytes + quantized section {n} bytes \
         (int{} codes, {} classes, heads {heads})\n",
        args.output.display(),
        args.bits,
        table.k(),
    )
}
