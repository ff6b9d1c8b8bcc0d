//! The `const` constructors that the source of a table embedded at build time calls
//! (docs/DESIGN.md §5, way 2). Not part of the API: they only assemble fields that this
//! crate's own validation computed (see `embed_source.rs`).

use crate::math::histogram::{Axis, Histogram};
use crate::quantized::qtable::{Code, Meta, QClass, QLogit, QTable};
use crate::{ClassName, Gaussian, Knot, OpenParams, Settings, Table};

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
    const N: usize,
    const F: usize,
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
    bayes_open: Option<OpenParams>,
    recal: [[Knot; N]; 4],
    recal_len: [u8; 4],
    bayes_os_axis: [Axis; F],
    bayes_os_terms: [[[f32; C]; B_BAYES]; F],
) -> Table<K, B_ML, B_MAP, B_BAYES, C, N, F> {
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
        bayes_open,
        recal,
        recal_len,
        bayes_os_axis,
        bayes_os_terms,
        extent: (),
    }
}

/// A knot of a recalibration map as validated by the build script.
pub const fn knot(x: f32, y: f32) -> Knot {
    Knot { x, y }
}

/// The open head's parameters as validated by the build script.
pub const fn open(temperature: f32, epsilon: f32, log_unknown: f32) -> Option<OpenParams> {
    Some(OpenParams {
        temperature,
        epsilon,
        log_unknown,
    })
}

/// `len` bytes of `bytes` from `at`: a part of an embedded quantized section (a
/// compile-time error if out of range; the build script only names validated parts).
pub const fn part(bytes: &'static [u8], at: usize, len: usize) -> &'static [u8] {
    bytes.split_at(at).1.split_at(len).0
}

/// `n` 4-byte values of bytes from `at`: a part of an embedded quantized section.
pub const fn part4(bytes: &'static [u8], at: usize, n: usize) -> &'static [[u8; 4]] {
    part(bytes, at, 4 * n).as_chunks::<4>().0
}

/// `n` 8-byte knots of bytes from `at`: a map of an embedded quantized section.
pub const fn part8(bytes: &'static [u8], at: usize, n: usize) -> &'static [[u8; 8]] {
    part(bytes, at, 8 * n).as_chunks::<8>().0
}

/// A quantized section's header fields, validated by the build script.
#[allow(clippy::too_many_arguments)]
pub const fn qmeta(
    bits: u8,
    k: u16,
    bins_ml: u16,
    bins_bayes: u16,
    categories: u16,
    table_crc: u32,
    lambdas: [f32; 3],
    log_prior: &'static [[u8; 4]],
    open: Option<OpenParams>,
    maps: [&'static [[u8; 8]]; 4],
    objectness: Option<(Axis, &'static [[u8; 4]])>,
    len: usize,
) -> Meta<'static> {
    Meta {
        bits,
        k,
        bins_ml,
        bins_bayes,
        categories,
        table_crc,
        lambda_ml: lambdas[0],
        lambda_map: lambdas[1],
        log_lambda: lambdas[2],
        log_prior,
        open,
        maps,
        objectness,
        len,
    }
}

/// One class of a quantized section, validated by the build script.
pub const fn qclass(
    scale: f32,
    zero_point: i32,
    ml: (i32, &'static [u8], &'static [[u8; 4]]),
    map: (i32, &'static [[u8; 4]]),
) -> QClass<'static> {
    QClass {
        scale,
        zero_point,
        ml_start: ml.0,
        ml_index: ml.1,
        ml_masses: ml.2,
        map_start: map.0,
        map_masses: map.1,
    }
}

/// One Bayes logit of a quantized section, validated by the build script.
pub const fn qlogit(
    start: i32,
    index: &'static [u8],
    terms: &'static [[u8; 4]],
) -> QLogit<'static> {
    QLogit {
        start,
        index,
        terms,
    }
}

/// The logit of an embedded section without the Bayes head.
pub const QLOGIT_NONE: QLogit<'static> = QLogit::EMPTY;

/// A quantized table from validated parts.
pub const fn qtable<const K: usize, Q: Code>(
    meta: Meta<'static>,
    classes: [QClass<'static>; K],
    logits: [QLogit<'static>; K],
) -> QTable<'static, K, Q> {
    QTable {
        meta,
        classes,
        logits,
        code: core::marker::PhantomData,
    }
}
