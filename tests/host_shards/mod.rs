//! `mlmap::host::fit`'s mergeable statistics: shards merged in any order and grouping
//! (also through their bytes) give the table of one fit over all rows; the exact sums
//! against a big-integer oracle; the versioned bytes refuse what they must; in-memory
//! rows (`Loaded`) fit like files.

use std::path::{Path, PathBuf};

use mlmap::host::data::Loaded;
use mlmap::host::dataset::{DataErrorKind, DataSource, Label, Row};
use mlmap::host::fit::{
    finish, fit, BayesParams, ClassMoments, FitCounts, FitEdges, FitError, FitParams, FitStats,
    TrainingSet, STATS_FORMAT_VERSION,
};
use mlmap::{EdgeMode, UpperTail};
use num_bigint::BigInt;
use proptest::prelude::*;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn train() -> DataSource {
    DataSource::open(&repo("examples/data/train.csv")).unwrap()
}

/// Rows in memory: classes `c0..c{k-1}`, one `(label, logits)` per row.
fn loaded(k: usize, rows: &[(Label, Vec<f64>)]) -> Loaded {
    Loaded {
        classes: (0..k).map(|c| format!("c{c}")).collect(),
        labels: rows.iter().map(|r| r.0).collect(),
        objectness: vec![1.0; rows.len()],
        logits: rows.iter().flat_map(|r| r.1.iter().copied()).collect(),
        locations: Vec::new(),
        has_labels: true,
        first_missing_label: None,
    }
}

fn row(i: usize, (label, logits): &(Label, Vec<f64>)) -> Row<'_> {
    Row {
        index: i as u64,
        line: None,
        id: None,
        label: *label,
        objectness: 1.0,
        logits,
    }
}

/// Merges `parts` in the order `order`, grouped as a left-leaning fold when `tree` is
/// false, else pairwise (a tree), each merged value passed through its bytes.
fn merge_all<T: Clone>(
    mut parts: Vec<T>,
    order: &[usize],
    tree: bool,
    merge: impl Fn(&mut T, &T),
    through_bytes: impl Fn(&T) -> T,
) -> T {
    let mut ordered: Vec<T> = order.iter().map(|&i| parts[i].clone()).collect();
    parts.clear();
    if tree {
        while ordered.len() > 1 {
            let mut next = Vec::new();
            for pair in ordered.chunks(2) {
                let mut a = through_bytes(&pair[0]);
                if let Some(b) = pair.get(1) {
                    merge(&mut a, b);
                }
                next.push(a);
            }
            ordered = next;
        }
        ordered.pop().unwrap()
    } else {
        let mut acc = ordered.remove(0);
        for p in &ordered {
            merge(&mut acc, &through_bytes(p));
        }
        acc
    }
}

/// A labelled row: a class, background or missing label, and K logits of mixed scales
/// (sums in f64 of such values depend on their order).
fn rows_strategy() -> impl Strategy<Value = (usize, Vec<(Label, Vec<f64>)>)> {
    (2usize..5).prop_flat_map(|k| {
        let logit = prop_oneof![
            -8.0f64..8.0,
            (-1.0f64..1.0).prop_map(|x| 1e7 + x),
            (-1.0f64..1.0).prop_map(|x| x * 1e-9),
        ];
        let label = prop_oneof![
            6 => (0..k).prop_map(Label::Class),
            1 => Just(Label::Background),
            1 => Just(Label::Missing),
        ];
        let one = (label, proptest::collection::vec(logit, k));
        (Just(k), proptest::collection::vec(one, 0..120)).prop_map(|(k, mut rows)| {
            // Every class gets at least one row.
            for c in 0..k {
                rows.push((
                    Label::Class(c),
                    (0..k).map(|j| (c * k + j) as f64 * 0.37).collect(),
                ));
            }
            (k, rows)
        })
    })
}

fn params_strategy() -> impl Strategy<Value = FitParams> {
    (
        1usize..30,
        1usize..30,
        prop::bool::ANY,
        prop::bool::ANY,
        prop::option::of(1usize..30),
    )
        .prop_map(|(bins_ml, bins_map, matlab, clamp, bayes)| FitParams {
            bins_ml,
            bins_map,
            edges: if matlab {
                EdgeMode::Matlab
            } else {
                EdgeMode::Linspace
            },
            upper_tail: if clamp {
                UpperTail::Clamp
            } else {
                UpperTail::Zero
            },
            bayes: bayes.map(|bins| BayesParams {
                bins,
                lambda: 0.01,
                objectness: false,
            }),
            ..FitParams::default()
        })
}

/// Rows given as arrays (the Python package's path): shards in any order, and signed
/// zeros, give the same statistics.
mod arrays;
/// The training data fitted in shards, in one fit and in memory; statistics of other
/// classes, settings or edges refused; the versioned bytes; bad rows in memory.
mod files;
/// Shards of random rows merged in any order and grouping, also through their bytes, give
/// the table of one fit; the exact sums against a big-integer oracle.
mod merges;
