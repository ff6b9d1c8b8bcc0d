//! Fitting the recalibration maps of DESIGN §1.9: for each head of a tuned table, the
//! isotonic regression of "the decision is right" on the head's top score, reduced to at
//! most [`MAX_KNOTS`](mlmap_core::MAX_KNOTS) knots, and kept only where it lowers the
//! validation ECE out of sample (two folds) within the guards.

use super::{accumulate, Judge, ValRows};
use crate::metrics::decision;
use crate::DynTable;
use mlmap_core::{Head, Knot, RecalMap};

/// The smallest value a fitted map takes: a group with no right decision gets it
/// (DESIGN §1.9 keeps every value positive, so that a mapped top score stays the top).
pub const MIN_SHARE: f32 = 1.0e-4;

/// Most groups the top scores are pooled into before the isotonic regression: with a
/// knot at 0 and one at 1, a map has at most 32 knots.
pub const MAP_GROUPS: usize = 30;

/// Fits a map to `(top score, decision right)` points (DESIGN §1.9): the points sorted
/// by score are pooled into at most [`MAP_GROUPS`] groups of about equal size (equal
/// scores stay in one group), the groups' shares of right decisions are made
/// non-decreasing by pool-adjacent-violators weighted by their sizes, and each group
/// gives a knot at its mean score with its pooled share; the first share is repeated at
/// 0 and the last at 1; a share of 0 becomes [`MIN_SHARE`]. `None` without points or
/// with a score outside `[0, 1]`.
pub fn fit_map(points: &[(f32, bool)]) -> Option<Vec<Knot>> {
    if points.is_empty() || points.iter().any(|p| !(0.0..=1.0).contains(&p.0)) {
        return None;
    }
    let mut sorted: Vec<(f32, bool)> = points.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = sorted.len();
    let size = n.div_ceil(MAP_GROUPS);
    // (sum of scores, right decisions, rows) per group.
    let mut groups: Vec<(f64, u64, u64)> = Vec::with_capacity(MAP_GROUPS);
    let mut cur = (0.0f64, 0u64, 0u64);
    for (i, &(x, right)) in sorted.iter().enumerate() {
        cur = (cur.0 + f64::from(x), cur.1 + u64::from(right), cur.2 + 1);
        let next_differs = sorted.get(i + 1).is_none_or(|p| p.0 != x);
        if cur.2 as usize >= size && next_differs {
            groups.push(cur);
            cur = (0.0, 0, 0);
        }
    }
    if cur.2 > 0 {
        groups.push(cur);
    }
    // Pool-adjacent-violators on the groups' shares, compared exactly on counts:
    // (right, rows, groups covered) per block.
    let mut blocks: Vec<(u64, u64, usize)> = Vec::with_capacity(groups.len());
    for &(_, right, rows) in &groups {
        let mut b = (right, rows, 1usize);
        while let Some(&prev) = blocks.last() {
            if u128::from(prev.0) * u128::from(b.1) > u128::from(b.0) * u128::from(prev.1) {
                blocks.pop();
                b = (prev.0 + b.0, prev.1 + b.1, prev.2 + b.2);
            } else {
                break;
            }
        }
        blocks.push(b);
    }
    // A share of 0 becomes MIN_SHARE: a map's values are positive (DESIGN §1.9).
    let shares = blocks
        .iter()
        .flat_map(|&(right, rows, covers)| {
            std::iter::repeat_n((right as f64 / rows as f64) as f32, covers)
        })
        .map(|y| y.clamp(MIN_SHARE, 1.0));
    let mut knots: Vec<Knot> = Vec::with_capacity(MAP_GROUPS + 2);
    for (&(sum, _, rows), y) in groups.iter().zip(shares) {
        let x = ((sum / rows as f64) as f32).clamp(0.0, 1.0);
        match knots.last_mut() {
            // Two groups whose means round to one float: one knot, the later share.
            Some(last) if x <= last.x => last.y = last.y.max(y),
            _ => knots.push(Knot { x, y }),
        }
    }
    let (first, last) = (*knots.first()?, *knots.last()?);
    if first.x > 0.0 {
        knots.insert(0, Knot { x: 0.0, y: first.y });
    } else if let Some(k) = knots.first_mut() {
        k.x = 0.0; // +0.0, never -0.0
    }
    if last.x < 1.0 {
        knots.push(Knot { x: 1.0, y: last.y });
    }
    // Every map this builds follows the rule; a point set that gives one knot only (all
    // scores 0 or all 1) gets the flat map through both ends.
    if knots.len() == 1 {
        let y = knots.first()?.y;
        knots = vec![Knot { x: 0.0, y }, Knot { x: 1.0, y }];
    }
    RecalMap::new(&knots).ok()?;
    Some(knots)
}

/// What `tune` decided for one head's map.
#[derive(Debug, Clone, PartialEq)]
pub struct MapChoice {
    /// The head.
    pub head: Head,
    /// The map fitted on every validation row (and never-seen row), written into the
    /// table when `kept`.
    pub knots: Vec<Knot>,
    /// Whether the table holds the map.
    pub kept: bool,
    /// The head's ECE without a map, each fold scored by a map fitted on the other,
    /// pooled over both folds (rows weighted).
    pub ece_without: f64,
    /// The same with the maps.
    pub ece_with: f64,
    /// How much more accuracy or mAP than the guards allow the head with the map loses
    /// against softmax on every row (0: within the guards).
    pub excess: f64,
    /// The same for the head without the map: a kept map never raises it.
    pub excess_without: f64,
}

/// One head's `(top score, decision right)` on every row, with the table's own scores
/// (maps left out).
fn points(table: &DynTable, head: Head, val: &ValRows<'_>) -> Vec<Option<(f32, bool)>> {
    let k = val.k;
    let cats = table.bayes_head().map_or(k, |b| b.categories()).max(k);
    let (mut s, mut scratch) = (vec![0.0f32; k], vec![0.0f32; cats]);
    let view = table.view().without_maps();
    val.logits
        .chunks_exact(k)
        .zip(val.objectness)
        .zip(val.labels)
        .map(|((x, &os), &label)| {
            view.score_into(head, x, os, &mut s, &mut scratch).ok()?;
            let pred = decision(&s, x);
            Some((s.get(pred).copied()?, label == Some(pred)))
        })
        .collect()
}

/// The rows of `val` whose index has parity `fold`, as owned columns.
struct Fold {
    logits: Vec<f32>,
    objectness: Vec<f32>,
    labels: Vec<Option<usize>>,
}

impl Fold {
    fn new(val: &ValRows<'_>, fold: usize) -> Self {
        let k = val.k;
        let mut f = Self {
            logits: Vec::new(),
            objectness: Vec::new(),
            labels: Vec::new(),
        };
        let rows = val
            .logits
            .chunks_exact(k)
            .zip(val.objectness)
            .zip(val.labels);
        for (i, ((x, &os), &label)) in rows.enumerate() {
            if i % 2 == fold {
                f.logits.extend_from_slice(x);
                f.objectness.push(os);
                f.labels.push(label);
            }
        }
        f
    }

    fn rows(&self, k: usize) -> ValRows<'_> {
        ValRows {
            k,
            logits: &self.logits,
            objectness: &self.objectness,
            labels: &self.labels,
        }
    }
}

/// Fits a map for every head of `table` on the rows of `val` (never-seen rows among
/// them as background, never right) and keeps it where the ECE of two-fold
/// cross-fitting (rows of even and of odd index; each half scored by the map fitted on
/// the other) is lower than without a map and the map, on every row, adds no loss of
/// accuracy or mAP beyond the guards (the head's excess over them does not grow).
/// Returns the table with the kept maps and every decision.
pub fn choose_maps(
    table: DynTable,
    val: &ValRows<'_>,
    judge: &Judge,
) -> (DynTable, Vec<MapChoice>) {
    let k = val.k;
    let mut table = table.without_maps();
    let mut choices = Vec::new();
    let folds = [Fold::new(val, 0), Fold::new(val, 1)];
    for head in [Head::Ml, Head::Map, Head::Bayes, Head::Open] {
        if !table.view().has_head(head) {
            continue;
        }
        let pts = points(&table, head, val);
        let fit = |fold: Option<usize>| -> Option<Vec<Knot>> {
            let picked: Vec<(f32, bool)> = pts
                .iter()
                .enumerate()
                .filter(|(i, _)| fold.is_none_or(|f| i % 2 != f))
                .filter_map(|(_, p)| *p)
                .collect();
            fit_map(&picked)
        };
        let Some(all) = fit(None) else { continue };
        // Pooled out-of-fold ECE without and with the maps.
        let (mut without, mut with, mut rows) = (0.0, 0.0, 0.0);
        let mut usable = true;
        for (f, fold) in folds.iter().enumerate() {
            let fold_rows = fold.rows(k);
            let n = fold.labels.len() as f64;
            let raw = accumulate(&table, head, &fold_rows, judge, false).and_then(|a| a.ece());
            let mapped = fit(Some(f))
                .and_then(|knots| table.clone().with_map(head, knots).ok())
                .and_then(|t| accumulate(&t, head, &fold_rows, judge, false))
                .and_then(|a| a.ece());
            match (raw, mapped) {
                (Some(r), Some(m)) => {
                    without += r * n;
                    with += m * n;
                    rows += n;
                }
                _ if n == 0.0 => {}
                _ => usable = false,
            }
        }
        let Ok(mapped_table) = table.clone().with_map(head, all.clone()) else {
            continue;
        };
        let excess_of = |t: &DynTable| {
            accumulate(t, head, val, judge, false).map_or(f64::INFINITY, |a| {
                judge
                    .guards
                    .excess(a.accuracy(), a.mean_ap(), &judge.reference)
            })
        };
        let (excess, excess_without) = (excess_of(&mapped_table), excess_of(&table));
        let (ece_without, ece_with) = if rows > 0.0 {
            (without / rows, with / rows)
        } else {
            (f64::NAN, f64::NAN)
        };
        // Within the guards: the map adds no loss of accuracy or mAP beyond what the
        // guards allow and the head without it already had.
        let kept = usable && rows > 0.0 && ece_with < ece_without && excess <= excess_without;
        if kept {
            table = mapped_table;
        }
        choices.push(MapChoice {
            head,
            knots: all,
            kept,
            ece_without,
            ece_with,
            excess,
            excess_without,
        });
    }
    (table, choices)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Worked by hand: 4 points, one group each (n < 30), shares 0, 1, 0, 1 pooled by
    /// PAV into 0, 0.5, 0.5, 1; knots at the scores, then the ends.
    #[test]
    fn fit_by_hand() {
        let pts = [(0.2, false), (0.4, true), (0.6, false), (0.8, true)];
        let knots = fit_map(&pts).unwrap();
        let xy: Vec<(f32, f32)> = knots.iter().map(|k| (k.x, k.y)).collect();
        assert_eq!(
            xy,
            [
                (0.0, MIN_SHARE),
                (0.2, MIN_SHARE),
                (0.4, 0.5),
                (0.6, 0.5),
                (0.8, 1.0),
                (1.0, 1.0)
            ]
        );
    }

    /// Ties stay in one group; scores at the ends give no extra knot; at most 32 knots.
    #[test]
    fn groups_and_ends() {
        let mut pts = vec![(0.0, false); 50];
        pts.extend(vec![(1.0, true); 50]);
        let knots = fit_map(&pts).unwrap();
        assert_eq!(
            knots,
            [
                Knot {
                    x: 0.0,
                    y: MIN_SHARE
                },
                Knot { x: 1.0, y: 1.0 }
            ]
        );
        let many: Vec<(f32, bool)> = (0..10_000)
            .map(|i| (i as f32 / 10_000.0, i % 3 == 0))
            .collect();
        let knots = fit_map(&many).unwrap();
        assert!(knots.len() <= mlmap_core::MAX_KNOTS);
        assert!(RecalMap::new(&knots).is_ok());
        assert!(fit_map(&[]).is_none());
        assert!(fit_map(&[(1.5, true)]).is_none());
        let flat = fit_map(&[(0.5, true)]).unwrap();
        assert_eq!(
            flat,
            [
                Knot { x: 0.0, y: 1.0 },
                Knot { x: 0.5, y: 1.0 },
                Knot { x: 1.0, y: 1.0 }
            ]
        );
    }
}
