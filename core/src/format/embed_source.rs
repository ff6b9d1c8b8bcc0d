//! Rust source for a table embedded at build time (docs/DESIGN.md §5, way 2). Not part
//! of the API: `mlmap`'s build script writes [`rust_source`] of a decoded, validated
//! [`DynTable`] to `$OUT_DIR`; the source calls the constructors of `embed.rs`.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;
use core::fmt::Write as _;

use crate::math::histogram::{EdgeMode, Histogram, UpperTail};
use crate::DynTable;

/// An `f32` as an exact, const-evaluable expression.
fn f(v: f32) -> String {
    format!("f32::from_bits(0x{:08x})", v.to_bits())
}

fn floats(values: &[f32]) -> String {
    let v: Vec<String> = values.iter().map(|&x| f(x)).collect();
    format!("[{}]", v.join(", "))
}

fn hist(h: &Histogram<Vec<f32>>) -> String {
    format!(
        "E::histogram({}, {}, {}, {}, {})",
        f(h.lo),
        f(h.hi),
        f(h.width),
        f(h.inv_width),
        floats(&h.freqs)
    )
}

/// The open head's parameters as an expression: `E::open(..)` with the validated
/// values, bit for bit, or `None`.
fn open_source(open: Option<crate::OpenParams>) -> String {
    match open {
        Some(o) => format!(
            "E::open({}, {}, {})",
            f(o.temperature()),
            f(o.epsilon()),
            f(o.log_unknown())
        ),
        None => "None".into(),
    }
}

/// Rust source defining `K`, `BINS_ML`, `BINS_MAP`, `BINS_BAYES`, `CATEGORIES`,
/// `EmbeddedTable`, `SOURCE`, `BYTES` and `TABLE` for the table `t` decoded from
/// `bytes` (read from `source`). `krate` is the path the source names this crate by.
pub fn rust_source(t: &DynTable, source: &str, bytes: &[u8], krate: &str) -> String {
    let v = t.view();
    let k = v.k();
    let bayes = v.bayes();
    let (bins_bayes, categories) = bayes.map_or((0, 0), |b| (b.bins(), b.categories()));
    let knots = v.maps.0.iter().map(|m| m.len()).max().unwrap_or(0);
    let mut s = String::new();
    let _ = writeln!(s, "use {krate}::__embed as E;");
    let consts = [
        ("Number of classes of the embedded table.", "K", k),
        ("ML bins of the embedded table.", "BINS_ML", v.bins_ml()),
        ("MAP bins of the embedded table.", "BINS_MAP", v.bins_map()),
        (
            "Bayes bins of the embedded table (0: no Bayes head).",
            "BINS_BAYES",
            bins_bayes,
        ),
        (
            "Bayes categories of the embedded table (0: no Bayes head).",
            "CATEGORIES",
            categories,
        ),
        (
            "Knots per recalibration map of the embedded table (0: no map).",
            "MAP_KNOTS",
            knots,
        ),
        (
            "1 when the embedded table has the objectness feature, else 0.",
            "OBJECTNESS_FEATURE",
            usize::from(bayes.is_some_and(|b| b.objectness.is_some())),
        ),
    ];
    for (doc, name, value) in consts {
        let _ = writeln!(s, "/// {doc}\npub const {name}: usize = {value};");
    }
    let _ = writeln!(
        s,
        "/// The type of [`TABLE`].\npub type EmbeddedTable = {krate}::Table<K, BINS_ML, BINS_MAP, BINS_BAYES, CATEGORIES, MAP_KNOTS, OBJECTNESS_FEATURE>;"
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
    let names: Vec<String> = v
        .names
        .iter()
        .map(|n| format!("E::class_name({}, {:?})", n.len, n.bytes))
        .collect();
    let priors: Vec<String> = v
        .priors
        .iter()
        .map(|g| {
            format!(
                "E::gaussian({}, {}, {}, {})",
                f(g.mean),
                f(g.var),
                f(g.neg_half_inv_var),
                f(g.norm)
            )
        })
        .collect();
    let ml: Vec<String> = v.ml.iter().map(hist).collect();
    let map: Vec<String> = v.map.iter().map(hist).collect();
    let st = v.settings();
    let edge = match st.edge_mode {
        EdgeMode::Linspace => "Linspace",
        EdgeMode::Matlab => "Matlab",
    };
    let tail = match st.upper_tail {
        UpperTail::Zero => "Zero",
        UpperTail::Clamp => "Clamp",
    };
    let open = open_source(v.open());
    let (axes, terms, brows, log_prior, lambda, log_lambda) = match bayes {
        Some(b) => {
            let axes: Vec<String> = b
                .axes()
                .iter()
                .map(|a| {
                    format!(
                        "E::axis({}, {}, {}, {}, {}, {})",
                        f(a.lo),
                        f(a.hi),
                        f(a.width),
                        f(a.inv_width),
                        a.bins,
                        f(a.cap)
                    )
                })
                .collect();
            let per_logit: Vec<String> = b
                .all_terms()
                .chunks(bins_bayes * categories)
                .map(|logit| {
                    let per_bin: Vec<String> = logit.chunks(categories).map(floats).collect();
                    format!("[{}]", per_bin.join(", "))
                })
                .collect();
            (
                format!("[{}]", axes.join(", ")),
                format!("[{}]", per_logit.join(",\n        ")),
                format!("{:?}", b.all_rows()),
                floats(b.log_prior),
                f(b.lambda),
                f(b.log_lambda),
            )
        }
        None => (
            format!("[E::axis(0.0, 0.0, 0.0, 0.0, 0, 0.0); {k}]"),
            format!("[[]; {k}]"),
            "[]".into(),
            "[]".into(),
            "0.0".into(),
            "0.0".into(),
        ),
    };
    let maps: Vec<String> = v
        .maps
        .0
        .iter()
        .map(|m| {
            let mut pairs: Vec<String> = m
                .iter()
                .map(|p| format!("E::knot({}, {})", f(p.x), f(p.y)))
                .collect();
            pairs.resize(knots, "E::knot(0.0, 0.0)".into());
            format!("[{}]", pairs.join(", "))
        })
        .collect();
    let map_lens: Vec<String> = v.maps.0.iter().map(|m| format!("{}", m.len())).collect();
    let (os_axis, os_terms) = match bayes.and_then(|b| b.objectness) {
        Some((a, terms)) => (
            format!(
                "[E::axis({}, {}, {}, {}, {}, {})]",
                f(a.lo),
                f(a.hi),
                f(a.width),
                f(a.inv_width),
                a.bins,
                f(a.cap)
            ),
            format!(
                "[[{}]]",
                terms
                    .chunks(categories.max(1))
                    .map(floats)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ),
        None => ("[]".into(), "[]".into()),
    };
    let _ = writeln!(
        s,
        "/// The validated table, ready to score: no decoding at start-up.\n\
         pub static TABLE: EmbeddedTable = E::table(\n    [{}],\n    {:?},\n    [{}],\n    [{}],\n    [{}],\n    \
         {krate}::Settings {{ lambda_ml: {}, lambda_map: {}, edge_mode: {krate}::EdgeMode::{edge}, \
         upper_tail: {krate}::UpperTail::{tail} }},\n    {axes},\n    {terms},\n    {brows},\n    {log_prior},\n    {lambda},\n    {log_lambda},\n    {open},\n    [{}],\n    [{}],\n    {os_axis},\n    {os_terms},\n);",
        names.join(", "),
        v.rows,
        priors.join(", "),
        ml.join(",\n        "),
        map.join(",\n        "),
        f(st.lambda_ml),
        f(st.lambda_map),
        maps.join(",\n        "),
        map_lens.join(", "),
    );
    s
}

/// Rust source defining `QUANTIZED_K`, `QUANTIZED_BITS`, `QuantizedCode`,
/// `EmbeddedQTable`, `QUANTIZED_SOURCE`, `QUANTIZED_SECTION` (the section's bytes) and
/// `QUANTIZED` (a [`QTable`](crate::QTable) over them, built without decoding) for the
/// quantized section of `bytes` (a section alone, or a table file with one), read from
/// `source`. The section is validated by [`DynQTable::from_bytes`](crate::DynQTable).
///
/// # Errors
///
/// The [`QTableError`](crate::QTableError) of an invalid or missing section.
pub fn quantized_source(
    bytes: &[u8],
    source: &str,
    krate: &str,
) -> Result<String, crate::QTableError> {
    let q = crate::DynQTable::from_bytes(bytes)?;
    let section = bytes
        .get(bytes.len() - q.section_len()..)
        .unwrap_or_default();
    let base = section.as_ptr() as usize;
    // Every slice of `q` borrows `section`: name it by its offset, through the
    // constructor `fun` of its element size (1, 4 or 8 bytes).
    let named = |fun: &str, ptr: *const u8, len: usize| -> String {
        if len == 0 {
            return "&[]".into();
        }
        let at = (ptr as usize).wrapping_sub(base);
        format!("E::{fun}(&QUANTIZED_SECTION, {at}, {len})")
    };
    let part = |p: &[u8]| named("part", p.as_ptr(), p.len());
    let part4 = |p: &[[u8; 4]]| named("part4", p.as_ptr().cast(), p.len());
    let part8 = |p: &[[u8; 8]]| named("part8", p.as_ptr().cast(), p.len());
    let m = &q.meta;
    let maps: Vec<String> = m.maps.iter().map(|k| part8(k)).collect();
    let objectness = match m.objectness {
        Some((a, terms)) => format!(
            "Some((E::axis({}, {}, {}, {}, {}, {}), {}))",
            f(a.lo),
            f(a.hi),
            f(a.width),
            f(a.inv_width),
            a.bins,
            f(a.cap),
            part4(terms)
        ),
        None => "None".into(),
    };
    let code = if m.bits == 8 { "i8" } else { "i16" };
    let open = open_source(m.open);
    let mut s = String::new();
    let _ = writeln!(s, "use {krate}::__embed as E;");
    let _ = writeln!(
        s,
        "/// Number of classes of the embedded quantized section.\npub const QUANTIZED_K: usize = {};",
        m.k
    );
    let _ = writeln!(
        s,
        "/// Bits per code of the embedded quantized section.\npub const QUANTIZED_BITS: u8 = {};",
        m.bits
    );
    let _ = writeln!(
        s,
        "/// The code type of the embedded quantized section.\npub type QuantizedCode = {code};"
    );
    let _ = writeln!(
        s,
        "/// The type of [`QUANTIZED`].\npub type EmbeddedQTable = {krate}::QTable<'static, QUANTIZED_K, QuantizedCode>;"
    );
    let _ = writeln!(
        s,
        "/// The file the quantized section was embedded from.\npub const QUANTIZED_SOURCE: &str = {source:?};"
    );
    let _ = writeln!(
        s,
        "/// The embedded section's bytes (`QTable::from_bytes` reads them too).\npub static QUANTIZED_SECTION: [u8; {}] = {:?};",
        section.len(),
        section
    );
    let classes: Vec<String> = q
        .classes
        .iter()
        .map(|c| {
            format!(
                "E::qclass({}, {}, ({}, {}, {}), ({}, {}))",
                f(c.scale),
                c.zero_point,
                c.ml_start,
                part(c.ml_index),
                part4(c.ml_masses),
                c.map_start,
                part4(c.map_masses)
            )
        })
        .collect();
    let logits: Vec<String> = (0..q.classes.len())
        .map(|j| match q.logits.get(j) {
            Some(l) => format!(
                "E::qlogit({}, {}, {})",
                l.start,
                part(l.index),
                part4(l.terms)
            ),
            None => "E::QLOGIT_NONE".into(),
        })
        .collect();
    let _ = writeln!(
        s,
        "/// The embedded quantized section, validated at build time: no decoding at start-up.\n\
         pub static QUANTIZED: EmbeddedQTable = E::qtable(\n    \
         E::qmeta({}, {}, {}, {}, {}, 0x{:08x}, [{}, {}, {}], {}, {open}, [{}], {}, {}),\n    [{}],\n    [{}],\n);",
        m.bits,
        m.k,
        m.bins_ml,
        m.bins_bayes,
        m.categories,
        m.table_crc,
        f(m.lambda_ml),
        f(m.lambda_map),
        f(m.log_lambda),
        part4(m.log_prior),
        maps.join(", "),
        objectness,
        m.len,
        classes.join(",\n     "),
        logits.join(",\n     ")
    );
    Ok(s)
}
