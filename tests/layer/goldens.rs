//! The ML, MAP and Bayes heads against the numpy goldens and hand-computed values; the
//! Bayes head outside every axis and its sum rule.

use super::*;

#[test]
fn small_tables_match_the_numpy_reference() {
    let (plain, clamp) = (small(), small_clamp());
    let (with_bg, no_bg) = (small_bayes(), small_bayes_nobg());
    let mut worst = (0.0f64, 0.0f64);
    let rows = goldens(SMALL_CSV);
    for g in &rows {
        let w = match g.table.as_str() {
            "small" => check_golden(&plain, g),
            "small_clamp" => check_golden(&clamp, g),
            "small_bayes" => check_golden(&with_bg, g),
            "small_bayes_nobg" => check_golden(&no_bg, g),
            other => panic!("unknown golden table {other}"),
        };
        worst = (worst.0.max(w.0), worst.1.max(w.1));
    }
    // Every table, every case, including the error cases.
    assert!(rows.iter().any(|g| g.error.is_some()));
    for table in ["small_clamp", "small_bayes", "small_bayes_nobg"] {
        assert!(rows.iter().any(|g| g.table == table), "{table}");
    }
    let bayes_rows = rows.iter().filter(|g| g.bayes.is_some()).count();
    assert!(bayes_rows >= 100, "{bayes_rows} rows with Bayes scores");
    eprintln!(
        "small tables: {} golden rows ({bayes_rows} with Bayes scores), worst score error \
         ML/MAP {:e}, Bayes {:e}",
        rows.len(),
        worst.0,
        worst.1
    );
}

#[test]
fn shipped_table_matches_the_numpy_reference() {
    let decoded = shipped();
    let rows = goldens(SHIPPED_CSV);
    assert!(rows.len() >= 500);
    assert!(rows.iter().filter(|g| g.bayes.is_some()).count() >= 400);
    let mut worst = (0.0f64, 0.0f64);
    for g in &rows {
        assert_eq!(g.table, "default");
        let w = check_golden(&decoded, g);
        worst = (worst.0.max(w.0), worst.1.max(w.1));
        // The table embedded at build time gives the very same bits.
        let embedded = &mlmap::embedded::TABLE;
        if g.error.is_none() {
            assert_eq!(
                embedded.ml(&g.logits, g.objectness),
                decoded.ml(&g.logits, g.objectness)
            );
            assert_eq!(
                embedded.map(&g.logits, g.objectness),
                decoded.map(&g.logits, g.objectness)
            );
            assert_eq!(
                bayes_of(embedded, &g.logits, g.objectness),
                bayes_of(&decoded, &g.logits, g.objectness)
            );
        }
    }
    eprintln!(
        "shipped table: {} golden rows, worst score error ML/MAP {:e}, Bayes {:e}",
        rows.len(),
        worst.0,
        worst.1
    );
}

/// Hand-computed values of the small table, independent of every script: a reader can
/// check them with pencil and paper.
#[test]
fn small_table_by_hand() {
    let t = small();
    // car 0.5 -> bin 0 (0.1); cyclist 0.5 -> bin [0, 1) (0.2); pedestrian 0.5 > 0: no
    // likelihood. a = (0.11, 0.21, 0.01), sum 0.33.
    let s = t.ml(&[0.5, 0.5, 0.5], 1.0).unwrap();
    let want = [0.11 / 0.33, 0.21 / 0.33, 0.01 / 0.33];
    for (g, w) in s.0.iter().zip(want) {
        assert!((f64::from(*g) - w).abs() < 1e-6, "{s:?} vs {want:?}");
    }
    // On inner edges: car 1.0 opens bin 1 (0.2), cyclist 0.0 opens bin 2 (0.2),
    // pedestrian -2.0 opens bin 2 (0.25). a = (0.21, 0.21, 0.26), sum 0.68.
    let s = t.ml(&[1.0, 0.0, -2.0], 1.0).unwrap();
    assert_eq!(s.0[0], s.0[1], "equal likelihoods give equal scores");
    assert!((f64::from(s.0[2]) - 0.26 / 0.68).abs() < 1e-6, "{s:?}");
    // On the closed last edges: car 4 -> 0.4, cyclist 2 -> 0.1, pedestrian 0 -> 0.25.
    let s = t.ml(&[4.0, 2.0, 0.0], 1.0).unwrap();
    assert!((f64::from(s.0[0]) - 0.41 / 0.78).abs() < 1e-6, "{s:?}");
    // One ulp above them: nothing (zero tail), or the last bins again (clamp).
    let above = [4.0f32.next_up(), 2.0f32.next_up(), 0.0f32.next_up()];
    assert_eq!(t.ml(&above, 1.0).unwrap().0, [1.0 / 3.0; 3]);
    assert_eq!(
        small_clamp().ml(&above, 1.0).unwrap(),
        small_clamp().ml(&[4.0, 2.0, 0.0], 1.0).unwrap()
    );
}

/// The small Bayes heads by hand, with products instead of the layer's sums of logs:
/// `p[c]` is proportional to `pi[c] * prod_j (h[c][j](x_j) + lambda)` (DESIGN §1.6).
#[test]
fn small_bayes_by_hand() {
    // x = (3, 0.5, -3.5): logit 0 in [2, 4] (bin 3), logit 1 in [0, 1) (bin 2), logit 2
    // in [-4, -3) (bin 0). Priors 40, 20, 20, 20 rows of 100; lambda 0.01.
    let car = 0.4 * 0.61 * 0.21 * 0.21; // 0.0107604
    let cyclist = 0.2 * 0.11 * 0.31 * 0.31; // 0.0021142
    let pedestrian = 0.2 * 0.11 * 0.26 * 0.01; // 0.0000572
    let background = 0.2 * 0.21 * 0.31 * 0.11; // 0.0014322
    let total: f64 = car + cyclist + pedestrian + background;
    let s = small_bayes().bayes(&[3.0, 0.5, -3.5], 1.0).unwrap();
    for (got, want) in
        s.0.iter()
            .zip([car / total, cyclist / total, pedestrian / total])
    {
        assert!((f64::from(*got) - want).abs() < GOLDEN_ABS_TOL, "{s:?}");
    }
    assert!((f64::from(s.0[0]) - 0.749_122_8).abs() < 1e-6, "{s:?}");
    // The background share is not a class score: the scores sum to 1 - 0.0997...
    let sum: f64 = s.0.iter().map(|&v| f64::from(v)).sum();
    assert!((sum - (1.0 - background / total)).abs() < 1e-6, "{sum}");
    // Without background (40, 20, 20 rows; lambda 0.001) and at objectness 0.5.
    let car = 0.5 * 0.601 * 0.201 * 0.201;
    let cyclist = 0.25 * 0.101 * 0.301 * 0.301;
    let pedestrian = 0.25 * 0.101 * 0.251 * 0.001;
    let total: f64 = car + cyclist + pedestrian;
    let s = small_bayes_nobg().bayes(&[3.0, 0.5, -3.5], 0.5).unwrap();
    for (got, want) in s.0.iter().zip([car, cyclist, pedestrian]) {
        assert!(
            (f64::from(*got) - 0.5 * want / total).abs() < GOLDEN_ABS_TOL,
            "{s:?}"
        );
    }
}

/// `OS * pi[c]`, the Bayes answer for a detection outside every axis, from the table's
/// row counts (in f64).
fn os_times_prior(rows: &[u64], objectness: f32) -> [f64; 3] {
    let total: u64 = rows.iter().sum();
    std::array::from_fn(|c| f64::from(objectness) * rows[c] as f64 / total as f64)
}

/// DESIGN §1.6: a detection whose every logit is outside its axis gets `OS * pi[c]`;
/// objectness 0 gives exactly 0 everywhere.
#[test]
fn bayes_outside_every_axis_is_os_times_prior() {
    fn run<const BM: usize, const BP: usize, const BB: usize, const C: usize>(
        t: &Table<3, BM, BP, BB, C>,
    ) -> usize {
        let head = t.bayes_head().expect("a Bayes head");
        let rows = head.all_rows().to_vec();
        let inf = f32::INFINITY;
        let below: [f32; 3] = std::array::from_fn(|j| head.axis(j).unwrap().lo().next_down());
        let above: [f32; 3] = std::array::from_fn(|j| head.axis(j).unwrap().hi().next_up());
        let outside = [
            below,
            above,
            [below[0], above[1], below[2]],
            [inf, -inf, inf],
            [-inf; 3],
            [f32::MAX, f32::MIN, 1e30],
        ];
        let mut checked = 0;
        for os in objectness_values() {
            let want = os_times_prior(&rows, os);
            for x in &outside {
                let got = bayes_of(t, x, os).unwrap();
                for (g, w) in got.iter().zip(want) {
                    assert!(
                        (f64::from(*g) - w).abs() <= GOLDEN_ABS_TOL,
                        "{x:?} OS {os}: {got:?}, want {want:?}"
                    );
                }
                if os == 0.0 {
                    assert_eq!(got, [0.0; 3], "{x:?}");
                }
                checked += 1;
            }
        }
        checked
    }
    let n = run(&shipped()) + run(&small_bayes()) + run(&small_bayes_nobg());
    assert_eq!(n, 3 * 6 * objectness_values().len());
}

/// DESIGN §1.6: scores are finite in `[0, OS]`; they sum to `OS` without a background
/// category and to less with one (by the background's share).
#[test]
#[cfg(feature = "invariants")]
fn bayes_scores_sum_to_os_without_background_and_less_with() {
    let rows = goldens(SMALL_CSV)
        .into_iter()
        .chain(goldens(SHIPPED_CSV))
        .filter(|g| g.error.is_none());
    let (with_bg, no_bg, shipped) = (small_bayes(), small_bayes_nobg(), shipped());
    let mut below = 0;
    for g in rows {
        let (x, os) = (g.logits, g.objectness);
        let (got, background) = match g.table.as_str() {
            "small_bayes_nobg" => (bayes_of(&no_bg, &x, os).unwrap(), false),
            "small_bayes" => (bayes_of(&with_bg, &x, os).unwrap(), true),
            "default" => (bayes_of(&shipped, &x, os).unwrap(), true),
            _ => continue,
        };
        let os64 = f64::from(os);
        let sum: f64 = got.iter().map(|&v| f64::from(v)).sum();
        assert!(
            got.iter().all(|&v| v.is_finite() && v >= 0.0 && v <= os),
            "{g:?}"
        );
        // As in the invariant tests: below OS ~ 1e-39 each f32 score carries up to one
        // smallest subnormal of rounding.
        let floor = 3.0 * f64::from(f32::from_bits(1));
        if background {
            assert!(
                sum <= os64 * (1.0 + mlmap::invariants::SUM_RELATIVE_TOLERANCE) + floor,
                "{g:?}: {sum}"
            );
            // Where numpy's background share is visible in f32 (and OS is not so small
            // that rounding is absolute), the sum is below OS.
            let want: f64 = g.bayes.unwrap().iter().sum();
            if os64 - want > 1e-5 * os64 && os >= f32::MIN_POSITIVE {
                assert!(sum < os64, "{g:?}: {sum}");
                below += 1;
            }
        } else {
            assert!(
                (sum - os64).abs() <= mlmap::invariants::SUM_RELATIVE_TOLERANCE * os64 + floor,
                "{g:?}: {sum}"
            );
        }
    }
    assert!(below > 100, "{below} rows with a visible background share");
}
