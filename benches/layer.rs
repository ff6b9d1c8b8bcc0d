//! The layers side by side, K = 3, on the shipped table (22 ML bins, 17 MAP bins):
//! the Sigmoid and Softmax layers mlmap replaces, ML, MAP (libm), MAP (`FastMath`, the
//! crate's own `exp`) and MAP (`Micromath`, feature `micromath`), per detection and per
//! batch of 4096 detections, and decoding the table; and the quantized table (`QTable`)
//! on int8 codes of the same rows (`round(x / 0.08)`): ML, MAP and Bayes.
//!
//! ```text
//! cargo bench --bench layer --features micromath
//! python3 tools/bench_ratios.py          # criterion's medians as ratios to Sigmoid
//! ```
//!
//! After criterion's benchmarks, the run prints the ratios to the Sigmoid layer once
//! more, measured interleaved: every round times each layer once on the 4096
//! detections, and each layer keeps its fastest round. On a shared machine whose load
//! drifts during the minutes criterion takes, these are the figures to quote; the
//! medians of criterion's benchmarks, taken one after the other, can disagree by tens
//! of percent from one run to the next.
//!
//! The detections are the rows of `examples/data/test.csv` (realistic logits: most in
//! the support of their class, some far outside, mixed classes), in file order; the
//! per-detection benchmarks cycle through the first 4096 so that every iteration sees a
//! different row, as a detector's output stream would.
// `criterion_group!` generates a public function that cannot carry a doc comment.
#![allow(missing_docs)]

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{criterion_group, Criterion, Throughput};
use mlmap::baseline::{sigmoid, softmax};
use mlmap::{quantize_into, Libm, QParams, QTable, Table};

type Shipped = Table<3, 22, 17, 22, 4>;

const TABLE: &[u8] = include_bytes!("../tables/default.mlmap");
const TEST_CSV: &str = include_str!("../examples/data/test.csv");
const BATCH: usize = 4096;

/// The scale of the int8 codes of the quantized layers.
const SCALE: f32 = 0.08;

/// The shipped table's int8 quantized section (ML, MAP and Bayes heads).
fn section(table: &Shipped) -> Vec<u8> {
    let params = QParams {
        bits: 8,
        scales: &[SCALE; 3],
        zero_points: &[0; 3],
        bayes: true,
    };
    let mut buf = vec![0u8; 8192];
    let n = quantize_into(&table.view(), &params, &mut buf)
        .expect("the section fits")
        .len();
    buf.truncate(n);
    buf
}

/// The logits as int8 codes.
fn codes(xs: &[[f32; 3]]) -> Vec<[i8; 3]> {
    xs.iter()
        .map(|x| x.map(|v| (v / SCALE).round().clamp(-128.0, 127.0) as i8))
        .collect()
}

/// The logits (in the table's class order) and objectness of the test rows.
fn detections(table: &Shipped) -> (Vec<[f32; 3]>, Vec<f32>) {
    let mut lines = TEST_CSV.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect("column");
    let logit_cols: [usize; 3] = core::array::from_fn(|i| col(table.class_name(i).expect("class")));
    let os_col = col("objectness");
    let (mut xs, mut os) = (Vec::new(), Vec::new());
    for line in lines.take(BATCH) {
        let f: Vec<&str> = line.split(',').collect();
        let num = |c: usize| f[c].parse::<f32>().expect("number");
        xs.push(logit_cols.map(num));
        os.push(num(os_col));
    }
    assert_eq!(
        xs.len(),
        BATCH,
        "examples/data/test.csv has fewer rows than a batch"
    );
    (xs, os)
}

fn layers(c: &mut Criterion) {
    let table = Shipped::from_bytes(TABLE).expect("the shipped table decodes");
    let (xs, os) = detections(&table);

    // One detection per iteration, cycling through the test rows.
    let mut g = c.benchmark_group("detection");
    g.throughput(Throughput::Elements(1));
    macro_rules! per_detection {
        ($name:literal, |$x:ident, $o:ident| $call:expr) => {
            let mut i = 0usize;
            g.bench_function($name, |b| {
                b.iter(|| {
                    let r = i % BATCH;
                    i = i.wrapping_add(1);
                    let ($x, $o) = (black_box(&xs[r]), black_box(os[r]));
                    black_box($call)
                })
            });
        };
    }
    per_detection!("sigmoid", |x, o| sigmoid::<Libm, 3>(x, o));
    per_detection!("softmax", |x, o| softmax::<Libm, 3>(x, o));
    per_detection!("ml", |x, o| table.ml(x, o));
    per_detection!("map", |x, o| table.map(x, o));
    per_detection!("map_fast", |x, o| table.map_with::<mlmap::FastMath>(x, o));
    #[cfg(feature = "micromath")]
    per_detection!("map_micromath", |x, o| table
        .map_with::<mlmap::Micromath>(x, o));
    let bytes = section(&table);
    let q = QTable::<3, i8>::from_bytes(&bytes).expect("the section reads back");
    let qs = codes(&xs);
    macro_rules! per_code {
        ($name:literal, |$c:ident, $o:ident| $call:expr) => {
            let mut i = 0usize;
            g.bench_function($name, |b| {
                b.iter(|| {
                    let r = i % BATCH;
                    i = i.wrapping_add(1);
                    let ($c, $o) = (black_box(&qs[r]), black_box(os[r]));
                    black_box($call)
                })
            });
        };
    }
    per_code!("q8_ml", |c, o| q.ml(c, o));
    per_code!("q8_map", |c, o| q.map(c, o));
    per_code!("q8_bayes", |c, o| q.bayes(c, o));
    g.finish();

    // A batch of 4096 detections per iteration. The baselines have no batch API: they
    // run in a plain loop, as firmware would write it.
    let mut g = c.benchmark_group("batch4096");
    g.throughput(Throughput::Elements(BATCH as u64));
    let mut out = vec![[0.0f32; 3]; BATCH];
    macro_rules! baseline_batch {
        ($name:literal, $f:path) => {
            g.bench_function($name, |b| {
                b.iter(|| {
                    for ((x, &o), s) in black_box(&xs).iter().zip(&os).zip(out.iter_mut()) {
                        *s = $f(x, o).map(|s| s.0).unwrap_or([f32::NAN; 3]);
                    }
                    black_box(&mut out);
                })
            });
        };
    }
    baseline_batch!("sigmoid", sigmoid::<Libm, 3>);
    baseline_batch!("softmax", softmax::<Libm, 3>);
    g.bench_function("ml", |b| {
        b.iter(|| black_box(table.ml_batch(black_box(&xs), Some(&os), &mut out)))
    });
    g.bench_function("map", |b| {
        b.iter(|| black_box(table.map_batch(black_box(&xs), Some(&os), &mut out)))
    });
    g.bench_function("map_fast", |b| {
        b.iter(|| {
            black_box(table.map_batch_with::<mlmap::FastMath>(black_box(&xs), Some(&os), &mut out))
        })
    });
    #[cfg(feature = "micromath")]
    g.bench_function("map_micromath", |b| {
        b.iter(|| {
            black_box(table.map_batch_with::<mlmap::Micromath>(black_box(&xs), Some(&os), &mut out))
        })
    });
    g.finish();

    // Decoding: magic, CRC-32, postcard, every invariant, the derived constants.
    let mut g = c.benchmark_group("decode");
    g.throughput(Throughput::Bytes(TABLE.len() as u64));
    g.bench_function("from_bytes", |b| {
        b.iter(|| black_box(Shipped::from_bytes(black_box(TABLE))))
    });
    g.finish();
}

/// What the interleaved layers run on: the table, its quantized section and the codes.
struct Ctx<'a> {
    table: Shipped,
    q: QTable<'a, 3, i8>,
    codes: Vec<[i8; 3]>,
}

/// One layer over all `xs`, through the batch API where the layer has one.
type Run = fn(&Ctx<'_>, &[[f32; 3]], &[f32], &mut [[f32; 3]]);

/// The quantized layers' batch: a plain loop over the codes.
fn loop_codes(
    codes: &[[i8; 3]],
    os: &[f32],
    out: &mut [[f32; 3]],
    f: impl Fn(&[i8; 3], f32) -> Result<mlmap::Scores<3>, mlmap::InferError>,
) {
    for ((c, &o), s) in codes.iter().zip(os).zip(out.iter_mut()) {
        *s = f(c, o).map(|s| s.0).unwrap_or([f32::NAN; 3]);
    }
}

/// The baselines' batch: a plain loop.
fn loop_over(
    xs: &[[f32; 3]],
    os: &[f32],
    out: &mut [[f32; 3]],
    f: impl Fn(&[f32; 3], f32) -> Result<mlmap::Scores<3>, mlmap::InferError>,
) {
    for ((x, &o), s) in xs.iter().zip(os).zip(out.iter_mut()) {
        *s = f(x, o).map(|s| s.0).unwrap_or([f32::NAN; 3]);
    }
}

const INTERLEAVED: &[(&str, Option<f64>, Run)] = &[
    ("sigmoid", None, |_, xs, os, out| {
        loop_over(xs, os, out, sigmoid::<Libm, 3>)
    }),
    ("softmax", None, |_, xs, os, out| {
        loop_over(xs, os, out, softmax::<Libm, 3>)
    }),
    ("ml", Some(0.5), |t, xs, os, out| {
        black_box(t.table.ml_batch(xs, Some(os), out)).ok();
    }),
    ("map", Some(1.25), |t, xs, os, out| {
        black_box(t.table.map_batch(xs, Some(os), out)).ok();
    }),
    ("map_fast", Some(0.75), |t, xs, os, out| {
        black_box(t.table.map_batch_with::<mlmap::FastMath>(xs, Some(os), out)).ok();
    }),
    #[cfg(feature = "micromath")]
    ("map_micromath", None, |t, xs, os, out| {
        black_box(
            t.table
                .map_batch_with::<mlmap::Micromath>(xs, Some(os), out),
        )
        .ok();
    }),
    ("q8_ml", Some(0.3), |t, _, os, out| {
        loop_codes(black_box(&t.codes), os, out, |c, o| t.q.ml(c, o))
    }),
    ("q8_map", Some(0.35), |t, _, os, out| {
        loop_codes(black_box(&t.codes), os, out, |c, o| t.q.map(c, o))
    }),
    ("q8_bayes", None, |t, _, os, out| {
        loop_codes(black_box(&t.codes), os, out, |c, o| t.q.bayes(c, o))
    }),
];

/// Ratios to the Sigmoid layer, every layer timed in turn, each keeping its best round.
fn interleaved_ratios(rounds: usize) {
    let table = Shipped::from_bytes(TABLE).expect("the shipped table decodes");
    let (xs, os) = detections(&table);
    let bytes = section(&table);
    let ctx = Ctx {
        q: QTable::from_bytes(&bytes).expect("the section reads back"),
        codes: codes(&xs),
        table,
    };
    let mut out = vec![[0.0f32; 3]; BATCH];
    let mut best = vec![f64::INFINITY; INTERLEAVED.len()];
    for _ in 0..rounds {
        for ((_, _, run), best) in INTERLEAVED.iter().zip(best.iter_mut()) {
            let start = Instant::now();
            run(&ctx, black_box(&xs), black_box(&os), black_box(&mut out));
            let ns = start.elapsed().as_secs_f64() * 1e9 / BATCH as f64;
            *best = best.min(ns);
        }
    }
    println!("\nInterleaved, batches of {BATCH} detections, best of {rounds} rounds:");
    println!(
        "  {:14} {:>13} {:>10}  goal",
        "layer", "ns/detection", "/ sigmoid"
    );
    for ((name, goal, _), &ns) in INTERLEAVED.iter().zip(&best) {
        let ratio = ns / best[0];
        let goal = match goal {
            Some(g) if ratio <= *g => format!("<= {g}: met"),
            Some(g) => format!("<= {g}: MISSED"),
            None => String::new(),
        };
        println!("  {name:14} {ns:13.2} {ratio:10.3}  {goal}");
    }
}

criterion_group! {
    name = benches;
    // The machine is shared and noisy: longer measurements, ratios over absolute times.
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(2))
        .measurement_time(Duration::from_secs(6))
        .noise_threshold(0.05);
    targets = layers
}

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    // `cargo bench` passes `--bench`; `cargo test --benches` does not (it only checks
    // that every benchmark runs once), and `--list` only lists them.
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|a| a == "--bench") && !args.iter().any(|a| a == "--list") {
        interleaved_ratios(2000);
    }
}
