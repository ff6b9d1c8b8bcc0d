//! The Rust call on the run-time shaped table the C API holds (`BoundedTable` of the
//! default maximum shape, scored through its `TableView`), for counting instructions
//! against the C API: `tools/callgrind_ffi.sh` runs it for N and 2N detections.
//!
//! ```text
//! cargo run -p mlmap-ffi --profile release-abort --features std --example bounded_count -- map 16384
//! ```
//!
//! Each head uses the backend the C API uses: `Libm` for MAP, and for the Bayes and open
//! heads the device default of `TableView::score_into` (`FastMath`).

use std::hint::black_box;
use std::process::ExitCode;

use mlmap::{BoundedTable, Head, InferError, Libm};

type Bounded = BoundedTable<16, 64, 64, 64, 17>;

const TABLE: &[u8] = include_bytes!("../../tables/default.mlmap");
const TEST_CSV: &str = include_str!("../../examples/data/test.csv");
const ROWS: usize = 4096;

type View<'a> = mlmap::TableView<'a, mlmap::Bounded<64>, mlmap::Bounded<64>>;
type Layer = fn(&View<'_>, &[f32; 3], f32, &mut [f32; 3]) -> Result<(), InferError>;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(kind), Some(Ok(n))) = (args.first(), args.get(1).map(|n| n.parse::<usize>())) else {
        eprintln!("usage: bounded_count noop|ml|map|bayes|open N");
        return ExitCode::from(2);
    };
    let table = Box::new(Bounded::from_bytes(TABLE).expect("the shipped table decodes"));
    let view = table.view().expect("decoded");
    // id,label,objectness,car,cyclist,pedestrian: the table's class order.
    let rows: Vec<([f32; 3], f32)> = TEST_CSV
        .lines()
        .skip(1)
        .take(ROWS)
        .map(|l| {
            let f: Vec<f32> = l
                .split(',')
                .skip(2)
                .map(|v| v.parse().expect("number"))
                .collect();
            ([f[1], f[2], f[3]], f[0])
        })
        .collect();
    let layer: Layer = match kind.as_str() {
        "noop" => |_, x, _, o| {
            *o = *x;
            Ok(())
        },
        "ml" => |v, x, os, o| v.ml_into(x, os, o, &mut [0.0; 3]),
        "map" => |v, x, os, o| v.map_into::<Libm>(x, os, o, &mut [0.0; 3]),
        "bayes" => |v, x, os, o| v.score_into(Head::Bayes, x, os, o, &mut [0.0; 4]),
        "open" => |v, x, os, o| v.score_into(Head::Open, x, os, o, &mut [0.0; 4]),
        other => {
            eprintln!("unknown kind {other:?}");
            return ExitCode::from(2);
        }
    };
    let mut checksum = 0.0f64;
    let mut out = [0.0f32; 3];
    for i in 0..n {
        let (x, os) = &rows[i % ROWS];
        if layer(black_box(&view), black_box(x), black_box(*os), &mut out).is_ok() {
            checksum += f64::from(black_box(out)[0]);
        }
    }
    println!("{kind} x {n}: checksum {checksum}");
    ExitCode::SUCCESS
}
