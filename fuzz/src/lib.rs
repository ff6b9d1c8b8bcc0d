//! Shared pieces of the mlmap fuzz targets: structured inputs built with `arbitrary`,
//! and checks of every table and score they meet.
//!
//! The invariants of DESIGN §1.3 are checked by `mlmap::invariants`, the checkers the
//! property tests use too; this crate adds what only the fuzz targets check (numpy's bin
//! rule at every edge, the scores against the formula, the batch API and `DynTable`
//! agreeing bit for bit), for the ML and MAP heads and, on tables that have them, the Bayes
//! head (DESIGN §1.6; arbitrary heads from [`ArbBayes`]) and the open head (DESIGN §1.8;
//! arbitrary temperatures and epsilons from [`ArbOpen`]). Every check panics (which
//! libFuzzer reports as a crash) when it does not hold, with a message naming the
//! invariant.

use std::fmt::Display;

use arbitrary::{Arbitrary, Unstructured};
use mlmap::host::BayesSpec;
use mlmap::host::DynTable;
use mlmap::invariants::{
    self, Sum, Violation, SUBNORMAL_STEP as TINY, SUM_RELATIVE_TOLERANCE as SUM_TOLERANCE,
};
use mlmap::{
    fast_math_max_score_error, Backend, BatchError, ClassSpec, EdgeMode, FastMath, Gaussian, Head,
    Histogram, InferError, Libm, Scores, Settings, Table, TableError, UpperTail,
    FAST_MATH_MAX_SCORE_ERROR, MAX_EPSILON, MAX_TEMPERATURE, MIN_TEMPERATURE,
};

/// The table shipped with the crate: K = 3, 22 ML bins, 17 MAP bins.
pub const SHIPPED: &[u8] = include_bytes!("../../tables/default.mlmap");

/// The shape of [`SHIPPED`].
pub type Shipped = Table<3, 22, 17, 22, 4>;

/// CRC-32/ISO-HDLC, the checksum of the table format.
pub const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// `bytes` with its last four bytes replaced by the CRC-32 of the bytes before them, so
/// that mutated bodies get past the checksum and reach the parser and the validation.
pub fn with_valid_crc(bytes: &[u8]) -> Option<Vec<u8>> {
    let body = bytes.get(..bytes.len().checked_sub(4)?)?;
    let mut v = body.to_vec();
    v.extend_from_slice(&CRC.checksum(body).to_le_bytes());
    Some(v)
}

/// `bytes` with a section trailer's length (its last eight bytes: length, then CRC-32)
/// set to the whole input and its CRC recomputed, so that mutated sections reach the
/// section's parser.
pub fn with_valid_trailer(bytes: &[u8]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    let n = b.len();
    if n < 8 {
        return b;
    }
    let len = u32::try_from(n).unwrap_or(u32::MAX).to_le_bytes();
    b[n - 8..n - 4].copy_from_slice(&len);
    let crc = CRC.checksum(&b[..n - 4]);
    b[n - 4..].copy_from_slice(&crc.to_le_bytes());
    b
}

/// Panics with `context` and the violation's message when an invariant does not hold.
pub fn must(result: Result<(), Violation>, context: impl Display) {
    if let Err(v) = result {
        panic!("{context}: {v}");
    }
}

mod bayes;
mod fronts;
mod inference;
mod maps;
mod open;
mod structured;
mod tables;

pub use bayes::*;
use fronts::check_fronts;
pub use inference::*;
pub use maps::*;
pub use open::*;
pub use structured::*;
pub use tables::*;
