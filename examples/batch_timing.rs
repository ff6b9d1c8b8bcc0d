//! Times the batch API over a whole NPY directory, in-process: the Rust side of
//! `tools/bench_vs_numpy.sh`.
//!
//! Loads `logits.npy` and `objectness.npy` (not timed), decodes the table as
//! `Table<3, 22, 17, 22, 4>`, then runs [`Table::ml_batch`] and [`Table::map_batch`] over every
//! row, several times, and prints the medians on one `key=value` line (with the feature
//! `micromath`, also `map_fast_s`: [`Table::map_batch_with`] and the `FastMath` backend):
//!
//! ```text
//! cargo run --release --features std,micromath --example batch_timing -- DIR [--table T] [--reps N] [--dump FILE]
//! ```
//!
//! `--dump FILE` writes the scores of the last repetition (the ML scores, then the MAP
//! scores, row-major float32 little-endian) for `tools/numpy_layer.py check`.

use std::hint::black_box;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use mlmap::host::dataset::DataSource;
use mlmap::Table;

/// The shape of the shipped table: 3 classes, 22 ML bins, 17 MAP bins.
type Calibration = Table<3, 22, 17, 22, 4>;
const K: usize = 3;

struct Args {
    dir: PathBuf,
    table: PathBuf,
    reps: usize,
    dump: Option<PathBuf>,
}

fn parse_args() -> Result<Args, String> {
    let mut args = std::env::args_os().skip(1);
    let mut a = Args {
        dir: PathBuf::new(),
        table: PathBuf::from("tables/default.mlmap"),
        reps: 7,
        dump: None,
    };
    let mut dir = None;
    while let Some(arg) = args.next() {
        let mut value = |name: &str| {
            args.next()
                .ok_or_else(|| format!("{name} needs a value"))
                .map(PathBuf::from)
        };
        match arg.to_str() {
            Some("--table") => a.table = value("--table")?,
            Some("--dump") => a.dump = Some(value("--dump")?),
            Some("--reps") => {
                let v = value("--reps")?;
                a.reps = v
                    .to_str()
                    .and_then(|s| s.parse().ok())
                    .filter(|&n: &usize| n >= 1)
                    .ok_or("--reps needs a positive integer")?;
            }
            _ if dir.is_none() => dir = Some(PathBuf::from(arg)),
            _ => return Err(format!("unexpected argument {}", arg.to_string_lossy())),
        }
    }
    a.dir = dir.ok_or("usage: batch_timing DIR [--table T] [--reps N] [--dump FILE]")?;
    Ok(a)
}

fn median(v: &mut [Duration]) -> Duration {
    v.sort_unstable();
    v[v.len() / 2]
}

fn run(a: &Args) -> Result<(), String> {
    let bytes = std::fs::read(&a.table).map_err(|e| format!("{}: {e}", a.table.display()))?;
    let table =
        Calibration::from_bytes(&bytes).map_err(|e| format!("{}: {e}", a.table.display()))?;
    let src = DataSource::open(&a.dir).map_err(|e| e.to_string())?;
    let mut logits: Vec<[f32; K]> = Vec::new();
    let mut objectness: Vec<f32> = Vec::new();
    src.for_each_row(|row| -> Result<(), mlmap::host::dataset::DataError> {
        let mut x = [0.0f32; K];
        for (d, &s) in x.iter_mut().zip(row.logits) {
            *d = s as f32;
        }
        logits.push(x);
        objectness.push(row.objectness as f32);
        Ok(())
    })
    .map_err(|e| e.to_string())?;
    if src.classes().len() != K || logits.is_empty() {
        return Err(format!("{}: need rows of {K} logits", a.dir.display()));
    }
    let n = logits.len();
    let mut ml = vec![[0.0f32; K]; n];
    let mut map = vec![[0.0f32; K]; n];
    let (mut t_ml, mut t_map, mut t_total) = (Vec::new(), Vec::new(), Vec::new());
    #[cfg(feature = "micromath")]
    let mut t_fast = Vec::new();
    for _ in 0..a.reps {
        let t0 = Instant::now();
        table
            .ml_batch(black_box(&logits), Some(black_box(&objectness)), &mut ml)
            .map_err(|e| e.to_string())?;
        black_box(&mut ml);
        let t1 = Instant::now();
        table
            .map_batch(black_box(&logits), Some(black_box(&objectness)), &mut map)
            .map_err(|e| e.to_string())?;
        black_box(&mut map);
        let t2 = Instant::now();
        t_ml.push(t1 - t0);
        t_map.push(t2 - t1);
        t_total.push(t2 - t0);
        #[cfg(feature = "micromath")]
        {
            let mut fast = vec![[0.0f32; K]; n];
            let t3 = Instant::now();
            table
                .map_batch_with::<mlmap::FastMath>(
                    black_box(&logits),
                    Some(black_box(&objectness)),
                    &mut fast,
                )
                .map_err(|e| e.to_string())?;
            black_box(&mut fast);
            t_fast.push(t3.elapsed());
        }
    }
    let (m_ml, m_map, m_total) = (median(&mut t_ml), median(&mut t_map), median(&mut t_total));
    print!(
        "mlmap_batch rows={n} reps={} ml_s={:.6} map_s={:.6} total_s={:.6} ns_per_detection={:.2}",
        a.reps,
        m_ml.as_secs_f64(),
        m_map.as_secs_f64(),
        m_total.as_secs_f64(),
        m_total.as_secs_f64() / n as f64 * 1e9
    );
    // MAP with the fast-math backend (feature `micromath`), reported on its own.
    #[cfg(feature = "micromath")]
    print!(" map_fast_s={:.6}", median(&mut t_fast).as_secs_f64());
    println!();
    if let Some(path) = &a.dump {
        let mut out = Vec::with_capacity(2 * n * K * 4);
        for v in ml.iter().chain(&map).flatten() {
            out.extend_from_slice(&v.to_le_bytes());
        }
        std::fs::write(path, out).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

fn main() -> ExitCode {
    match parse_args().and_then(|a| run(&a)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("batch_timing: {e}");
            ExitCode::from(2)
        }
    }
}
