//! Runs N detections (or N table decodings) of one kind, for counting instructions with
//! valgrind: `tools/callgrind_counts.sh` runs it for N and 2N and reports the
//! difference divided by N, so the fixed cost (start-up, reading the rows) cancels.
//!
//! ```text
//! cargo run --release --features micromath,std --example instr_count -- map 16384
//! ```
//!
//! Kinds: `sigmoid`, `softmax`, `ml`, `map`, `map_fast` (MAP with the `FastMath`
//! backend), `map_micromath` (MAP with `Micromath`), `bayes` and `bayes_fast` (the Bayes head with
//! `Libm` and `FastMath`), `open` (the open head as shipped: T = 1, epsilon = 0),
//! `open_eps` (the open head with T = 1.37 and epsilon = 1e-3, an unknown category as
//! `tune` chooses one), `open_map` (`open_eps` with a recalibration map of 32 knots,
//! DESIGN §1.9), `sigmoid_fast` (the Sigmoid layer
//! with `FastMath`), `q8_ml`, `q8_map`, `q8_bayes`, `q8_open` (the quantized table, int8
//! codes `round(x / 0.08)` of the same rows), `q8_noop` (the loop around the quantized
//! kinds), `q8_decode` (`QTable::from_bytes` of the section), `decode`, and `noop` (a layer that only copies the logits: the cost
//! of the loop around the layer).
//!
//! The runtime-safety kinds run on the sections of `tests/golden/monitor_small.mlmap`
//! and `tests/golden/conformal_small.mlmap` (the shipped table's): `monitor_push`
//! (`Monitor::push`, W = 50, the window ends amortised over its detections),
//! `monitor_push_nowin` (the same with a window that never ends: the push alone),
//! `monitor_push_open` (`Monitor::push_open`: the open head's scores and the push in one
//! pass, W = 50), `conformal_set` (`ConformalSpec::set64`: the open head's scores and
//! the class set, DESIGN §8), and `open_set_of` (`Table::open`, then
//! `ConformalSpec::set_of` on its scores). The detections are
//! the first 4096 rows of `examples/data/test.csv`, cycled in file order; use an N that
//! is a multiple of 4096 so N and 2N see the same mix of rows.

use std::hint::black_box;
use std::process::ExitCode;

use mlmap::baseline::{sigmoid, softmax};
use mlmap::{
    quantize_into, ConformalSpec, FastMath, InferError, Libm, Micromath, Monitor, MonitorParams,
    MonitorSpec, QParams, QTable, Scores, Table,
};

type Shipped = Table<3, 22, 17, 22, 4>;
/// The shipped shape with room for a map of 32 knots per head.
type ShippedMaps = Table<3, 22, 17, 22, 4, { mlmap::MAX_KNOTS }>;

const TABLE: &[u8] = include_bytes!("../tables/default.mlmap");
const TEST_CSV: &str = include_str!("data/test.csv");
/// The shipped table with a monitor section (W = 50).
const MONITOR_FILE: &[u8] = include_bytes!("../tests/golden/monitor_small.mlmap");
/// The shipped table with a conformal section (the open head, alpha 0.1).
const CONFORMAL_FILE: &[u8] = include_bytes!("../tests/golden/conformal_small.mlmap");
const ROWS: usize = 4096;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(kind), Some(Ok(n))) = (args.first(), args.get(1).map(|n| n.parse::<usize>())) else {
        eprintln!(
            "usage: instr_count noop|sigmoid|sigmoid_fast|softmax|ml|map|map_fast|map_micromath|bayes|bayes_fast|open|open_eps|open_map|decode|q8_noop|q8_ml|q8_map|q8_bayes|q8_open|q8_decode|monitor_push|monitor_push_nowin|monitor_push_open|conformal_set|open_set_of N"
        );
        return ExitCode::from(2);
    };
    let mut table = Shipped::from_bytes(TABLE).expect("the shipped table decodes");
    if kind == "open_map" {
        return open_map(&table, n);
    }
    if kind == "open_eps" {
        let d = mlmap::host::DynTable::from_table(&table)
            .with_open(1.37, 1e-3)
            .expect("valid open-head parameters");
        table = Shipped::try_from(&d).expect("the same shape");
    }
    let (xs, os) = detections(&table);
    if kind.starts_with("monitor_") || kind == "conformal_set" || kind == "open_set_of" {
        return safety(&table, kind, &xs, &os, n);
    }
    if let Some(head) = kind.strip_prefix("q8_") {
        return quantized(&table, head, &xs, &os, n);
    }
    let layer: fn(&Shipped, &[f32; 3], f32) -> Result<Scores<3>, InferError> = match kind.as_str() {
        "noop" => |_, x, _| Ok(Scores(*x)),
        "sigmoid" => |_, x, o| sigmoid::<Libm, 3>(x, o),
        "sigmoid_fast" => |_, x, o| sigmoid::<FastMath, 3>(x, o),
        "softmax" => |_, x, o| softmax::<Libm, 3>(x, o),
        "ml" => |t, x, o| t.ml(x, o),
        "map" => |t, x, o| t.map(x, o),
        "map_fast" => |t, x, o| t.map_with::<FastMath>(x, o),
        "map_micromath" => |t, x, o| t.map_with::<Micromath>(x, o),
        "bayes" => |t, x, o| t.bayes_with::<Libm>(x, o),
        "bayes_fast" => |t, x, o| t.bayes_with::<FastMath>(x, o),
        "open" | "open_eps" => |t, x, o| t.open(x, o),
        "decode" => {
            let mut ok = 0usize;
            for _ in 0..n {
                ok += usize::from(Shipped::from_bytes(black_box(TABLE)).is_ok());
            }
            println!("{kind} x {n}: {ok} decoded");
            return ExitCode::SUCCESS;
        }
        other => {
            eprintln!("unknown kind {other:?}");
            return ExitCode::from(2);
        }
    };
    let mut checksum = 0.0f64;
    for i in 0..n {
        let r = i % ROWS;
        let s = layer(black_box(&table), black_box(&xs[r]), black_box(os[r]));
        checksum += f64::from(black_box(s).map(|s| s.0[0]).unwrap_or(0.0));
    }
    println!("{kind} x {n}: checksum {checksum}");
    ExitCode::SUCCESS
}

/// `open_eps` with a map of 32 knots on the open head: `x = i / 31`, `y` a concave
/// curve, so that the binary search takes every path.
fn open_map(table: &Shipped, n: usize) -> ExitCode {
    let knots: Vec<mlmap::Knot> = (0..32)
        .map(|i| {
            let x = i as f32 / 31.0;
            mlmap::Knot {
                x,
                y: 0.02 + 0.97 * x.sqrt(),
            }
        })
        .collect();
    let d = mlmap::host::DynTable::from_table(table)
        .with_open(1.37, 1e-3)
        .and_then(|d| d.with_map(mlmap::Head::Open, knots))
        .expect("valid parameters");
    let t = ShippedMaps::try_from(&d).expect("the same shape");
    let (xs, os) = detections(table);
    let mut checksum = 0.0f64;
    for i in 0..n {
        let r = i % ROWS;
        let s = black_box(&t).open(black_box(&xs[r]), black_box(os[r]));
        checksum += f64::from(black_box(s).map(|s| s.0[0]).unwrap_or(0.0));
    }
    println!("open_map x {n}: checksum {checksum}");
    ExitCode::SUCCESS
}

/// The runtime-safety kinds: the monitor's pushes and the conformal sets.
fn safety(table: &Shipped, kind: &str, xs: &[[f32; 3]], os: &[f32], n: usize) -> ExitCode {
    let view = table.view();
    let mut checksum = 0.0f64;
    if kind == "conformal_set" {
        let spec = ConformalSpec::from_bytes(CONFORMAL_FILE, &view).expect("the conformal section");
        let (mut scores, mut scratch) = ([0.0f32; 3], [0.0f32; 4]);
        for i in 0..n {
            let r = i % ROWS;
            let set = black_box(&spec).set64(
                black_box(&view),
                black_box(&xs[r]),
                black_box(os[r]),
                &mut scores,
                &mut scratch,
            );
            checksum += black_box(set).map_or(0.0, |m| m as f64) + f64::from(scores[0]);
        }
        println!("{kind} x {n}: checksum {checksum}");
        return ExitCode::SUCCESS;
    }
    if kind == "open_set_of" {
        let spec = ConformalSpec::from_bytes(CONFORMAL_FILE, &view).expect("the conformal section");
        let mut mask = [0u32; 1];
        for i in 0..n {
            let r = i % ROWS;
            let scores = black_box(table).open(black_box(&xs[r]), black_box(os[r]));
            let size = scores.and_then(|s| black_box(&spec).set_of(&s.0, &mut mask));
            checksum += black_box(size).map_or(0.0, f64::from) + f64::from(mask[0]);
        }
        println!("{kind} x {n}: checksum {checksum}");
        return ExitCode::SUCCESS;
    }
    let shipped = MonitorSpec::from_bytes(MONITOR_FILE, &view).expect("the monitor section");
    // The same section with a window that never ends: the cost of the push alone.
    let mut reference = [0.0f32; 3 * 22];
    for (i, e) in reference.iter_mut().enumerate() {
        *e = shipped.reference(i / 22, i % 22).expect("a share");
    }
    let params = MonitorParams {
        window: u32::MAX,
        ..shipped.params()
    };
    let mut section = vec![0u8; mlmap::monitor_section_len(3, 22)];
    let crc = u32::from_le_bytes(TABLE[TABLE.len() - 4..].try_into().expect("four bytes"));
    mlmap::write_monitor_section(&mut section, crc, 3, 22, true, &params, &reference)
        .expect("the section");
    let endless = MonitorSpec::from_bytes(&section, &view).expect("the section reads back");
    let spec = if kind == "monitor_push_nowin" {
        &endless
    } else {
        &shipped
    };
    let mut monitor: Monitor<'_, 3, 22, 4> = Monitor::new(spec).expect("the shipped shape");
    let mut windows = 0usize;
    for i in 0..n {
        let r = i % ROWS;
        let report = if kind == "monitor_push_open" {
            black_box(&mut monitor)
                .push_open(black_box(&xs[r]), black_box(os[r]))
                .map(|(s, w)| {
                    checksum += f64::from(s.0[0]);
                    w
                })
        } else if kind.starts_with("monitor_push") {
            black_box(&mut monitor).push(black_box(&xs[r]), black_box(os[r]))
        } else {
            eprintln!("unknown kind {kind:?}");
            return ExitCode::from(2);
        };
        if let Ok(Some(w)) = black_box(report) {
            windows += 1;
            checksum += f64::from(w.summary.psi_max);
        }
    }
    println!("{kind} x {n}: {windows} windows, checksum {checksum}");
    ExitCode::SUCCESS
}

/// The scale of the int8 codes of the quantized kinds (logits -10.24 to 10.16).
const SCALE: f32 = 0.08;

/// The quantized kinds: the shipped table's int8 section, the same rows as codes.
fn quantized(table: &Shipped, head: &str, xs: &[[f32; 3]], os: &[f32], n: usize) -> ExitCode {
    let params = QParams {
        bits: 8,
        scales: &[SCALE; 3],
        zero_points: &[0; 3],
        bayes: true,
    };
    let mut buf = vec![0u8; 8192];
    let bytes = quantize_into(&table.view(), &params, &mut buf).expect("the section fits");
    let q = QTable::<3, i8>::from_bytes(bytes).expect("the section reads back");
    let codes: Vec<[i8; 3]> = xs
        .iter()
        .map(|x| x.map(|v| (v / SCALE).round().clamp(-128.0, 127.0) as i8))
        .collect();
    type Layer = fn(&QTable<'_, 3, i8>, &[i8; 3], f32) -> Result<Scores<3>, InferError>;
    let layer: Layer = match head {
        "noop" => |_, c, _| Ok(Scores(c.map(f32::from))),
        "ml" => |q, c, o| q.ml(c, o),
        "map" => |q, c, o| q.map(c, o),
        "bayes" => |q, c, o| q.bayes(c, o),
        "open" => |q, c, o| q.open(c, o),
        "decode" => {
            let mut ok = 0usize;
            for _ in 0..n {
                ok += usize::from(QTable::<3, i8>::from_bytes(black_box(bytes)).is_ok());
            }
            println!("q8_decode x {n}: {ok} decoded ({} bytes)", bytes.len());
            return ExitCode::SUCCESS;
        }
        other => {
            eprintln!("unknown kind q8_{other}");
            return ExitCode::from(2);
        }
    };
    let mut checksum = 0.0f64;
    for i in 0..n {
        let r = i % ROWS;
        let s = layer(black_box(&q), black_box(&codes[r]), black_box(os[r]));
        checksum += f64::from(black_box(s).map(|s| s.0[0]).unwrap_or(0.0));
    }
    println!("q8_{head} x {n}: checksum {checksum}");
    ExitCode::SUCCESS
}

/// The logits (in the table's class order) and objectness of the first rows.
fn detections(table: &Shipped) -> (Vec<[f32; 3]>, Vec<f32>) {
    let mut lines = TEST_CSV.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect("column");
    let logit_cols: [usize; 3] = core::array::from_fn(|i| col(table.class_name(i).expect("class")));
    let os_col = col("objectness");
    let (mut xs, mut os) = (Vec::new(), Vec::new());
    for line in lines.take(ROWS) {
        let f: Vec<&str> = line.split(',').collect();
        let num = |c: usize| f[c].parse::<f32>().expect("number");
        xs.push(logit_cols.map(num));
        os.push(num(os_col));
    }
    (xs, os)
}
