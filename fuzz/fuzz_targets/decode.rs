//! Any bytes either fail to decode or give a table that satisfies every table invariant
//! of DESIGN §1.3 (5) and re-encodes to the very same bytes (DESIGN §3).
//!
//! Six fixed shapes and the run-time shaped host table are tried: the shipped table's
//! (format version 3, with its Bayes head and the open head's temperature and epsilon),
//! the small Bayes tables' with and without background (versions 2 and 3, e.g.
//! `tests/golden/layer/small_open.mlmap`), and three without a Bayes head (version 1); on
//! the input as given and on the input with its last four bytes replaced by a valid
//! CRC-32 (without that, almost every mutation would stop at the checksum). A table that
//! decodes with the open head has parameters in their ranges (DESIGN §1.8), and one
//! without it answers `NoOpenHead`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mlmap::host::DynTable;
use mlmap::{DecodeError, InferError, Table};
use mlmap_fuzz::{check_dyn_table, check_encoding, check_table, with_valid_crc};

fuzz_target!(|data: &[u8]| {
    decode_all(data);
    if let Some(fixed) = with_valid_crc(data) {
        decode_all(&fixed);
    }
});

fn decode_all(bytes: &[u8]) {
    let dynt = DynTable::from_bytes(bytes);
    if let Ok(d) = &dynt {
        check_dyn_table(d);
        assert_eq!(
            d.to_vec().expect("encodes"),
            bytes,
            "DynTable re-encodes differently"
        );
    }
    let shape = dynt.as_ref().ok().map(|d| {
        let bayes = d
            .bayes_head()
            .map_or((0, 0), |b| (b.bins(), b.categories()));
        (d.k(), d.bins_ml(), d.bins_map(), bayes.0, bayes.1)
    });
    decode_as::<3, 22, 17, 22, 4>(bytes, &dynt, shape);
    decode_as::<3, 4, 2, 4, 4>(bytes, &dynt, shape);
    decode_as::<3, 4, 2, 4, 3>(bytes, &dynt, shape);
    decode_as::<3, 22, 17, 0, 0>(bytes, &dynt, shape);
    decode_as::<2, 4, 3, 0, 0>(bytes, &dynt, shape);
    decode_as::<2, 1, 1, 0, 0>(bytes, &dynt, shape);
}

/// The shape of a table: K, ML bins, MAP bins, Bayes bins and categories (0 without
/// the Bayes head).
type Shape = (usize, usize, usize, usize, usize);

fn decode_as<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const B_BAYES: usize,
    const C: usize,
>(
    bytes: &[u8],
    dynt: &Result<DynTable, DecodeError>,
    dyn_shape: Option<Shape>,
) {
    let r = Table::<K, B_ML, B_MAP, B_BAYES, C>::from_bytes(bytes);
    // Errors are values with a message, never a panic.
    if let Err(e) = &r {
        assert!(!e.to_string().is_empty());
    }
    // Host and device accept exactly the same tables of this shape.
    let this_shape = dyn_shape == Some((K, B_ML, B_MAP, B_BAYES, C));
    assert_eq!(
        r.is_ok(),
        this_shape,
        "Table<{K},{B_ML},{B_MAP},{B_BAYES},{C}>: {:?}, DynTable: {:?}",
        r.as_ref().err(),
        dynt.as_ref().err()
    );
    if let Ok(t) = r {
        check_table(&t);
        check_encoding(&t, Some(bytes));
        // The open head's parameters are in range (also checked by `check_table`), and
        // the host reads the same ones; without them the head is refused.
        let version = bytes.get(4).copied();
        match t.open_params() {
            Some(p) => {
                assert_eq!(version, Some(3), "an open head outside version 3");
                assert!(
                    mlmap::invariants::check_open_params(p.temperature(), p.epsilon()).is_ok(),
                    "decoded open head out of range: {p:?}"
                );
                let d = dynt.as_ref().ok().and_then(DynTable::open_params);
                assert_eq!(d, Some(p), "DynTable reads another open head");
            }
            None if B_BAYES > 0 => {
                assert_ne!(version, Some(3), "a version-3 table without the open head");
                let scores = t.view().open_into::<mlmap::FastMath>(
                    &[0.0; K],
                    1.0,
                    &mut [0.0; K],
                    &mut [0.0; C],
                );
                assert_eq!(scores, Err(InferError::NoOpenHead));
            }
            None => {}
        }
        if let Ok(d) = dynt {
            assert_eq!(
                *d,
                DynTable::from_table(&t),
                "DynTable decodes other statistics"
            );
        }
    }
}
