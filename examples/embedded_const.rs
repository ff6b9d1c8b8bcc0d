//! Embedding way 2: `build.rs` turned the table named by `MLMAP_TABLE` (default
//! `tables/default.mlmap`) into Rust constants; the firmware scores with no decoding.
//!
//! ```text
//! cargo run --example embedded_const
//! MLMAP_TABLE=/path/to/other.mlmap cargo run --example embedded_const
//! ```

use mlmap::embedded::{self, TABLE};

fn main() {
    println!(
        "embedded table from {}: K = {}, {} ML bins, {} MAP bins, lambdas {} / {}",
        embedded::SOURCE,
        embedded::K,
        embedded::BINS_ML,
        embedded::BINS_MAP,
        TABLE.settings().lambda_ml,
        TABLE.settings().lambda_map,
    );
    let logits = [[4.1f32, -2.3, -1.7], [0.4, 2.9, 1.1], [-1.0, -0.5, 3.3]];
    let objectness = [0.93f32, 0.71, 0.88];
    let mut out = [[0.0f32; 3]; 3];
    match TABLE.map_batch(&logits, Some(&objectness), &mut out) {
        Ok(()) => {
            for (x, s) in logits.iter().zip(&out) {
                let best = mlmap::argmax(s);
                println!(
                    "{x:>5.1?} -> MAP {s:.3?} -> {}",
                    TABLE.class_name(best).unwrap_or("?")
                );
            }
        }
        Err(e) => eprintln!("{e}"),
    }
}
