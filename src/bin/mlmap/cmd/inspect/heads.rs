//! The Bayes head and its objectness feature, as text and as JSON.

use super::*;

/// The name of Bayes category `c`: a class name, or `background` (index K).
fn category_name<'a>(names: &[&'a str], c: usize) -> &'a str {
    names.get(c).copied().unwrap_or("background")
}

/// The frequencies of category `c`, logit `j` recovered from the stored log-terms:
/// `exp(t) - lambda`, never below 0.
fn bayes_frequencies(b: &BayesView<'_>, c: usize, j: usize) -> Vec<f32> {
    let lambda = f64::from(b.lambda());
    (0..b.bins())
        .map(|bin| {
            b.term(c, j, bin)
                .map_or(0.0, |t| (f64::from(t).exp() - lambda).max(0.0) as f32)
        })
        .collect()
}

/// The share of the training rows in each Bayes category.
fn prior_shares(b: &BayesView<'_>) -> Vec<f64> {
    let total: u64 = b.all_rows().iter().sum();
    b.all_rows()
        .iter()
        .map(|&n| n as f64 / total.max(1) as f64)
        .collect()
}

/// The Bayes head in text: settings, categories, axes, and a sparkline per category
/// and logit.
pub(super) fn bayes_text(s: &mut String, b: &BayesView<'_>, names: &[&str], bins: bool) {
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "Bayes head  {} bins per logit, lambda {:e}, {} categories{}",
        b.bins(),
        b.lambda(),
        b.categories(),
        if b.has_background() {
            " (the classes and background)"
        } else {
            ""
        }
    );
    let _ = writeln!(s, "{:<12} {:>10} {:>11}", "category", "rows", "prior");
    for (c, (rows, share)) in b.all_rows().iter().zip(prior_shares(b)).enumerate() {
        let _ = writeln!(
            s,
            "{:<12} {rows:>10} {share:>11.5}",
            category_name(names, c)
        );
    }
    let _ = writeln!(s, "axes (bins of each logit over every training row)");
    for (j, axis) in b.axes().iter().enumerate() {
        let _ = writeln!(
            s,
            "  logit {:<12} [{:>9.4}, {:>9.4}]",
            category_name(names, j),
            axis.lo(),
            axis.hi()
        );
    }
    let _ = writeln!(s, "frequencies per category and logit (sparkline)");
    for c in 0..b.categories() {
        for (j, axis) in b.axes().iter().enumerate() {
            let freqs = bayes_frequencies(b, c, j);
            let _ = writeln!(
                s,
                "  {:<12} {:<12} |{}|",
                category_name(names, c),
                category_name(names, j),
                sparkline(&freqs)
            );
            if bins {
                for (k, f) in freqs.iter().enumerate() {
                    let close = if k + 1 == axis.bins() { ']' } else { ')' };
                    let _ = writeln!(
                        s,
                        "         bin {k:>3}  [{:>10.5}, {:>10.5}{close}  {f:.6}",
                        axis.edge(k),
                        axis.edge(k + 1)
                    );
                }
            }
        }
    }
    if let Some(axis) = b.objectness_axis() {
        let _ = writeln!(
            s,
            "objectness feature (DESIGN §1.6): the objectness logit ln(OS) - ln(1 - OS), \
             clamped into [{:.4}, {:.4}]",
            axis.lo(),
            axis.hi()
        );
        for c in 0..b.categories() {
            let freqs = objectness_frequencies(b, c);
            let _ = writeln!(
                s,
                "  {:<12} {:<12} |{}|",
                category_name(names, c),
                "objectness",
                sparkline(&freqs)
            );
        }
    }
}

/// The frequencies of category `c`'s histogram of the objectness logit:
/// `exp(term) - lambda` of each bin (the feature's terms are bin-major, then category).
fn objectness_frequencies(b: &BayesView<'_>, c: usize) -> Vec<f32> {
    let cats = b.categories();
    b.objectness_terms()
        .iter()
        .skip(c)
        .step_by(cats.max(1))
        .map(|&t| (t.exp() - b.lambda()).max(0.0))
        .collect()
}

/// The Bayes head in JSON.
pub(super) fn bayes_json(b: &BayesView<'_>, names: &[&str]) -> serde_json::Value {
    let axes: Vec<serde_json::Value> = b
        .axes()
        .iter()
        .enumerate()
        .map(|(j, a)| {
            let edges: Vec<f32> = (0..=a.bins()).map(|k| a.edge(k)).collect();
            serde_json::json!({ "logit": category_name(names, j), "edges": edges })
        })
        .collect();
    let categories: Vec<serde_json::Value> = b
        .all_rows()
        .iter()
        .zip(prior_shares(b))
        .enumerate()
        .map(|(c, (rows, share))| {
            let freqs: Vec<Vec<f32>> = (0..b.logits())
                .map(|j| bayes_frequencies(b, c, j))
                .collect();
            serde_json::json!({
                "name": category_name(names, c),
                "rows": rows,
                "prior": share,
                "frequencies": freqs,
            })
        })
        .collect();
    serde_json::json!({
        "bins": b.bins(),
        "lambda": b.lambda(),
        "background": b.has_background(),
        "axes": axes,
        "categories": categories,
        "objectness_feature": b.objectness_axis().map(|a| {
            let edges: Vec<f32> = (0..=a.bins()).map(|k| a.edge(k)).collect();
            let freqs: Vec<Vec<f32>> = (0..b.categories())
                .map(|c| objectness_frequencies(b, c))
                .collect();
            serde_json::json!({ "edges": edges, "frequencies": freqs })
        }),
    })
}
