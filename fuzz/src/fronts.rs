//! Every front of one head on one detection gives `Table`'s bits: the run-time shaped
//! `DynTable` (default backend and backend `M`), the views' `score_into` (the head's
//! default backend, as the CLI, Python and C use it) and the batch calls, with the same
//! error when the detection is invalid.

use super::*;

/// The scores as bits, or the error.
type Bits<const K: usize> = Result<[u32; K], InferError>;

fn bits<const K: usize>(r: Result<[f32; K], InferError>) -> Bits<K> {
    r.map(|s| s.map(f32::to_bits))
}

/// One detection through `DynTable`'s method of `head` with backend `M`.
fn dyn_with<M: Backend, const K: usize>(
    dynt: &DynTable,
    head: Head,
    x: &[f32; K],
    objectness: f32,
) -> Result<[f32; K], InferError> {
    let mut out = [0.0f32; K];
    let mut scratch = vec![0.0f32; K + 1];
    match head {
        Head::Ml => dynt.ml_into(x, objectness, &mut out, &mut scratch[..K]),
        Head::Map => dynt.map_into::<M>(x, objectness, &mut out, &mut scratch[..K]),
        Head::Bayes | Head::Open => {
            let c = dynt.bayes_head().map_or(K, |b| b.categories());
            let s = &mut scratch[..c];
            if head == Head::Bayes {
                dynt.bayes_into::<M>(x, objectness, &mut out, s)
            } else {
                dynt.open_into::<M>(x, objectness, &mut out, s)
            }
        }
    }
    .map(|()| out)
}

/// One detection through a view's `score_into` (the head's default backend).
fn view_score<F: AsRef<[f32]>, G: AsRef<[f32]>, const K: usize>(
    view: &mlmap::TableView<'_, F, G>,
    head: Head,
    x: &[f32; K],
    objectness: f32,
) -> Result<[f32; K], InferError> {
    let (mut out, mut scratch) = ([0.0f32; K], vec![0.0f32; K + 1]);
    view.score_into(head, x, objectness, &mut out, &mut scratch)
        .map(|()| out)
}

/// A table's batch call of one head, as a closure (a table type without a Bayes head
/// has no Bayes or open batch call to name).
pub(crate) type BatchCall<'t, const K: usize> =
    &'t dyn Fn(&[[f32; K]], Option<&[f32]>, &mut [[f32; K]]) -> Result<(), BatchError>;

/// The second row of a two-row batch of `x` through `call`, a row error as the
/// detection's error.
fn batch<const K: usize>(
    call: BatchCall<'_, K>,
    x: &[f32; K],
    objectness: f32,
) -> Result<[f32; K], InferError> {
    let mut out = [[0.0f32; K]; 2];
    match call(&[*x, *x], Some(&[objectness, objectness]), &mut out) {
        Ok(()) => Ok(out[1]),
        Err(BatchError::Row { index: 0, error }) => Err(error),
        Err(other) => panic!("batch: not the first row's error: {other:?}"),
    }
}

/// Checks that every front of `head` gives, for detection `x`, the bits (or the error)
/// of `Table`'s method: `default` with the head's default backend, `with_m` with backend
/// `M` (for the ML head, which has no backend, both are `Table::ml`). `batch_call` is the
/// head's batch call, `batch_m` its call with backend `M` where the table has one.
#[allow(clippy::too_many_arguments)]
pub(crate) fn check_fronts<
    M: Backend,
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    dynt: &DynTable,
    head: Head,
    x: &[f32; K],
    objectness: f32,
    default: &Result<Scores<K>, InferError>,
    with_m: &Result<Scores<K>, InferError>,
    batch_call: BatchCall<'_, K>,
    batch_m: Option<BatchCall<'_, K>>,
    what: impl Display,
) {
    let want = bits(default.as_ref().map(|s| s.0).map_err(|e| *e));
    let want_m = bits(with_m.as_ref().map(|s| s.0).map_err(|e| *e));
    let fronts = [
        (
            "Table::view().score_into",
            want,
            view_score(&t.view(), head, x, objectness),
        ),
        (
            "DynTable::view().score_into",
            want,
            view_score(&dynt.view(), head, x, objectness),
        ),
        (
            "DynTable with the backend",
            want_m,
            dyn_with::<M, K>(dynt, head, x, objectness),
        ),
        ("batch", want, batch(batch_call, x, objectness)),
    ];
    for (front, want, got) in fronts {
        assert_eq!(bits(got), want, "{what}: {head:?} {front} differs");
    }
    if let Some(call) = batch_m {
        let got = batch(call, x, objectness);
        assert_eq!(
            bits(got),
            want_m,
            "{what}: {head:?} batch with the backend differs"
        );
    }
}
