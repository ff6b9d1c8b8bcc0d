//! The layer against the numpy reference, its error cases, the batch API and the exact
//! "I don't know" answer (DESIGN §1.2, §1.3, §1.6, §1.8).

use mlmap::{BatchError, InferError, Libm, Scores, Table, UpperTail};

use crate::support::{
    goldens, shipped, small, small_bayes, small_bayes_nobg, small_clamp, small_settings,
    small_specs, Golden, Shipped, Small, SmallBayes, SmallBayesNoBg, GOLDEN_ABS_TOL, SHIPPED_CSV,
    SMALL_CSV,
};

/// Bayes scores of one detection through the table's view (so that the same code
/// serves table types with and without the head).
fn bayes_of<const BM: usize, const BP: usize, const BB: usize, const C: usize>(
    table: &Table<3, BM, BP, BB, C>,
    logits: &[f32; 3],
    objectness: f32,
) -> Result<[f32; 3], InferError> {
    let mut out = [0.0f32; 3];
    let mut scratch = [0.0f32; C];
    table
        .view()
        .bayes_into::<Libm>(logits, objectness, &mut out, &mut scratch)?;
    Ok(out)
}

/// Checks one golden row against `table` (every head it has); returns the largest
/// score error seen, ML / MAP and Bayes.
fn check_golden<const BM: usize, const BP: usize, const BB: usize, const C: usize>(
    table: &Table<3, BM, BP, BB, C>,
    g: &Golden,
) -> (f64, f64) {
    let what = format!(
        "{} / {} / logits {:?} / objectness {}",
        g.table, g.case, g.logits, g.objectness
    );
    let ml = table.ml(&g.logits, g.objectness);
    let map = table.map(&g.logits, g.objectness);
    let bayes = bayes_of(table, &g.logits, g.objectness);
    let (Some(want_ml), Some(want_map)) = (g.ml, g.map) else {
        let want = g.error.expect("a golden row holds scores or an error");
        assert_eq!(ml, Err(want), "ML: {what}");
        assert_eq!(map, Err(want), "MAP: {what}");
        if BB > 0 {
            assert_eq!(bayes, Err(want), "Bayes: {what}");
        }
        return (0.0, 0.0);
    };
    let mut worst = (0.0f64, 0.0f64);
    let heads = [
        ("ML", ml.map(|s| s.0), Some(want_ml)),
        ("MAP", map.map(|s| s.0), Some(want_map)),
        ("Bayes", bayes, g.bayes),
    ];
    for (head, got, want) in heads {
        let Some(want) = want else {
            // No Bayes scores in the golden file: the table has no Bayes head.
            assert_eq!(got, Err(InferError::NoBayesHead), "{head}: {what}");
            assert_eq!(BB, 0, "{what}: the golden file has no Bayes scores");
            continue;
        };
        let got = got.unwrap_or_else(|e| panic!("{head}: {what}: unexpected {e:?}"));
        for (i, (&s, &w)) in got.iter().zip(&want).enumerate() {
            let err = (f64::from(s) - w).abs();
            assert!(
                err <= GOLDEN_ABS_TOL,
                "{head} score {i}: {what}: got {s}, want {w} (error {err:e} > {GOLDEN_ABS_TOL:e})"
            );
            if head == "Bayes" {
                worst.1 = worst.1.max(err);
            } else {
                worst.0 = worst.0.max(err);
            }
        }
    }
    worst
}

/// Logit rows for the batch tests: valid, valid, NaN, valid.
fn batch_rows() -> [[f32; 3]; 4] {
    [
        [3.0, -2.0, -1.0],
        [0.5, 0.5, f32::INFINITY],
        [0.5, f32::NAN, 0.5],
        [-1.0, 2.0, 0.0],
    ]
}

const SENTINEL: [f32; 3] = [-7.0; 3];

/// Objectness values for the exactness tests: the ends, tiny, awkward and a sweep.
fn objectness_values() -> Vec<f32> {
    let mut v = vec![
        0.0,
        -0.0,
        1.0,
        f32::from_bits(1),
        f32::MIN_POSITIVE,
        1e-30,
        0.1,
        1.0 / 3.0,
        0.5,
        0.93,
        1.0f32.next_down(),
    ];
    v.extend((0..=1000).map(|i| i as f32 / 1000.0));
    v.extend((0..200).map(|i| 0.7 + i as f32 * 1.3e-3));
    v
}

/// The run-time shaped table gives the same bits, the `exp` backends stay within their
/// stated bounds, and a negligible likelihood never lowers a score.
mod backends;
/// The Bayes head on the whole test split (every front, the formula, the batch), and the
/// open head against the numpy reference.
mod bayes_open;
/// The ML, MAP and Bayes heads against the numpy goldens and hand-computed values; the
/// Bayes head outside every axis and its sum rule.
mod goldens;
/// Errors, the batch API, ties, the exact `OS / K` answer out of support, the embedded
/// table and the auto traits.
mod rules;
