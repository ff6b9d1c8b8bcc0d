//! Quantized input (docs/FORMAT.md, the `MLMQ` section): the heads scored from integer
//! logits, with the maths of `crate::heads` folded into tables of codes.
//!
//! `qtable` is the fixed-size [`QTable`](crate::QTable) (the section read in place, and
//! the quantized heads); `quantize` builds the section from a table
//! ([`quantize_into`](crate::quantize_into)); `dyn_qtable` is its run-time-shaped form
//! (feature `alloc`).

#[cfg(feature = "alloc")]
pub mod dyn_qtable;
pub mod qtable;
pub mod quantize;
