//! The Bayes head on the whole test split (every front, the formula, the batch), and the
//! open head against the numpy reference.

use super::*;

/// The Bayes head (DESIGN §1.6) on the shipped table: the fixed-size table and the
/// run-time shaped one compute the same bits for every row of `examples/data/test.csv`,
/// as does the batch API; and the batch reports the first bad row like the others.
#[cfg(feature = "std")]
mod bayes {
    use mlmap::host::DynTable;
    use mlmap::FastMath;

    use super::*;
    use crate::support::{SHIPPED_MLMAP, TEST_SPLIT_CSV};

    /// The logits and objectness of every row of the shipped test split.
    fn test_rows() -> (Vec<[f32; 3]>, Vec<f32>) {
        let csv = include_str!("../../examples/data/test.csv");
        let mut lines = csv.lines();
        assert_eq!(
            lines.next(),
            Some("id,label,objectness,car,cyclist,pedestrian")
        );
        let (mut xs, mut os) = (Vec::new(), Vec::new());
        for line in lines {
            let f: Vec<&str> = line.split(',').collect();
            let num = |i: usize| f[i].parse::<f32>().unwrap();
            os.push(num(2));
            xs.push([num(3), num(4), num(5)]);
        }
        (xs, os)
    }

    /// Every front of the layer (the fixed-size table, the run-time shaped one, the
    /// batch API) against the numpy reference on the sampled rows of the test split:
    /// ML, MAP and Bayes (`FastMath`) within `GOLDEN_ABS_TOL`.
    #[test]
    fn every_front_matches_the_numpy_reference_on_the_test_split() {
        let t = shipped();
        let d = DynTable::from_bytes(SHIPPED_MLMAP).unwrap();
        let golden = goldens(TEST_SPLIT_CSV);
        assert_eq!(golden.len(), 500);
        let xs: Vec<[f32; 3]> = golden.iter().map(|g| g.logits).collect();
        let os: Vec<f32> = golden.iter().map(|g| g.objectness).collect();
        let mut batch = [
            vec![[0.0f32; 3]; xs.len()],
            vec![[0.0f32; 3]; xs.len()],
            vec![[0.0f32; 3]; xs.len()],
        ];
        t.ml_batch(&xs, Some(&os), &mut batch[0]).unwrap();
        t.map_batch(&xs, Some(&os), &mut batch[1]).unwrap();
        t.bayes_batch(&xs, Some(&os), &mut batch[2]).unwrap();
        let (mut out, mut scratch) = ([0.0f32; 3], [0.0f32; 4]);
        let mut worst = [0.0f64; 3];
        for (i, g) in golden.iter().enumerate() {
            let (x, o) = (&g.logits, g.objectness);
            let want = [g.ml.unwrap(), g.map.unwrap(), g.bayes.unwrap()];
            let mut fronts: Vec<(&str, usize, [f32; 3])> = vec![
                ("Table::ml", 0, t.ml(x, o).unwrap().0),
                ("Table::map", 1, t.map(x, o).unwrap().0),
                ("Table::bayes", 2, t.bayes(x, o).unwrap().0),
            ];
            for (h, b) in batch.iter().enumerate() {
                fronts.push(("batch", h, b[i]));
            }
            d.ml_into(x, o, &mut out, &mut [0.0; 3]).unwrap();
            fronts.push(("DynTable::ml_into", 0, out));
            d.map_into::<Libm>(x, o, &mut out, &mut [0.0; 3]).unwrap();
            fronts.push(("DynTable::map_into", 1, out));
            d.bayes_into::<FastMath>(x, o, &mut out, &mut scratch)
                .unwrap();
            fronts.push(("DynTable::bayes_into", 2, out));
            for (front, head, got) in fronts {
                for (&s, &w) in got.iter().zip(&want[head]) {
                    let err = (f64::from(s) - w).abs();
                    worst[head] = worst[head].max(err);
                    assert!(
                        err <= GOLDEN_ABS_TOL,
                        "{front}, {}: got {got:?}, want {:?}",
                        g.case,
                        want[head]
                    );
                }
            }
        }
        eprintln!(
            "test split, worst score error ML {:e}, MAP {:e}, Bayes {:e}",
            worst[0], worst[1], worst[2]
        );
    }

    /// The batch API gives the bits of one call per row, on every row of the test split.
    #[test]
    fn the_batch_gives_the_bits_of_single_calls_on_the_test_split() {
        let t = shipped();
        let (xs, os) = test_rows();
        assert_eq!(xs.len(), 10_000);
        let mut batch = vec![[0.0f32; 3]; xs.len()];
        t.bayes_batch(&xs, Some(&os), &mut batch).unwrap();
        let mut distinct = std::collections::HashSet::new();
        for ((x, &o), row) in xs.iter().zip(&os).zip(&batch) {
            let s = t.bayes(x, o).unwrap().0;
            assert_eq!(row.map(f32::to_bits), s.map(f32::to_bits), "{x:?} {o}");
            distinct.insert(s.map(f32::to_bits));
        }
        // Not a degenerate comparison: the rows get many different scores.
        assert!(distinct.len() > 5_000, "{}", distinct.len());
    }

    /// Every row of the test split against the formula in `f64` from the stored terms:
    /// within the stated tolerance (and the measured error is reported).
    #[test]
    #[cfg(feature = "invariants")]
    fn test_split_follows_the_formula_within_the_stated_tolerance() {
        use mlmap::invariants::{bayes_reference, bayes_score_tolerance, check_scores, Sum};
        let t = shipped();
        let head = t.bayes_head().unwrap();
        let tolerance = bayes_score_tolerance(&head);
        let (xs, os) = test_rows();
        let (mut want, mut scratch) = ([0.0f64; 3], [0.0f64; 4]);
        let mut worst = 0.0f64;
        for (x, &o) in xs.iter().zip(&os) {
            let s = t.bayes(x, o).unwrap().0;
            check_scores(&s, o, Sum::AtMost).unwrap();
            assert!(bayes_reference(&head, x, o, &mut want, &mut scratch));
            for (&v, &w) in s.iter().zip(&want) {
                if w > 1e-30 {
                    worst = worst.max((f64::from(v) - w).abs() / w);
                }
            }
        }
        eprintln!("Bayes, test split: worst relative error {worst:e}, tolerance {tolerance:e}");
        assert!(worst <= tolerance, "{worst:e} > {tolerance:e}");
    }

    #[test]
    fn bayes_batch_reports_the_first_bad_row() {
        let t = shipped();
        let rows = batch_rows();
        let mut out = [SENTINEL; 4];
        assert_eq!(
            t.bayes_batch(&rows, None, &mut out),
            Err(BatchError::Row {
                index: 2,
                error: InferError::NanLogit { class: 1 }
            })
        );
        assert_eq!(out[0], t.bayes(&rows[0], 1.0).unwrap().0);
        assert_eq!(out[1], t.bayes(&rows[1], 1.0).unwrap().0);
        assert_eq!(out[2..], [SENTINEL; 2]);
        // A bad objectness in row 1 of valid rows; then resuming after it.
        let valid = [rows[0], rows[1], rows[3]];
        let mut out = [SENTINEL; 3];
        assert_eq!(
            t.bayes_batch(&valid, Some(&[0.5, -0.25, 0.5]), &mut out),
            Err(BatchError::Row {
                index: 1,
                error: InferError::Objectness
            })
        );
        assert_eq!(out[0], t.bayes(&valid[0], 0.5).unwrap().0);
        assert_eq!(out[1..], [SENTINEL; 2]);
        let mut rest = [SENTINEL; 1];
        t.bayes_batch(&valid[2..], Some(&[0.5]), &mut rest).unwrap();
        assert_eq!(rest[0], t.bayes(&valid[2], 0.5).unwrap().0);
        // Lengths are checked before any row: nothing written.
        let mut short = [SENTINEL; 1];
        assert_eq!(
            t.bayes_batch(&rows, None, &mut short),
            Err(BatchError::LengthMismatch)
        );
        assert_eq!(short, [SENTINEL]);
    }
}

/// One row of `tests/golden/layer/open.csv`: the open head's expected scores (float64,
/// from tools/mlmap_ref.py), or its error.
struct OpenGolden {
    table: String,
    case: String,
    objectness: f32,
    logits: [f32; 3],
    scores: Option<[f64; 3]>,
    error: Option<InferError>,
}

fn open_goldens() -> Vec<OpenGolden> {
    let csv = include_str!("../golden/layer/open.csv");
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    assert_eq!(
        lines.next(),
        Some("table,case,objectness,x0,x1,x2,open0,open1,open2,q,error")
    );
    lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), 11, "golden line {line:?}");
            let error = match f[10] {
                "" => None,
                "objectness" => Some(InferError::Objectness),
                e => Some(InferError::NanLogit {
                    class: e.strip_prefix("nan_logit:").unwrap().parse().unwrap(),
                }),
            };
            let x = |i: usize| f[i].parse::<f32>().unwrap();
            let s = |i: usize| f[i].parse::<f64>().unwrap();
            OpenGolden {
                table: f[0].to_owned(),
                case: f[1].to_owned(),
                objectness: x(2),
                logits: [x(3), x(4), x(5)],
                scores: error.is_none().then(|| [s(6), s(7), s(8)]),
                error,
            }
        })
        .collect()
}

#[test]
fn open_head_matches_the_numpy_reference() {
    let with_bg =
        SmallBayes::from_bytes(include_bytes!("../golden/layer/small_open.mlmap")).unwrap();
    let no_bg = SmallBayesNoBg::from_bytes(include_bytes!("../golden/layer/small_open_nobg.mlmap"))
        .unwrap();
    let shipped = shipped();
    let rows = open_goldens();
    let mut worst = 0.0f64;
    for g in &rows {
        let (x, os) = (&g.logits, g.objectness);
        let got = match g.table.as_str() {
            "small_open" => with_bg.open(x, os),
            "small_open_nobg" => no_bg.open(x, os),
            "default" => shipped.open(x, os),
            other => panic!("unknown golden table {other}"),
        };
        let what = format!("{} {}: x = {x:?}, OS = {os}", g.table, g.case);
        match (g.scores, g.error) {
            (None, Some(e)) => assert_eq!(got.err(), Some(e), "{what}"),
            (Some(want), None) => {
                let got = got.unwrap_or_else(|e| panic!("{what}: {e:?}")).0;
                for (i, (&s, &w)) in got.iter().zip(&want).enumerate() {
                    let err = (f64::from(s) - w).abs();
                    assert!(
                        err <= GOLDEN_ABS_TOL,
                        "{what}: open score {i} {s} vs {w} (error {err:e})"
                    );
                    worst = worst.max(err);
                }
                // The decision is the detector's: the largest logit, ties to the lower
                // index (every golden case).
                let best = (0..3).fold(0, |b, i| if x[i] > x[b] { i } else { b });
                assert_eq!(mlmap::decide(&got, x), best, "{what}");
            }
            _ => unreachable!("a golden row has scores or an error"),
        }
        // epsilon = 0 and no background: the temperature layer, bit for bit.
        if g.table == "small_open_nobg" && g.error.is_none() {
            let t = no_bg.open_params().unwrap().temperature();
            let want = mlmap::baseline::temperature::<mlmap::FastMath, 3>(x, t, os).unwrap();
            assert_eq!(no_bg.open(x, os).unwrap(), want, "{what}");
        }
    }
    for table in ["small_open", "small_open_nobg", "default"] {
        assert!(
            rows.iter().filter(|g| g.table == table).count() >= 40,
            "{table}"
        );
    }
    assert!(rows.iter().any(|g| g.error.is_some()));
    eprintln!(
        "open head: {} golden rows, worst score error {worst:e}",
        rows.len()
    );
}

#[cfg(feature = "std")]
#[test]
fn tables_without_the_open_head_say_so() {
    // Version 2: a Bayes head, no open head.
    assert_eq!(
        small_bayes().open(&[0.0; 3], 1.0),
        Err(InferError::NoOpenHead)
    );
    assert_eq!(small_bayes().open_params(), None);
    let d = mlmap::host::DynTable::from_table(&small_bayes());
    let (mut out, mut scratch) = ([0.0f32; 3], [0.0f32; 4]);
    assert_eq!(
        d.open_into::<mlmap::FastMath>(&[0.0; 3], 1.0, &mut out, &mut scratch),
        Err(InferError::NoOpenHead)
    );
    // Version 1: no Bayes head, so none.
    let d = mlmap::host::DynTable::from_table(&small());
    assert_eq!(
        d.open_into::<mlmap::FastMath>(&[0.0; 3], 1.0, &mut out, &mut scratch),
        Err(InferError::NoOpenHead)
    );
    assert!(d.with_open(1.0, 0.0).is_err());
}
