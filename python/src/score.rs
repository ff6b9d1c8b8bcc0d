//! Scoring many rows through the layer, in parallel over chunks of rows, with no
//! Python object in reach (so it runs with the GIL released).

use mlmap::host::DynTable;
use mlmap::{Head, InferError};
use rayon::prelude::*;

use crate::arrays::{Column, Rows};

/// Rows per parallel task: large enough that a task costs far more than its
/// scheduling, small enough that two cores share the work evenly.
const CHUNK_ROWS: usize = 16_384;

/// Below this many rows the work stays on the calling thread.
const PARALLEL_MIN_ROWS: usize = 4 * CHUNK_ROWS;

/// Where scoring stopped: the first row the layer refused, and why.
#[derive(Debug, Clone, Copy)]
pub struct RowError {
    /// Row index.
    pub row: usize,
    /// The layer's error.
    pub error: InferError,
}

/// Scores the rows of `logits` (exactly as many as `out` holds, rows `first..` of the
/// whole arrays) into `out`.
fn score_chunk(
    table: &DynTable,
    head: Head,
    logits: Rows<'_>,
    objectness: Column<'_>,
    k: usize,
    first: usize,
    out: &mut [f32],
) -> Result<(), RowError> {
    let view = table.view();
    let cats = table.bayes_head().map_or(k, |b| b.categories().max(k));
    let mut scratch = vec![0f32; cats];
    let mut x = vec![0f32; k];
    let mut one = |i: usize, xs: &[f32], s: &mut [f32]| {
        let row = first + i;
        let os = objectness.get_f32(row);
        view.score_into(head, xs, os, s, &mut scratch)
            .map_err(|error| RowError { row, error })
    };
    let rows = out.chunks_exact_mut(k);
    match logits {
        Rows::F32(all) => {
            for (i, (s, xs)) in rows.zip(all.chunks_exact(k)).enumerate() {
                one(i, xs, s)?;
            }
        }
        Rows::F64(all) => {
            for (i, (s, src)) in rows.zip(all.chunks_exact(k)).enumerate() {
                for (d, &v) in x.iter_mut().zip(src) {
                    *d = v as f32;
                }
                one(i, &x, s)?;
            }
        }
    }
    Ok(())
}

/// The `N x K` scores of `head` for every row, row-major, computed on the rayon pool
/// for large inputs. The first error is the one of the lowest row, as a serial loop
/// would report.
///
/// # Errors
///
/// The first row the layer refuses (a NaN logit, a bad objectness),
/// [`InferError::NoBayesHead`] or [`InferError::NoOpenHead`].
pub fn score(
    table: &DynTable,
    head: Head,
    logits: Rows<'_>,
    objectness: Column<'_>,
    n: usize,
) -> Result<Vec<f32>, RowError> {
    let k = table.k();
    if head == Head::Bayes && table.bayes_head().is_none() {
        return Err(RowError {
            row: 0,
            error: InferError::NoBayesHead,
        });
    }
    if head == Head::Open && table.open_params().is_none() {
        return Err(RowError {
            row: 0,
            error: InferError::NoOpenHead,
        });
    }
    // One logit and one objectness per row and class, or nothing is scored.
    let values = n.checked_mul(k).filter(|&v| k > 0 && v == logits.len());
    let Some(values) = values.filter(|_| objectness.covers(n)) else {
        return Err(RowError {
            row: 0,
            error: InferError::Length,
        });
    };
    let mut out = vec![0f32; values];
    if n < PARALLEL_MIN_ROWS || rayon::current_num_threads() < 2 {
        score_chunk(table, head, logits, objectness, k, 0, &mut out)?;
        return Ok(out);
    }
    let pieces = logits.pieces(CHUNK_ROWS * k);
    let results: Vec<Result<(), RowError>> = out
        .par_chunks_mut(CHUNK_ROWS * k)
        .zip(pieces)
        .enumerate()
        .map(|(c, (chunk, x))| score_chunk(table, head, x, objectness, k, c * CHUNK_ROWS, chunk))
        .collect();
    // Chunks are in row order, and each stops at its first error.
    results.into_iter().collect::<Result<(), RowError>>()?;
    Ok(out)
}
