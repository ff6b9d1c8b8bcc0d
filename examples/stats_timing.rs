//! Times the two passes of a sharded fit in memory: `ClassMoments::push` (one value),
//! `FitStats::push` (pass (a)) and
//! `FitCounts::push` (pass (b)) over synthetic rows, the same passes over the rows held
//! as arrays (`push_rows` of `f32` logits and `i64` labels, in blocks of 16384 rows, as
//! the Python package calls them), and a merge of two halves, and prints nanoseconds
//! per row and per value on one `key=value` line:
//!
//! ```text
//! cargo run --release --features std --example stats_timing -- [ROWS] [CLASSES]
//! ```
//!
//! The rows are made here (a fixed pseudo-random sequence), so nothing is read from disk.

use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

use mlmap::host::dataset::{Label, Row};
use mlmap::host::fit::{finish, ClassMoments, FitCounts, FitParams, FitStats};

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let rows: usize = args
        .next()
        .and_then(|a| a.parse().ok())
        .unwrap_or(2_000_000);
    let k: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(3);
    if k < 2 || rows == 0 {
        eprintln!("usage: stats_timing [ROWS >= 1] [CLASSES >= 2]");
        return ExitCode::from(2);
    }
    // A xorshift sequence: logits in about [-8, 8], labels cycling over the classes and
    // background.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 16.0 - 8.0
    };
    let logits: Vec<f64> = (0..rows * k).map(|_| next()).collect();
    let label = |i: usize| match i % (k + 1) {
        c if c < k => Label::Class(c),
        _ => Label::Background,
    };
    let row = |i: usize| Row {
        index: i as u64,
        line: None,
        id: None,
        label: label(i),
        objectness: 1.0,
        logits: &logits[i * k..(i + 1) * k],
    };
    let classes: Vec<String> = (0..k).map(|c| format!("class{c}")).collect();
    let params = FitParams::default();

    // One class's exact moments over every logit: the cost of one value (the best of 5
    // runs, as the machine may be busy).
    let mut push_s = f64::INFINITY;
    for _ in 0..5 {
        let t = Instant::now();
        let mut moments = ClassMoments::new("all");
        for &x in black_box(&logits) {
            moments.push(x);
        }
        push_s = push_s.min(t.elapsed().as_secs_f64());
        black_box(&moments);
    }
    // The plain f64 sum and sum of squares, for scale.
    let mut plain_s = f64::INFINITY;
    for _ in 0..5 {
        let t = Instant::now();
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for &x in black_box(&logits) {
            s1 += x;
            s2 += x * x;
        }
        plain_s = plain_s.min(t.elapsed().as_secs_f64());
        black_box((s1, s2));
    }

    let t = Instant::now();
    let mut stats = FitStats::new(&classes);
    for i in 0..rows {
        stats.push(&row(i));
    }
    let pass_a = t.elapsed().as_secs_f64();

    let Ok(edges) = stats.edges(&params) else {
        eprintln!("the synthetic rows cannot be fitted");
        return ExitCode::from(1);
    };
    let t = Instant::now();
    let mut counts = FitCounts::new(&edges);
    let mut inside = true;
    for i in 0..rows {
        inside &= counts.push(&row(i));
    }
    let pass_b = t.elapsed().as_secs_f64();

    // The same rows as arrays: f32 logits, i64 labels (-1 background), pushed in
    // blocks; the best of 5 runs of each pass.
    let narrow: Vec<f32> = logits.iter().map(|&v| v as f32).collect();
    let labels: Vec<i64> = (0..rows)
        .map(|i| match label(i) {
            Label::Class(c) => c as i64,
            _ => -1,
        })
        .collect();
    const BLOCK: usize = 16_384;
    let (mut block_a, mut block_b) = (f64::INFINITY, f64::INFINITY);
    let mut block_stats = FitStats::new(&classes);
    let mut block_ok = true;
    for _ in 0..5 {
        let t = Instant::now();
        let mut s = FitStats::new(&classes);
        for (x, l) in narrow.chunks(BLOCK * k).zip(labels.chunks(BLOCK)) {
            block_ok &= s.push_rows(black_box(x), l).is_ok();
        }
        block_a = block_a.min(t.elapsed().as_secs_f64());
        block_stats = s;
    }
    let Ok(block_edges) = block_stats.edges(&params) else {
        eprintln!("the synthetic rows cannot be fitted");
        return ExitCode::from(1);
    };
    for _ in 0..5 {
        let t = Instant::now();
        let mut c = FitCounts::new(&block_edges);
        for (x, l) in narrow.chunks(BLOCK * k).zip(labels.chunks(BLOCK)) {
            block_ok &= c.push_rows(black_box(x), l) == Ok(None);
        }
        block_b = block_b.min(t.elapsed().as_secs_f64());
        black_box(&c);
    }
    // The f64 path of the same values gives the same statistics.
    let widened: Vec<f64> = narrow.iter().map(|&v| f64::from(v)).collect();
    let mut wide_stats = FitStats::new(&classes);
    block_ok &= wide_stats.push_rows(&widened, &labels).is_ok() && wide_stats == block_stats;

    let mut half = FitStats::new(&classes);
    for i in 0..rows / 2 {
        half.push(&row(i));
    }
    let mut rest = FitStats::new(&classes);
    for i in rows / 2..rows {
        rest.push(&row(i));
    }
    let m = Instant::now();
    let merged = half.merge(&rest).is_ok();
    let merge_s = m.elapsed().as_secs_f64();
    let t = Instant::now();
    let table = finish(&stats, &counts);
    let finish_s = t.elapsed().as_secs_f64();
    black_box(&table);
    if !(inside && merged && half == stats && table.is_ok() && block_ok) {
        eprintln!("the passes disagree");
        return ExitCode::from(1);
    }
    let ns = |s: f64, n: usize| s * 1e9 / n as f64;
    println!(
        "rows={rows} classes={k} moments_push_ns_per_value={:.2} plain_f64_sums_ns_per_value={:.2} \
         pass_a_ns_per_row={:.1} pass_b_ns_per_row={:.1} block_f32_pass_a_ns_per_row={:.1} \
         block_f32_pass_b_ns_per_row={:.1} merge_us={:.1} finish_us={:.1}",
        ns(push_s, rows * k),
        ns(plain_s, rows * k),
        ns(pass_a, rows),
        ns(pass_b, rows),
        ns(block_a, rows),
        ns(block_b, rows),
        merge_s * 1e6,
        finish_s * 1e6,
    );
    ExitCode::SUCCESS
}
