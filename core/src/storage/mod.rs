//! Where a decoded table lives, and the one view every storage is scored through.
//!
//! `table` is the fixed-size [`Table`](crate::Table) (const generics), `bounded` the
//! caller's storage of a bounded shape, `lent` storage lent slice by slice at exactly a
//! table's shape (the C API's arena), `dyn_table` the run-time shape (feature `alloc`).
//! Each decodes through the one decoder and scores through [`TableView`](crate::TableView)
//! (`view`).

pub mod bounded;
#[cfg(feature = "alloc")]
pub mod dyn_table;
pub mod lent;
pub mod table;
pub mod view;
