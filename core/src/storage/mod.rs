//! Where a decoded table lives, and the one view every storage is scored through.
//!
//! `inner` is the one table type, [`TableInner<S>`](crate::TableInner), generic over its
//! [`Storage`](crate::Storage): one decoder, one view, one set of accessors. The
//! storages are `table` (fixed-size arrays: [`Table`](crate::Table)), `bounded` (arrays
//! of a maximum shape, a prefix in use: [`BoundedTable`](crate::BoundedTable)), `lent`
//! (slices lent at exactly a table's shape, the C API's arena) and `dyn_table` (vectors,
//! feature `alloc`); each only adds its constructors. Every table scores through
//! [`TableView`](crate::TableView) (`view`).

pub mod bounded;
#[cfg(feature = "alloc")]
pub mod dyn_table;
pub mod inner;
pub mod lent;
pub mod table;
pub mod view;
