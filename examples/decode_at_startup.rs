//! Embedding way 1: the table's bytes live in a calibration flash sector that can be
//! rewritten without reflashing the code; the firmware decodes them once at start-up.
//!
//! On the host this reads the file named on the command line (default: the shipped
//! table) to stand in for the flash sector:
//!
//! ```text
//! cargo run --example decode_at_startup -- tables/default.mlmap
//! ```

use mlmap::{DecodeError, Table};

/// The shape this firmware was built for: 3 classes, 22 ML bins, 17 MAP bins.
type Calibration = Table<3, 22, 17, 22, 4>;

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "tables/default.mlmap".into());
    let sector = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(2);
        }
    };
    // CRC, shape and every invariant are checked here; a bad sector is refused and the
    // firmware can fall back (e.g. to the table embedded at build time).
    let table = match Calibration::from_bytes(&sector) {
        Ok(t) => t,
        Err(e @ DecodeError::ShapeMismatch { .. }) => {
            eprintln!("{path}: {e}: rebuild the firmware for this table's shape");
            std::process::exit(2);
        }
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(2);
        }
    };
    let detections: [([f32; 3], f32); 4] = [
        ([4.1, -2.3, -1.7], 0.93), // a confident car
        ([1.2, 0.3, -0.4], 0.55),  // a weak background hit
        ([11.5, -9.0, -8.7], 0.9), // a car logit far above anything seen in training
        ([-9.0, -9.5, -8.8], 0.8), // nothing like any class
    ];
    for (logits, os) in detections {
        match (table.ml(&logits, os), table.map(&logits, os)) {
            (Ok(ml), Ok(map)) => println!(
                "logits {logits:>5.1?} OS {os:.2}: ML {:.3?} -> {}, MAP {:.3?} -> {}",
                ml.0,
                table.class_name(ml.argmax()).unwrap_or("?"),
                map.0,
                table.class_name(map.argmax()).unwrap_or("?"),
            ),
            (Err(e), _) | (_, Err(e)) => println!("logits {logits:?}: {e}"),
        }
    }
}
