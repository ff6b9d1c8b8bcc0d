//! The table embedded at build time (DESIGN §5, way 2).
//!
//! `build.rs` reads the table file named by the `MLMAP_TABLE` environment variable
//! (default: `tables/default.mlmap`, fitted from `examples/data/train.csv`), validates it
//! with the same code as [`Table::from_bytes`](crate::Table::from_bytes), and writes it
//! out as Rust constants: the firmware gets a ready [`TABLE`] in flash and pays no
//! decoding at start-up. An invalid file fails the build, naming the file and the
//! broken invariant.
//!
//! ```
//! use mlmap::embedded::{TABLE, K};
//!
//! let logits = [4.0_f32; K];
//! let scores = TABLE.ml(&logits, 0.9)?;
//! assert!((scores.0.iter().sum::<f32>() - 0.9).abs() < 1e-5);
//! # Ok::<(), mlmap::InferError>(())
//! ```

include!(concat!(env!("OUT_DIR"), "/embedded_table.rs"));

/// The quantized section embedded at build time (docs/FORMAT.md, "The quantized
/// section"): `build.rs` reads the file named by `MLMAP_QUANTIZED` (default:
/// `tables/default_q8.mlmap`, the shipped table quantized to int8 codes with scale 0.08
/// and zero point 0, written by `mlmap quantize`), validates its section with the code of
/// [`QTable::from_bytes`](crate::QTable::from_bytes), and writes the section's bytes and
/// a ready [`QTable`](crate::QTable) over them: no decoding at start-up, every head of
/// the section ready to score, the open head's parameters included when it has them
/// ([`QTable::open`](crate::QTable::open)). An invalid or missing section fails the
/// build, naming the file.
///
/// ```
/// use mlmap::embedded::quantized::{QUANTIZED, QUANTIZED_K};
///
/// let scores = QUANTIZED.map(&[50; QUANTIZED_K], 0.9)?;
/// assert!((scores.0.iter().sum::<f32>() - 0.9).abs() < 1e-5);
/// # Ok::<(), mlmap::InferError>(())
/// ```
pub mod quantized {
    include!(concat!(env!("OUT_DIR"), "/embedded_quantized.rs"));
}
