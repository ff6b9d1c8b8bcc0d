//! The `.mlmap` table format (docs/FORMAT.md) and the Rust source written from it.
//!
//! `wire` is the header, the settings and the class specs, their encoding and (in
//! `wire/parse.rs`) the in-place decoder; `name` the class-name rule; `embed` the `const`
//! constructors of the Rust source that `build.rs` and `mlmap export-c` write, and
//! `embed_source` (feature `alloc`) the writer of that source. The sections that may
//! follow a table are in `crate::sections`.

pub mod embed;
#[cfg(feature = "alloc")]
pub mod embed_source;
pub mod name;
pub mod wire;
