//! The arithmetic of every head, on slices, shared by every storage.
//!
//! `layer` holds the ML and MAP heads, the normalisation they share and the decisions
//! ([`argmax`](crate::argmax), [`decide`](crate::decide)); `bayes` the Bayes head and its
//! objectness feature; `open` the open head; `recal` the recalibration maps of every
//! head (DESIGN §1.9). The numerical building blocks they use are in `crate::math`.

pub mod bayes;
pub mod layer;
pub mod open;
pub mod recal;
