//! Turns the table file named by `MLMAP_TABLE` (default `tables/default.mlmap`) into
//! validated Rust constants in `$OUT_DIR/embedded_table.rs` (DESIGN §5, way 2).
//!
//! The decoder and validation are the library's own source files, compiled into this
//! script with `#[path]`, so the build accepts exactly the tables `Table::from_bytes`
//! accepts, and the derived constants (bin widths, Gaussian normalisers) are computed by
//! the same `f32` code that computes them on the device.
#![allow(dead_code, unused_imports, clippy::all)]

extern crate std;

#[path = "src/baseline.rs"]
mod baseline;
#[path = "src/dyn_table.rs"]
mod dyn_table;
#[path = "src/error.rs"]
mod error;
#[path = "src/gaussian.rs"]
mod gaussian;
#[path = "src/histogram.rs"]
mod histogram;
#[path = "src/layer.rs"]
mod layer;
#[path = "src/math.rs"]
mod math;
#[path = "src/name.rs"]
mod name;
#[path = "src/table.rs"]
mod table;
#[path = "src/wire.rs"]
mod wire;

// Names the shared modules refer to through the crate root.
use error::{BatchError, DecodeError, EncodeError, Head, InferError, TableError};
use gaussian::Gaussian;
use histogram::{EdgeMode, Histogram, UpperTail, FREQUENCY_SUM_TOLERANCE};
use layer::Scores;
use math::Libm;
use name::{ClassName, NAME_MAX};
use table::Table;
use wire::{ClassSpec, Settings, FORMAT_VERSION, MAX_LAMBDA};

use std::fmt::Write as _;
use std::path::PathBuf;
use std::{env, fmt, fs};

/// A build failure whose `Debug` is the plain message, so cargo shows it readably.
struct BuildError(String);

impl fmt::Debug for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BuildError {}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("cargo::rerun-if-env-changed=MLMAP_TABLE");
    println!("cargo::rerun-if-changed=build.rs");
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR")?);
    let path = match env::var_os("MLMAP_TABLE") {
        Some(p) => {
            let p = PathBuf::from(p);
            if p.is_absolute() {
                p
            } else {
                manifest.join(p)
            }
        }
        None => manifest.join("tables").join("default.mlmap"),
    };
    println!("cargo::rerun-if-changed={}", path.display());
    let fail = |msg: String| -> Box<dyn std::error::Error> {
        Box::new(BuildError(format!(
            "mlmap: cannot embed the table `{}` (MLMAP_TABLE): {msg}",
            path.display()
        )))
    };
    let bytes = fs::read(&path).map_err(|e| fail(e.to_string()))?;
    let table = dyn_table::DynTable::from_bytes(&bytes).map_err(|e| fail(e.to_string()))?;
    // Name the source relative to the package when it is inside it (reproducible builds).
    let shown = path
        .strip_prefix(&manifest)
        .unwrap_or(&path)
        .display()
        .to_string();
    let code = render(&table, &shown, &bytes);
    let out = PathBuf::from(env::var("OUT_DIR")?).join("embedded_table.rs");
    fs::write(out, code)?;
    Ok(())
}

/// An `f32` as an exact, const-evaluable expression.
fn f(v: f32) -> String {
    format!("f32::from_bits(0x{:08x})", v.to_bits())
}

fn hist(h: &Histogram<Vec<f32>>) -> String {
    let freqs: Vec<String> = h.freqs.iter().map(|&v| f(v)).collect();
    format!(
        "crate::Histogram {{ lo: {}, hi: {}, width: {}, inv_width: {}, freqs: [{}] }}",
        f(h.lo),
        f(h.hi),
        f(h.width),
        f(h.inv_width),
        freqs.join(", ")
    )
}

fn render(t: &dyn_table::DynTable, source: &str, bytes: &[u8]) -> String {
    let mut s = String::new();
    let k = t.k();
    let _ = writeln!(
        s,
        "/// Number of classes of the embedded table.\npub const K: usize = {k};"
    );
    let _ = writeln!(
        s,
        "/// ML bins of the embedded table.\npub const BINS_ML: usize = {};",
        t.bins_ml()
    );
    let _ = writeln!(
        s,
        "/// MAP bins of the embedded table.\npub const BINS_MAP: usize = {};",
        t.bins_map()
    );
    let _ = writeln!(
        s,
        "/// The type of [`TABLE`].\npub type EmbeddedTable = crate::Table<K, BINS_ML, BINS_MAP>;"
    );
    let _ = writeln!(
        s,
        "/// The file the table was embedded from.\npub const SOURCE: &str = {source:?};"
    );
    let _ = writeln!(
        s,
        "/// The embedded file's bytes (for checks; firmware needs only [`TABLE`])."
    );
    let _ = writeln!(s, "pub static BYTES: [u8; {}] = {:?};", bytes.len(), bytes);
    let names: Vec<String> = t
        .names
        .iter()
        .map(|n| {
            format!(
                "crate::ClassName {{ len: {}, bytes: {:?} }}",
                n.len, n.bytes
            )
        })
        .collect();
    let priors: Vec<String> = t
        .priors
        .iter()
        .map(|g| {
            format!(
                "crate::Gaussian {{ mean: {}, var: {}, neg_half_inv_var: {}, norm: {} }}",
                f(g.mean),
                f(g.var),
                f(g.neg_half_inv_var),
                f(g.norm)
            )
        })
        .collect();
    let ml: Vec<String> = t.ml.iter().map(hist).collect();
    let map: Vec<String> = t.map.iter().map(hist).collect();
    let st = &t.settings;
    let edge = match st.edge_mode {
        EdgeMode::Linspace => "Linspace",
        EdgeMode::Matlab => "Matlab",
    };
    let tail = match st.upper_tail {
        UpperTail::Zero => "Zero",
        UpperTail::Clamp => "Clamp",
    };
    let _ = writeln!(
        s,
        "/// The validated table, ready to score: no decoding at start-up.\n\
         pub static TABLE: EmbeddedTable = crate::Table {{\n    names: [{}],\n    rows: {:?},\n    \
         priors: [{}],\n    ml: [{}],\n    map: [{}],\n    settings: crate::Settings {{ lambda_ml: {}, \
         lambda_map: {}, edge_mode: crate::EdgeMode::{edge}, upper_tail: crate::UpperTail::{tail} }},\n}};",
        names.join(", "),
        t.rows,
        priors.join(", "),
        ml.join(",\n        "),
        map.join(",\n        "),
        f(st.lambda_ml),
        f(st.lambda_map),
    );
    s
}
