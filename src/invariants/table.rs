//! Invariant 5 of DESIGN §1.3: the table invariants, for fixed and run-time shaped tables.

use super::*;

/// Invariant 5: both lambdas are in `(0, MAX_LAMBDA]`.
///
/// # Errors
///
/// [`Violation::Lambda`] for the first lambda out of range.
pub fn check_settings(settings: &Settings) -> Result<(), Violation> {
    for (head, lambda) in [
        (Head::Ml, settings.lambda_ml),
        (Head::Map, settings.lambda_map),
    ] {
        if !(lambda > 0.0 && lambda <= MAX_LAMBDA) {
            return Err(Violation::Lambda { head, lambda });
        }
    }
    Ok(())
}

/// Invariant 5: at least two names, each non-empty, at most [`NAME_MAX`] bytes, not
/// `background`, and no name twice.
///
/// # Errors
///
/// [`Violation::ClassCount`], [`Violation::Name`] or [`Violation::DuplicateName`].
pub fn check_names<'a, I>(names: I) -> Result<(), Violation>
where
    I: IntoIterator<Item = &'a str>,
    I::IntoIter: Clone,
{
    let names = names.into_iter();
    let mut count = 0;
    for (class, name) in names.clone().enumerate() {
        count += 1;
        if name.is_empty() || name.len() > NAME_MAX || name == "background" {
            return Err(Violation::Name {
                class,
                len: name.len(),
            });
        }
        if let Some(first) = names.clone().take(class).position(|n| n == name) {
            return Err(Violation::DuplicateName { class, first });
        }
    }
    if count < 2 {
        return Err(Violation::ClassCount {
            expected: 2,
            found: count,
        });
    }
    Ok(())
}

/// Invariant 5: the prior of `class` has a finite mean and a finite positive variance
/// (e.g. `check_prior(i, g.mean(), g.variance())` for a [`Gaussian`](crate::Gaussian)).
///
/// # Errors
///
/// [`Violation::Mean`] or [`Violation::Variance`].
pub fn check_prior(class: usize, mean: f32, variance: f32) -> Result<(), Violation> {
    if !mean.is_finite() {
        return Err(Violation::Mean { class, mean });
    }
    if !(variance.is_finite() && variance > 0.0) {
        return Err(Violation::Variance { class, variance });
    }
    Ok(())
}

/// Invariant 5 for a [`Histogram`]: [`check_bins`] of its edges `e_0 ..= e_B` and its
/// frequencies.
///
/// # Errors
///
/// As [`check_bins`].
pub fn check_histogram<F: AsRef<[f32]>>(
    head: Head,
    class: usize,
    histogram: &Histogram<F>,
    bins: usize,
) -> Result<(), Violation> {
    let edges = (0..=histogram.bins()).map(|k| histogram.edge(k));
    check_bins(head, class, edges, histogram.frequencies(), bins)
}

/// Invariant 5 for the `head` histogram of `class`, given as its edges and frequencies
/// (so that any storage of a histogram can be checked): `bins + 1` edges, finite and
/// strictly increasing; `bins` frequencies, finite and `>= 0`, summing to 1 within
/// [`FREQUENCY_SUM_TOLERANCE`]. The sum is checked twice: in `f32` in bin order (the
/// format's rule), and exactly, where it may differ from the `f32` sum by the rounding
/// of `bins` additions (allowed: `bins * f32::EPSILON`).
///
/// # Errors
///
/// [`Violation::BinCount`] (of the frequencies, or of the edges as `edges - 1`),
/// [`Violation::EdgeNotFinite`], [`Violation::EdgesNotIncreasing`],
/// [`Violation::Frequency`] or [`Violation::FrequencySum`]: the first problem found, in
/// that order.
pub fn check_bins<E: IntoIterator<Item = f32>>(
    head: Head,
    class: usize,
    edges: E,
    frequencies: &[f32],
    bins: usize,
) -> Result<(), Violation> {
    let wrong_count = |found| Violation::BinCount {
        head,
        class,
        expected: bins,
        found,
    };
    if frequencies.len() != bins {
        return Err(wrong_count(frequencies.len()));
    }
    let mut previous = f32::NEG_INFINITY;
    let mut count = 0;
    for (edge, value) in edges.into_iter().enumerate() {
        count += 1;
        if !value.is_finite() {
            return Err(Violation::EdgeNotFinite {
                head,
                class,
                edge,
                value,
            });
        }
        if !(value > previous) {
            return Err(Violation::EdgesNotIncreasing {
                head,
                class,
                edge,
                previous,
                value,
            });
        }
        previous = value;
    }
    if count != bins + 1 {
        return Err(wrong_count(count.saturating_sub(1)));
    }
    let (mut sum32, mut sum64) = (0.0f32, 0.0f64);
    for (bin, &value) in frequencies.iter().enumerate() {
        if !(value.is_finite() && value >= 0.0) {
            return Err(Violation::Frequency {
                head,
                class,
                bin,
                value,
            });
        }
        sum32 += value;
        sum64 += f64::from(value);
    }
    let slack = bins as f64 * f64::from(f32::EPSILON);
    let sum = if !((sum32 - 1.0).abs() <= FREQUENCY_SUM_TOLERANCE) {
        f64::from(sum32)
    } else if !((sum64 - 1.0).abs() <= f64::from(FREQUENCY_SUM_TOLERANCE) + slack) {
        sum64
    } else {
        return Ok(());
    };
    Err(Violation::FrequencySum { head, class, sum })
}

/// Invariant 5 for a fixed-size table: settings, names, and every class's prior and
/// histograms (of `B_ML` and `B_MAP` bins), through the public accessors; and, when the
/// table has a Bayes head, [`check_bayes`] with its shape `B_BAYES` bins and `C`
/// categories.
///
/// # Errors
///
/// The first [`Violation`] of [`check_settings`], [`check_names`], [`check_prior`],
/// [`check_histogram`] or [`check_bayes`]; [`Violation::ClassCount`] when an accessor has
/// no class `i < K`; [`Violation::BayesBins`] or [`Violation::BayesCategories`] when the
/// Bayes head has another shape than `B_BAYES` and `C`.
pub fn check_table<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const B_BAYES: usize,
    const C: usize,
    const N: usize,
    const F: usize,
>(
    table: &Table<K, B_ML, B_MAP, B_BAYES, C, N, F>,
) -> Result<(), Violation> {
    check_settings(table.settings())?;
    let missing = |found| Violation::ClassCount { expected: K, found };
    let names = (0..K).map(|i| table.class_name(i).unwrap_or(""));
    if let Some(found) = (0..K).position(|i| table.class_name(i).is_none()) {
        return Err(missing(found));
    }
    check_names(names)?;
    for class in 0..K {
        let (Some(prior), Some(ml), Some(map)) = (
            table.priors().get(class),
            table.ml_histograms().get(class),
            table.map_histograms().get(class),
        ) else {
            return Err(missing(class));
        };
        check_prior(class, prior.mean(), prior.variance())?;
        check_histogram(Head::Ml, class, ml, B_ML)?;
        check_histogram(Head::Map, class, map, B_MAP)?;
    }
    if let Some(head) = table.bayes_head() {
        check_bayes(&head, K)?;
        if head.bins() != B_BAYES {
            return Err(Violation::BayesBins {
                logit: 0,
                expected: B_BAYES,
                found: head.bins(),
            });
        }
        if head.categories() != C {
            return Err(Violation::BayesCategories {
                classes: K,
                logits: head.logits(),
                categories: head.categories(),
            });
        }
    }
    Ok(())
}

/// Invariant 5 for a run-time shaped table, as [`check_table`] does for a fixed one.
///
/// # Errors
///
/// As [`check_table`]; [`Violation::ClassCount`] when the names, priors or histograms
/// are fewer than [`DynTable::k`](crate::host::DynTable::k).
#[cfg(feature = "std")]
#[cfg_attr(docsrs, doc(cfg(feature = "std")))]
pub fn check_dyn_table(table: &crate::host::DynTable) -> Result<(), Violation> {
    let k = table.k();
    check_settings(table.settings())?;
    for found in [
        table.class_names().len(),
        table.priors().len(),
        table.ml_histograms().len(),
        table.map_histograms().len(),
    ] {
        if found != k {
            return Err(Violation::ClassCount { expected: k, found });
        }
    }
    // `class_names()` cannot be replayed; the names again, through `spec`.
    check_names((0..k).map(|i| table.spec(i).map_or("", |s| s.name)))?;
    let classes = table
        .priors()
        .iter()
        .zip(table.ml_histograms())
        .zip(table.map_histograms());
    for (class, ((prior, ml), map)) in classes.enumerate() {
        check_prior(class, prior.mean(), prior.variance())?;
        check_histogram(Head::Ml, class, ml, table.bins_ml())?;
        check_histogram(Head::Map, class, map, table.bins_map())?;
    }
    if let Some(head) = table.bayes_head() {
        check_bayes(&head, k)?;
    }
    Ok(())
}
