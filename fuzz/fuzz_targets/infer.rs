//! Any logits and objectness, NaN, ±inf and subnormals included, on a valid table: a NaN
//! logit or an objectness that is NaN or outside [0, 1] is an error, never a NaN score
//! (DESIGN §1.3, invariant 4); otherwise every score is in [0, OS] and they sum to OS
//! (invariant 1), no evidence gives exactly OS / K (invariant 2), the scores follow the
//! formula of DESIGN §1.2, and ML, MAP (libm) and MAP (FastMath) all hold. The batch API
//! and the host's `DynTable` must give the same bits. On the shipped table and on
//! arbitrary tables given an arbitrary Bayes head, the Bayes head's invariants (DESIGN
//! §1.6) and its formula are checked too.
#![no_main]

use std::sync::OnceLock;

use arbitrary::Unstructured;
use libfuzzer_sys::fuzz_target;
use mlmap_fuzz::{
    check_detections, check_detections_with_bayes, ArbBayes, ArbTable, Shipped, SHIPPED,
};

fn shipped() -> &'static Shipped {
    static T: OnceLock<Shipped> = OnceLock::new();
    T.get_or_init(|| Shipped::from_bytes(SHIPPED).expect("the shipped table decodes"))
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let Ok(choice) = u.int_in_range(0u8..=6) else {
        return;
    };
    match choice {
        // The shipped table (with its Bayes head), where the FastMath error bound is
        // documented.
        0 => check_detections_with_bayes(shipped(), &mut u, true),
        1 => table::<3, 22, 17>(&mut u),
        2 => table::<2, 4, 3>(&mut u),
        3 => table::<4, 1, 2>(&mut u),
        // Arbitrary Bayes heads: with background, without, one bin.
        4 => bayes_table::<3, 22, 17, 5, 4>(&mut u),
        5 => bayes_table::<4, 1, 2, 3, 4>(&mut u),
        _ => bayes_table::<2, 4, 3, 1, 3>(&mut u),
    }
});

/// A structured arbitrary table (skipped when invalid), then detections on it.
fn table<const K: usize, const B_ML: usize, const B_MAP: usize>(u: &mut Unstructured<'_>) {
    let Ok(a) = u.arbitrary::<ArbTable<K, B_ML, B_MAP>>() else {
        return;
    };
    let Ok(t) = a.build() else { return };
    check_detections(&t, u, false);
}

/// A structured arbitrary table with an arbitrary Bayes head (skipped when either is
/// invalid), then detections on it.
fn bayes_table<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    u: &mut Unstructured<'_>,
) {
    let (Ok(a), Ok(b)) = (
        u.arbitrary::<ArbTable<K, B_ML, B_MAP>>(),
        u.arbitrary::<ArbBayes<K, BB, C>>(),
    ) else {
        return;
    };
    let Ok(t) = a.build() else { return };
    let Some(t) = b.attach(&t) else { return };
    check_detections_with_bayes(&t, u, false);
}
