//! What the crate tells its caller when something is wrong, and how its types print.
//!
//! `error` holds the error enums, each with one `message()` per variant that `Display`,
//! `defmt` and the C status strings share (the section errors keep theirs beside their
//! sections). With feature `defmt`, `defmt_impls`, `defmt_sections` and `defmt_storage`
//! give every exported type a `defmt::Format` (`tools/check_defmt.py` checks none is
//! missing).

#[cfg(feature = "defmt")]
mod defmt_impls;
#[cfg(feature = "defmt")]
mod defmt_sections;
#[cfg(feature = "defmt")]
mod defmt_storage;
pub mod error;
