//! The Bayes head (DESIGN §1.6): arbitrary heads (`ArbBayes`), its objectness feature,
//! and its scores against the formula.

use super::*;

/// An arbitrary Bayes head for a table of `K` classes, `BB` bins per logit and `C`
/// categories: a lambda, a range per logit, rows per category and per (category,
/// logit) frequencies from integer weights, stored as a fit stores them
/// (`ln(h + lambda)` in `f64`, rounded to `f32`); now and then a term of any bits.
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbBayes<const K: usize, const BB: usize, const C: usize> {
    lambda: BayesLambda,
    ranges: [(Real, Real); K],
    rows: [u32; C],
    weights: [[[u16; BB]; K]; C],
    /// A term to overwrite with any bits (index into the terms, then the bits).
    hostile: Option<(u16, u32)>,
    /// The objectness feature (DESIGN §1.6): its axis (start, span) and per category
    /// integer weights of its bins.
    objectness: Option<ArbObjectness<BB, C>>,
}

/// An arbitrary objectness feature of a Bayes head with `BB` bins and `C` categories:
/// its axis (start, span) and, per category, the integer weights of its bins.
pub type ArbObjectness<const BB: usize, const C: usize> = ((Real, Real), [[u16; BB]; C]);

/// The Bayes head's smoothing from fuzz input.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum BayesLambda {
    /// `10^(-v / 4096)`: from 1 down to about 1e-16.
    Decades(u16),
    /// Any bits (mostly invalid).
    Bits(u32),
}

impl<const K: usize, const BB: usize, const C: usize> ArbBayes<K, BB, C> {
    /// The head as a [`BayesSpec`] (valid unless a range, the rows, lambda or a hostile
    /// term make it invalid).
    pub fn spec(&self) -> BayesSpec {
        let lambda = match self.lambda {
            BayesLambda::Decades(v) => 10f64.powf(-f64::from(v) / 4096.0) as f32,
            BayesLambda::Bits(b) => f32::from_bits(b),
        };
        let mut terms = Vec::with_capacity(K * BB * C);
        for j in 0..K {
            for b in 0..BB {
                for w in &self.weights {
                    let total: u64 = w[j].iter().map(|&v| u64::from(v)).sum();
                    let h = if total == 0 {
                        1.0 / BB as f64
                    } else {
                        f64::from(w[j][b]) / total as f64
                    };
                    terms.push((h + f64::from(lambda)).ln() as f32);
                }
            }
        }
        if let Some((i, bits)) = self.hostile {
            let n = terms.len();
            terms[usize::from(i) % n] = f32::from_bits(bits);
        }
        // The feature's terms: bin-major, then category.
        let objectness = self.objectness.as_ref().map(|((lo, span), weights)| {
            let span = span.positive();
            let span = if span == 0.0 { 1.0 } else { span };
            let mut t = Vec::with_capacity(BB * C);
            for b in 0..BB {
                for w in weights {
                    let total: u64 = w.iter().map(|&v| u64::from(v)).sum();
                    let h = if total == 0 {
                        1.0 / BB as f64
                    } else {
                        f64::from(w[b]) / total as f64
                    };
                    t.push((h + f64::from(lambda)).ln() as f32);
                }
            }
            ((lo.get(), lo.get() + span), t)
        });
        BayesSpec {
            lambda,
            // 0 rows (invalid) only for `u32::MAX`, a span of 0 (invalid) made 1: most
            // heads are valid even when the input runs out (and reads as zeros).
            rows: self
                .rows
                .iter()
                .map(|&n| u64::from(n.wrapping_add(1)))
                .collect(),
            ranges: self
                .ranges
                .iter()
                .map(|(lo, span)| {
                    let span = span.positive();
                    let span = if span == 0.0 { 1.0 } else { span };
                    (lo.get(), lo.get() + span)
                })
                .collect(),
            terms,
            objectness,
        }
    }

    /// `table` with this Bayes head, as the fixed-size type `Table<K, B_ML, B_MAP, BB,
    /// C>` (through `DynTable::with_bayes` and the wire format), checked by
    /// [`check_dyn_table`] and [`check_table`]; `None` when `with_bayes` refuses the head.
    /// Asserts that it never accepts terms that [`invariants::check_bayes_terms`]
    /// refuses.
    pub fn attach<const B_ML: usize, const B_MAP: usize>(
        &self,
        table: &Table<K, B_ML, B_MAP>,
    ) -> Option<Table<K, B_ML, B_MAP, BB, C>> {
        let spec = self.spec();
        let valid_terms = (0..C).all(|c| {
            (0..K).all(|j| {
                let terms = (0..BB).map(|b| spec.terms[(j * BB + b) * C + c]);
                invariants::check_bayes_terms(c, j, spec.lambda, terms, BB).is_ok()
            })
        });
        if spec.objectness.is_some() {
            // The objectness feature (DESIGN §1.6): checked on its own (the checks below
            // are written for heads without it); no table for them.
            if let Ok(d) = DynTable::from_table(table).with_bayes(spec.clone()) {
                check_objectness_feature::<K, B_ML, B_MAP, BB, C>(&d);
            }
            return None;
        }
        match DynTable::from_table(table).with_bayes(spec.clone()) {
            Ok(d) => {
                assert!(
                    valid_terms,
                    "with_bayes accepted terms the checkers refuse: {spec:?}"
                );
                check_dyn_table(&d);
                let t = Table::<K, B_ML, B_MAP, BB, C>::try_from(&d)
                    .expect("a valid Bayes head converts to its shape");
                check_table(&t);
                assert_eq!(DynTable::from_table(&t), d, "Table and DynTable differ");
                Some(t)
            }
            Err(_) => None,
        }
    }
}

/// A table with the objectness feature (DESIGN §1.6): its bytes decode to the same table
/// (version 4), the fixed-size type with `F = 1` scores the Bayes head bit for bit as
/// the host's table for objectness values across the axis and both ends, every score in
/// `[0, OS]` and their sum at most `OS`; a type without room refuses it.
pub fn check_objectness_feature<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    d: &DynTable,
) {
    let bytes = d.to_vec().expect("a valid table encodes");
    assert_eq!(bytes[4], 4, "the objectness feature is format version 4");
    assert_eq!(&DynTable::from_bytes(&bytes).expect("decodes"), d);
    assert_eq!(
        Table::<K, B_ML, B_MAP, BB, C>::from_bytes(&bytes).err(),
        Some(mlmap::DecodeError::ObjectnessMismatch { found: true })
    );
    let t = Table::<K, B_ML, B_MAP, BB, C, 0, 1>::from_bytes(&bytes).expect("room for it");
    let x = [0.0f32; K];
    let (mut out, mut scratch) = ([0.0f32; K], [0.0f32; C]);
    for os in [0.0f32, 1e-30, 0.1, 0.5, 0.9, 1.0 - f32::EPSILON, 1.0] {
        let s = t.bayes(&x, os).expect("a valid detection");
        d.bayes_into::<mlmap::FastMath>(&x, os, &mut out, &mut scratch)
            .expect("a valid detection");
        assert_eq!(s.0.map(f32::to_bits), out.map(f32::to_bits), "OS = {os:e}");
        assert!(s.0.iter().all(|&v| (0.0..=os).contains(&v)), "{s:?}");
        assert!(s.0.iter().sum::<f32>() <= os * (1.0 + 1e-5), "{s:?}");
    }
}

/// Scores one detection with the Bayes head (FastMath, the default, and Libm) and
/// checks DESIGN §1.6: errors for bad inputs (invariant 4, from `Table`, `DynTable` and
/// the batch); otherwise scores in `[0, OS]` with the head's sum rule, within
/// [`invariants::bayes_score_tolerance`] of the formula evaluated in `f64` from the
/// view's terms ([`invariants::bayes_reference`]), the prior's shares when every logit
/// is outside its axis, FastMath within `fast_math_max_score_error(C) * OS` of Libm
/// (plus `OS * f32::MIN_POSITIVE` and two subnormal steps, see `tests/invariants/`),
/// and the same bits from `DynTable` and the batch.
pub fn check_bayes_detection<
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
    let fast = t.bayes(x, objectness);
    let libm = t.bayes_with::<Libm>(x, objectness);
    let what = format_args!("Bayes: x = {x:?}, OS = {objectness:e}");
    for r in [&fast, &libm] {
        must(invariants::check_error(x, objectness, r.err()), what);
    }
    check_fronts::<Libm, K, B_ML, B_MAP, BB, C>(
        t,
        dynt,
        Head::Bayes,
        x,
        objectness,
        &fast,
        &libm,
        &|xs, os, out| t.bayes_batch(xs, os, out),
        None,
        what,
    );
    let (Ok(fast), Ok(libm)) = (fast, libm) else {
        return;
    };
    let mut want = [0.0f64; K];
    let mut s64 = [0.0f64; C];
    assert!(invariants::bayes_reference(
        &head, x, objectness, &mut want, &mut s64
    ));
    let unknown = (0..K).all(|j| head.axis(j).and_then(|a| a.bin(x[j])).is_none());
    for (name, s) in [("FastMath", &fast.0), ("Libm", &libm.0)] {
        must(
            invariants::check_scores(s, objectness, invariants::bayes_sum(&head)),
            format_args!("{what}: {name} {s:?}"),
        );
        if let Some(i) = invariants::bayes_mismatch(&head, s, &want, objectness) {
            panic!(
                "{what}: {name} score {i} of {s:?} is not the formula's {want:?} within a relative {:e}",
                invariants::bayes_score_tolerance(&head)
            );
        }
        if unknown {
            must(
                invariants::check_prior_share(s, objectness, &head),
                format_args!("{what}: {name} {s:?}"),
            );
        }
    }
    let os64 = f64::from(objectness);
    let bound = f64::from(fast_math_max_score_error(C)) * os64
        + os64 * f64::from(f32::MIN_POSITIVE)
        + 2.0 * TINY;
    for (a, b) in fast.0.iter().zip(&libm.0) {
        assert!(
            f64::from((a - b).abs()) <= bound,
            "{what}: FastMath {:?} and Libm {:?} more than {bound:e} apart",
            fast.0,
            libm.0
        );
    }
}
