//! The `.mlmap` file (DESIGN §3, docs/FORMAT.md): exact round trips, agreement with the
//! reference encoder, and rejection of every corrupted, truncated or invalid file with
//! the matching error.

use mlmap::{
    CharKind, DecodeError, EncodeError, Head, NameError, Table, TableError, UpperTail, MAX_LAMBDA,
    MAX_LAMBDA_BAYES, NAME_MAX,
};

use crate::support::{
    fix_crc, log_term, shipped, small, small_bayes, small_bayes_nobg, small_settings, small_specs,
    with_crc, RawBayes, RawTable, Shipped, Small, SmallBayes, SmallBayesNoBg, SHIPPED_MLMAP,
    SMALL_BAYES_MLMAP, SMALL_BAYES_NOBG_MLMAP, SMALL_CLAMP_MLMAP, SMALL_MLMAP,
};

fn encode<const K: usize, const BM: usize, const BP: usize, const BB: usize, const C: usize>(
    t: &Table<K, BM, BP, BB, C>,
) -> Vec<u8> {
    let mut buf = vec![0u8; Table::<K, BM, BP, BB, C>::MAX_ENCODED_LEN];
    let len = t
        .to_slice(&mut buf)
        .expect("MAX_ENCODED_LEN suffices")
        .len();
    buf.truncate(len);
    buf
}

/// A valid table of shape `K, BM, BP` with the longest names and row counts.
fn worst_case<const K: usize, const BM: usize, const BP: usize>() -> Table<K, BM, BP> {
    let names: Vec<String> = (0..K)
        .map(|i| format!("{i:0>width$}", width = NAME_MAX))
        .collect();
    let classes = std::array::from_fn(|i| mlmap::ClassSpec {
        name: names[i].as_str(),
        rows: u64::MAX,
        mean: -1.234_567_8e-20,
        variance: 1e30,
        ml_range: (-3.0e30, 3.0e30),
        ml_freqs: [1.0 / BM as f32; BM],
        map_range: (f32::MIN_POSITIVE, 1.0),
        map_freqs: [1.0 / BP as f32; BP],
    });
    Table::from_parts(small_settings(UpperTail::Clamp), classes).expect("a valid worst case")
}

/// Format version 2, the Bayes head (DESIGN §1.6, docs/FORMAT.md): byte-exact round
/// trips, the reference encoder, shape mismatches and one error per broken invariant.
mod bayes;
/// One error per broken invariant, the name rule of old and new tables, other category
/// counts, and malformed bodies located.
mod broken;
/// Exact round trips, the reference encoder's bytes, every corruption and truncation
/// rejected, other shapes, magics and versions, and the size bounds.
mod bytes;
