//! A structured table, built from arbitrary statistics with `Table::from_parts`, either
//! is rejected or satisfies every table invariant, stores its statistics unchanged, and
//! survives `to_slice` -> `from_bytes` unchanged, with a deterministic encoding shared by
//! the host's `DynTable`.
#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use libfuzzer_sys::fuzz_target;
use mlmap_fuzz::{check_encoding, check_table, ArbTable};

#[derive(Arbitrary, Debug)]
enum Input {
    /// The shape of the shipped table.
    Shipped(ArbTable<3, 22, 17>),
    Small(ArbTable<2, 4, 3>),
    /// One bin per head: the degenerate histogram.
    OneBin(ArbTable<2, 1, 1>),
    Wide(ArbTable<5, 9, 2>),
}

fuzz_target!(|data: &[u8]| {
    // Plain `arbitrary` (not `arbitrary_take_rest`, which reads the last element of an
    // array from the bytes after it), so that hand-written seeds keep their layout.
    let Ok(input) = Input::arbitrary(&mut Unstructured::new(data)) else {
        return;
    };
    match &input {
        Input::Shipped(t) => roundtrip(t),
        Input::Small(t) => roundtrip(t),
        Input::OneBin(t) => roundtrip(t),
        Input::Wide(t) => roundtrip(t),
    }
});

fn roundtrip<const K: usize, const B_ML: usize, const B_MAP: usize>(a: &ArbTable<K, B_ML, B_MAP>) {
    // `build` asserts that the table holds exactly the statistics it was given.
    let Ok(t) = a.build() else { return };
    check_table(&t);
    let bytes = check_encoding(&t, None);
    assert!(bytes.len() <= mlmap::Table::<K, B_ML, B_MAP>::MAX_ENCODED_LEN);
    // A buffer one byte too short is an error, not a panic or a truncated table.
    let mut short = vec![0u8; bytes.len() - 1];
    assert!(
        t.to_slice(&mut short).is_err(),
        "encoded into a too-short buffer"
    );
}
