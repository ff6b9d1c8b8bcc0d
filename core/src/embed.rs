//! The `const` constructors that the source of a table embedded at build time calls
//! (docs/DESIGN.md §5, way 2). Not part of the API: they only assemble fields that this
//! crate's own validation computed (see `embed_source.rs`).

use crate::histogram::{Axis, Histogram};
use crate::{ClassName, Gaussian, Settings, Table};

/// A histogram from validated fields.
pub const fn histogram<F>(lo: f32, hi: f32, width: f32, inv_width: f32, freqs: F) -> Histogram<F> {
    Histogram {
        lo,
        hi,
        width,
        inv_width,
        freqs,
    }
}

/// A prior from validated fields.
pub const fn gaussian(mean: f32, var: f32, neg_half_inv_var: f32, norm: f32) -> Gaussian {
    Gaussian {
        mean,
        var,
        neg_half_inv_var,
        norm,
    }
}

/// A class name from its stored bytes.
pub const fn class_name(len: u8, bytes: [u8; crate::NAME_MAX]) -> ClassName {
    ClassName { len, bytes }
}

/// A Bayes axis from validated fields.
pub const fn axis(lo: f32, hi: f32, width: f32, inv_width: f32, bins: u16, cap: f32) -> Axis {
    Axis {
        lo,
        hi,
        width,
        inv_width,
        bins,
        cap,
    }
}

/// A table from validated parts.
#[allow(clippy::too_many_arguments)]
pub const fn table<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const B_BAYES: usize,
    const C: usize,
>(
    names: [ClassName; K],
    rows: [u64; K],
    priors: [Gaussian; K],
    ml: [Histogram<[f32; B_ML]>; K],
    map: [Histogram<[f32; B_MAP]>; K],
    settings: Settings,
    bayes_axes: [Axis; K],
    bayes_terms: [[[f32; C]; B_BAYES]; K],
    bayes_rows: [u64; C],
    bayes_log_prior: [f32; C],
    bayes_lambda: f32,
    bayes_log_lambda: f32,
) -> Table<K, B_ML, B_MAP, B_BAYES, C> {
    Table {
        names,
        rows,
        priors,
        ml,
        map,
        settings,
        bayes_axes,
        bayes_terms,
        bayes_rows,
        bayes_log_prior,
        bayes_lambda,
        bayes_log_lambda,
    }
}
