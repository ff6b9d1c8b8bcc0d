//! A structured table, built from arbitrary statistics with `Table::from_parts`, either
//! is rejected or satisfies every table invariant, stores its statistics unchanged, and
//! survives `to_slice` -> `from_bytes` unchanged, with a deterministic encoding shared by
//! the host's `DynTable`. The same for tables given an arbitrary Bayes head (format
//! version 2) and then an arbitrary open head (version 3: temperature and epsilon,
//! DESIGN §1.8), with and without a background category.
#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use libfuzzer_sys::fuzz_target;
use mlmap_fuzz::{check_encoding, check_table, ArbBayes, ArbOpen, ArbTable};

#[derive(Arbitrary, Debug)]
enum Input {
    /// The shape of the shipped table.
    Shipped(ArbTable<3, 22, 17>),
    Small(ArbTable<2, 4, 3>),
    /// One bin per head: the degenerate histogram.
    OneBin(ArbTable<2, 1, 1>),
    Wide(ArbTable<5, 9, 2>),
    /// A Bayes head with background, then an open head (the small golden table's shape).
    Open(ArbTable<3, 4, 2>, ArbBayes<3, 4, 4>, ArbOpen),
    /// A Bayes head without background, then an open head.
    OpenNoBackground(ArbTable<2, 3, 1>, ArbBayes<2, 2, 2>, ArbOpen),
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
        Input::Open(t, b, o) => roundtrip_open(t, b, o),
        Input::OpenNoBackground(t, b, o) => roundtrip_open(t, b, o),
    }
});

/// As [`roundtrip`], through a Bayes head (version 2) and then the open head (version 3):
/// `attach` checks each table, its encoding and its decoding.
fn roundtrip_open<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    a: &ArbTable<K, B_ML, B_MAP>,
    b: &ArbBayes<K, BB, C>,
    o: &ArbOpen,
) {
    let Ok(t) = a.build() else { return };
    let Some(t) = b.attach(&t) else { return };
    let bytes = check_encoding(&t, None);
    assert_eq!(
        bytes.get(4),
        Some(&2),
        "a Bayes head without the open head is version 2"
    );
    let Some(t) = o.attach(&t) else { return };
    let bytes = check_encoding(&t, None);
    assert!(bytes.len() <= mlmap::Table::<K, B_ML, B_MAP, BB, C>::MAX_ENCODED_LEN);
    let mut short = vec![0u8; bytes.len() - 1];
    assert!(
        t.to_slice(&mut short).is_err(),
        "encoded into a too-short buffer"
    );
}

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
