//! Any logits and objectness, NaN, ±inf and subnormals included, on a valid table: a NaN
//! logit or an objectness that is NaN or outside [0, 1] is an error, never a NaN score
//! (DESIGN §1.3, invariant 4); otherwise every score is in [0, OS] and they sum to OS
//! (invariant 1), no evidence gives exactly OS / K (invariant 2), the scores follow the
//! formula of DESIGN §1.2, and ML, MAP (libm) and MAP (FastMath) all hold. The batch API
//! and the host's `DynTable` must give the same bits.
#![no_main]

use std::sync::OnceLock;

use arbitrary::Unstructured;
use libfuzzer_sys::fuzz_target;
use mlmap_fuzz::{check_detections, ArbTable, Shipped, SHIPPED};

fn shipped() -> &'static Shipped {
    static T: OnceLock<Shipped> = OnceLock::new();
    T.get_or_init(|| Shipped::from_bytes(SHIPPED).expect("the shipped table decodes"))
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let Ok(choice) = u.int_in_range(0u8..=3) else {
        return;
    };
    match choice {
        // The shipped table, where the FastMath error bound is documented.
        0 => check_detections(shipped(), &mut u, true),
        1 => table::<3, 22, 17>(&mut u),
        2 => table::<2, 4, 3>(&mut u),
        _ => table::<4, 1, 2>(&mut u),
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
