//! Any logits and objectness, NaN, ±inf and subnormals included, on a valid table: a NaN
//! logit or an objectness that is NaN or outside [0, 1] is an error, never a NaN score
//! (DESIGN §1.3, invariant 4); otherwise every score is in [0, OS] and they sum to OS
//! (invariant 1), no evidence gives exactly OS / K (invariant 2), the scores follow the
//! formula of DESIGN §1.2, and ML, MAP (libm) and MAP (FastMath) all hold. The batch API
//! and the host's `DynTable` must give the same bits. On the shipped table and on
//! arbitrary tables given an arbitrary Bayes head, the Bayes head's invariants (DESIGN
//! §1.6) and its formula are checked too; and, on the shipped table (temperature 1,
//! epsilon 0 as fitted, or an arbitrary temperature and epsilon) and on arbitrary Bayes
//! heads given an arbitrary temperature and epsilon, the open head's (DESIGN §1.8): its
//! range and sum, the detector's decision, its formula, the temperature layer at epsilon
//! 0 without background, and that a larger epsilon never raises a score. Tables given
//! arbitrary recalibration maps (DESIGN §1.9) on every head: accepted exactly when the
//! knots keep the rule, and each mapped top is `g(top)`, the other scores below it,
//! the order and the decision those of the table without maps.
#![no_main]

use std::sync::OnceLock;

use arbitrary::Unstructured;
use libfuzzer_sys::fuzz_target;
use mlmap_fuzz::{
    check_detections, check_detections_with_bayes, check_detections_with_maps,
    check_detections_with_open, ArbBayes, ArbMaps, ArbOpen, ArbTable, Shipped, SHIPPED,
};

fn shipped() -> &'static Shipped {
    static T: OnceLock<Shipped> = OnceLock::new();
    T.get_or_init(|| Shipped::from_bytes(SHIPPED).expect("the shipped table decodes"))
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let Ok(choice) = u.int_in_range(0u8..=10) else {
        return;
    };
    match choice {
        // The shipped table (with its Bayes head and its open head as fitted), where the
        // FastMath error bound is documented.
        0 => check_detections_with_bayes(shipped(), &mut u, true),
        1 => table::<3, 22, 17>(&mut u),
        2 => table::<2, 4, 3>(&mut u),
        3 => table::<4, 1, 2>(&mut u),
        // Arbitrary Bayes heads with an arbitrary open head: with background, without,
        // one bin.
        4 => bayes_table::<3, 22, 17, 5, 4>(&mut u),
        5 => bayes_table::<4, 1, 2, 3, 4>(&mut u),
        6 => bayes_table::<2, 4, 3, 1, 3>(&mut u),
        // The shipped table with an arbitrary temperature and epsilon.
        7 => shipped_open(&mut u),
        // Arbitrary recalibration maps: on the shipped table, on an arbitrary table
        // without a Bayes head, and on arbitrary Bayes and open heads.
        8 => {
            if let Ok(maps) = u.arbitrary::<ArbMaps>() {
                check_detections_with_maps(shipped(), &maps, &mut u);
            }
        }
        9 => {
            let (Ok(a), Ok(maps)) = (u.arbitrary::<ArbTable<3, 4, 2>>(), u.arbitrary::<ArbMaps>())
            else {
                return;
            };
            if let Ok(t) = a.build() {
                check_detections_with_maps(&t, &maps, &mut u);
            }
        }
        _ => {
            let (Ok(a), Ok(b), Ok(open), Ok(maps)) = (
                u.arbitrary::<ArbTable<3, 4, 2>>(),
                u.arbitrary::<ArbBayes<3, 4, 4>>(),
                u.arbitrary::<ArbOpen>(),
                u.arbitrary::<ArbMaps>(),
            ) else {
                return;
            };
            let Ok(t) = a.build() else { return };
            let Some(t) = b.attach(&t) else { return };
            match open.attach(&t) {
                Some(o) => check_detections_with_maps(&o, &maps, &mut u),
                None => check_detections_with_maps(&t, &maps, &mut u),
            }
        }
    }
});

/// The shipped table given an arbitrary open head (skipped when its parameters are
/// invalid), then detections on it.
fn shipped_open(u: &mut Unstructured<'_>) {
    let Ok(open) = u.arbitrary::<ArbOpen>() else {
        return;
    };
    let Some(t) = open.attach(shipped()) else {
        return;
    };
    let higher = open.attach_raised(shipped());
    check_detections_with_open(&t, higher.as_ref(), u, true);
}

/// A structured arbitrary table (skipped when invalid), then detections on it.
fn table<const K: usize, const B_ML: usize, const B_MAP: usize>(u: &mut Unstructured<'_>) {
    let Ok(a) = u.arbitrary::<ArbTable<K, B_ML, B_MAP>>() else {
        return;
    };
    let Ok(t) = a.build() else { return };
    check_detections(&t, u, false);
}

/// A structured arbitrary table with an arbitrary Bayes head (skipped when either is
/// invalid) and an arbitrary open head (left out when its parameters are invalid: the
/// version-2 table must then refuse the open head), then detections on it.
fn bayes_table<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    u: &mut Unstructured<'_>,
) {
    let (Ok(a), Ok(b), Ok(open)) = (
        u.arbitrary::<ArbTable<K, B_ML, B_MAP>>(),
        u.arbitrary::<ArbBayes<K, BB, C>>(),
        u.arbitrary::<ArbOpen>(),
    ) else {
        return;
    };
    let Ok(t) = a.build() else { return };
    let Some(t) = b.attach(&t) else { return };
    match open.attach(&t) {
        Some(with_open) => {
            let higher = open.attach_raised(&t);
            check_detections_with_open(&with_open, higher.as_ref(), u, false);
        }
        None => check_detections_with_bayes(&t, u, false),
    }
}
