//! The open head (DESIGN §1.8): arbitrary temperatures and epsilons (`ArbOpen`), its
//! scores against the formula, and that a larger epsilon never raises a score.

use super::*;

/// The open head's temperature from fuzz input.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum ArbTemperature {
    /// 1, what `fit` writes.
    One,
    /// `10^(12 v / 65535 - 6)`: every decade of the allowed `[1e-6, 1e6]`.
    Decades(u16),
    /// A bound of the allowed range, one step beyond it, or a value never allowed.
    Bound(u8),
    /// Any bits (mostly invalid).
    Bits(u32),
}

impl ArbTemperature {
    /// The value.
    pub fn get(self) -> f32 {
        match self {
            ArbTemperature::One => 1.0,
            ArbTemperature::Decades(v) => 10f64.powf(12.0 * f64::from(v) / 65535.0 - 6.0) as f32,
            ArbTemperature::Bound(i) => {
                const S: [f32; 8] = [
                    MIN_TEMPERATURE,
                    MAX_TEMPERATURE,
                    MIN_TEMPERATURE.next_down(),
                    MAX_TEMPERATURE.next_up(),
                    0.0,
                    -1.0,
                    f32::INFINITY,
                    f32::NAN,
                ];
                S[usize::from(i) % S.len()]
            }
            ArbTemperature::Bits(b) => f32::from_bits(b),
        }
    }
}

/// The open head's epsilon (the unknown category's prior weight) from fuzz input.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum ArbEpsilon {
    /// 0: no unknown category, what `fit` writes.
    Zero,
    /// `10^(68 v / 65535 - 38)`: every decade from about `f32::MIN_POSITIVE` to the
    /// allowed maximum `1e30`.
    Decades(u16),
    /// A bound of the allowed values, one step beyond one, or a value never allowed
    /// (negative zero, a subnormal, infinity, NaN).
    Bound(u8),
    /// Any bits (mostly invalid).
    Bits(u32),
}

impl ArbEpsilon {
    /// The value.
    pub fn get(self) -> f32 {
        match self {
            ArbEpsilon::Zero => 0.0,
            ArbEpsilon::Decades(v) => 10f64.powf(68.0 * f64::from(v) / 65535.0 - 38.0) as f32,
            ArbEpsilon::Bound(i) => {
                const S: [f32; 9] = [
                    f32::MIN_POSITIVE,
                    MAX_EPSILON,
                    1.0,
                    -0.0,
                    f32::MIN_POSITIVE.next_down(),
                    MAX_EPSILON.next_up(),
                    -1.0e-3,
                    f32::INFINITY,
                    f32::NAN,
                ];
                S[usize::from(i) % S.len()]
            }
            ArbEpsilon::Bits(b) => f32::from_bits(b),
        }
    }
}

/// The open head's parameters, and a second, larger epsilon for the monotonicity check.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub struct ArbOpen {
    temperature: ArbTemperature,
    epsilon: ArbEpsilon,
    /// The larger epsilon: `epsilon * 2^(raise / 256)` (from 0: `10^(raise / 1024 - 37.5)`),
    /// at most the allowed maximum.
    raise: u16,
}

impl ArbOpen {
    /// The temperature and epsilon.
    pub fn params(&self) -> (f32, f32) {
        (self.temperature.get(), self.epsilon.get())
    }

    /// An epsilon no smaller than [`ArbOpen::params`]' (when that one is valid).
    pub fn raised(&self) -> f32 {
        let e = self.epsilon.get();
        let up = if e == 0.0 {
            10f64.powf(f64::from(self.raise) / 1024.0 - 37.5)
        } else {
            f64::from(e) * 2f64.powf(f64::from(self.raise) / 256.0)
        };
        // Never below e: f32 rounding of the product cannot go under it (up >= e).
        (up.min(f64::from(MAX_EPSILON)) as f32).max(e)
    }

    /// `table` (which must have a Bayes head) with this open head, through
    /// `DynTable::with_open` and the wire format (version 3), checked by
    /// [`check_dyn_table`] and [`check_table`], with the parameters stored bit for bit;
    /// `None` when `with_open` refuses the parameters, which must then be the ones
    /// [`invariants::check_open_params`] refuses (and the other way round).
    pub fn attach<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const BB: usize,
        const C: usize,
    >(
        &self,
        table: &Table<K, B_ML, B_MAP, BB, C>,
    ) -> Option<Table<K, B_ML, B_MAP, BB, C>> {
        let (temperature, epsilon) = self.params();
        with_open(table, temperature, epsilon)
    }

    /// `table` with the temperature of [`ArbOpen::params`] and [`ArbOpen::raised`] as
    /// epsilon (unchecked beyond what decoding checks: [`ArbOpen::attach`] checks the
    /// same code on the other epsilon).
    pub fn attach_raised<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const BB: usize,
        const C: usize,
    >(
        &self,
        table: &Table<K, B_ML, B_MAP, BB, C>,
    ) -> Option<Table<K, B_ML, B_MAP, BB, C>> {
        let d = DynTable::from_table(table)
            .with_open(self.temperature.get(), self.raised())
            .ok()?;
        Table::try_from(&d).ok()
    }
}

/// `table` with the open head `(temperature, epsilon)`: see [`ArbOpen::attach`].
fn with_open<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    table: &Table<K, B_ML, B_MAP, BB, C>,
    temperature: f32,
    epsilon: f32,
) -> Option<Table<K, B_ML, B_MAP, BB, C>> {
    let valid = invariants::check_open_params(temperature, epsilon).is_ok();
    let what = format!("with_open(T = {temperature:e}, epsilon = {epsilon:e})");
    match DynTable::from_table(table).with_open(temperature, epsilon) {
        Ok(d) => {
            assert!(valid, "{what} accepted parameters the checkers refuse");
            check_dyn_table(&d);
            let t = Table::<K, B_ML, B_MAP, BB, C>::try_from(&d)
                .expect("a table with a valid open head converts to its shape");
            check_table(&t);
            let p = t
                .open_params()
                .expect("the open head survives the wire format");
            assert_eq!(
                (p.temperature().to_bits(), p.epsilon().to_bits()),
                (temperature.to_bits(), epsilon.to_bits()),
                "{what}: stored as {p:?}"
            );
            let bytes = d.to_vec().expect("a valid table encodes");
            // Version 3: the open head without a map (a table is written in the lowest
            // version that holds it).
            assert_eq!(
                bytes.get(4).copied(),
                Some(3),
                "{what}: not written as format version 3"
            );
            Some(t)
        }
        Err(e) => {
            assert!(!valid, "{what} refused valid parameters: {e}");
            assert!(
                matches!(e, TableError::Temperature | TableError::Epsilon),
                "{what}: {e:?}"
            );
            None
        }
    }
}

/// Scores one detection with the open head (FastMath, the default, and Libm) and checks
/// DESIGN §1.8 through the shared checkers: errors for bad inputs
/// ([`invariants::check_error`], and the same error from `DynTable`, the view's
/// `score_into(Head::Open)` and the batch); otherwise scores in `[0, OS]` summing to at
/// most `OS` ([`invariants::check_scores`] with [`Sum::AtMost`]), the detector's decision
/// ([`invariants::check_open_decision`]), within [`invariants::open_score_tolerance`] of
/// the `f64` formula ([`invariants::open_mismatch`] against
/// [`invariants::open_reference`]); with epsilon 0 and no background category, bit for
/// bit the temperature layer; and the same bits from `DynTable`, the view and the batch.
pub fn check_open_detection<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    dynt: &DynTable,
    x: &[f32; K],
    objectness: f32,
) {
    let head = t.bayes_head().expect("a table type with a Bayes head");
    let params = t.open_params().expect("a table with the open head");
    let fast = t.open(x, objectness);
    let libm = t.open_with::<Libm>(x, objectness);
    let what = format_args!("open: x = {x:?}, OS = {objectness:e}, {params:?}");
    for r in [&fast, &libm] {
        must(invariants::check_error(x, objectness, r.err()), what);
    }
    check_fronts::<Libm, K, B_ML, B_MAP, BB, C>(
        t,
        dynt,
        Head::Open,
        x,
        objectness,
        &fast,
        &libm,
        &|xs, os, out| t.open_batch(xs, os, out),
        None,
        what,
    );
    let (Ok(fast), Ok(libm)) = (fast, libm) else {
        return;
    };
    let mut want = [0.0f64; K];
    let mut s64 = [0.0f64; C];
    assert!(
        invariants::open_reference(&head, &params, x, objectness, &mut want, &mut s64).is_some(),
        "{what}: the reference refused the lengths"
    );
    for (name, s) in [("FastMath", &fast.0), ("Libm", &libm.0)] {
        must(
            invariants::check_scores(s, objectness, Sum::AtMost),
            format_args!("{what}: {name} {s:?}"),
        );
        must(
            invariants::check_open_decision(s, x),
            format_args!("{what}: {name} {s:?}"),
        );
        if let Some(i) = invariants::open_mismatch(&head, &params, x, s, &want, objectness) {
            panic!(
                "{what}: {name} score {i} of {s:?} is not the formula's {want:?} within a relative {:e}",
                invariants::open_score_tolerance(&head, &params, x)
            );
        }
    }
    let bits = |s: &[f32; K]| s.map(f32::to_bits);
    // epsilon 0 and no background category: q = 1 exactly, the temperature layer.
    if params.epsilon() == 0.0 && C == K {
        for (name, got, want) in [
            (
                "FastMath",
                fast,
                mlmap::baseline::temperature::<FastMath, K>(x, params.temperature(), objectness),
            ),
            (
                "Libm",
                libm,
                mlmap::baseline::temperature::<Libm, K>(x, params.temperature(), objectness),
            ),
        ] {
            let want = want.expect("valid inputs");
            assert_eq!(
                bits(&got.0),
                bits(&want.0),
                "{what}: {name} epsilon 0 without background is not the temperature layer"
            );
        }
    }
}

/// DESIGN §1.8: raising epsilon never raises a score, with either backend, not even by a
/// rounding step. `low` and `high` are one table with two epsilons, `high`'s the larger.
pub fn check_open_monotone<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    low: &Table<K, B_ML, B_MAP, BB, C>,
    high: &Table<K, B_ML, B_MAP, BB, C>,
    x: &[f32; K],
    objectness: f32,
) {
    let (lo, hi) = match (low.open_params(), high.open_params()) {
        (Some(a), Some(b)) => (a, b),
        _ => panic!("both tables must have the open head"),
    };
    assert!(
        lo.epsilon() <= hi.epsilon() && lo.temperature() == hi.temperature(),
        "{lo:?} vs {hi:?}"
    );
    for (name, a, b) in [
        (
            "FastMath",
            low.open(x, objectness),
            high.open(x, objectness),
        ),
        (
            "Libm",
            low.open_with::<Libm>(x, objectness),
            high.open_with::<Libm>(x, objectness),
        ),
    ] {
        let (Ok(a), Ok(b)) = (a, b) else {
            assert_eq!(
                a.err(),
                b.err(),
                "{name}: the two epsilons give other errors"
            );
            continue;
        };
        for (i, (sa, sb)) in a.0.iter().zip(&b.0).enumerate() {
            assert!(
                sb <= sa,
                "{name}: class {i}: epsilon {:e} gives {sa:e}, the larger {:e} gives {sb:e}; x = {x:?}, OS = {objectness:e}, T = {:e}",
                lo.epsilon(),
                hi.epsilon(),
                lo.temperature()
            );
        }
    }
}
