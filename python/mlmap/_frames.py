"""pandas DataFrames and class-name labels, for `fit`, `tune`, `evaluate` and
`Calibrator`: the one place that turns them into the arrays the extension module reads.

A DataFrame of logits (anything with ``columns``, ``to_numpy`` and two dimensions) names
the classes by its columns; labels may be class names (``"background"`` for a
background row) as well as integers. pandas is never imported: a DataFrame is
recognised by what it has.
"""

import functools
import inspect
import warnings
from typing import Any, Callable, List, Optional, Sequence, TypeVar

import numpy as np

#: The label of a background row (a detection that matched no object), as class
#: names go.
BACKGROUND = "background"

_F = TypeVar("_F", bound=Callable[..., Any])

#: `fit` and `tune` warn (`TableSizeWarning`) when the table file they return is
#: larger than this many bytes (1 MiB).
TABLE_SIZE_WARNING = 1 << 20


class TableSizeWarning(UserWarning):
    """A fitted table is larger than `mlmap.TABLE_SIZE_WARNING` bytes (1 MiB).

    The Bayes head holds `K * (K + 1)` histograms of `bins` bins per logit (a
    200-class table is about 3.5 MB with it, a 1000-class one about 88 MB); the ML and
    MAP heads `K` histograms each. To shrink the table: `bayes=False` (no Bayes and
    open heads), a Bayes head with fewer bins (`bayes={"bins": 8}`), or fewer
    `bins_ml` / `bins_map`. Silence it with
    `warnings.simplefilter("ignore", mlmap.TableSizeWarning)`.
    """


def warn_if_large(table: Any, stacklevel: int = 3) -> None:
    """Warns (`TableSizeWarning`) when `table`'s file exceeds `TABLE_SIZE_WARNING`."""
    size = getattr(table, "size", 0)
    if size > TABLE_SIZE_WARNING:
        heads = getattr(table, "heads", ())
        hint = (
            "bayes=False (no Bayes or open head) or fewer Bayes bins (bayes={'bins': 8})"
            if "bayes" in heads
            else "fewer bins_ml / bins_map"
        )
        warnings.warn(
            f"the fitted table is {size / 1e6:.1f} MB ({getattr(table, 'k', '?')} classes, "
            f"heads {', '.join(heads)}), above {TABLE_SIZE_WARNING >> 20} MiB; to shrink "
            f"it, fit with {hint}",
            TableSizeWarning,
            stacklevel=stacklevel,
        )


_FRAMES_NOTE = """

A pandas DataFrame of logits (also as `val`, `ood` or `background`) gives the class
names by its columns; labels may be class names, `"background"` for a background row,
as well as integers (an unknown name raises `ValueError`)."""


def is_dataframe(x: Any) -> bool:
    """Whether `x` is a 2-D table with named columns (a pandas DataFrame)."""
    return hasattr(x, "columns") and hasattr(x, "to_numpy") and getattr(x, "ndim", 0) == 2


def columns(x: Any) -> Optional[List[str]]:
    """A DataFrame's column names as strings; `None` for anything else."""
    if not is_dataframe(x):
        return None
    return [str(c) for c in x.columns]


def values(x: Any) -> Any:
    """A DataFrame's values as a numpy array; anything else unchanged."""
    return x.to_numpy() if is_dataframe(x) else x


def class_names(logits: Any, classes: Optional[Sequence[str]], what: str = "logits") -> Optional[List[str]]:
    """The class names of `logits`: its DataFrame columns, `classes`, or `None`
    (neither given). Both given must agree."""
    names = columns(logits)
    if classes is None:
        return names
    given = [str(c) for c in classes]
    if names is not None and names != given:
        raise ValueError(f"classes: {given} differ from the DataFrame's columns {names}")
    return given


def same_columns(x: Any, names: Optional[Sequence[str]], what: str) -> Any:
    """`x`'s values, after checking that a DataFrame's columns are `names` in order."""
    cols = columns(x)
    if cols is not None and names is not None and cols != list(names):
        raise ValueError(f"{what}: the DataFrame's columns {cols} are not the classes {list(names)}")
    return values(x)


def labels(y: Any, n: Optional[int], names: Sequence[str], what: str = "labels") -> Any:
    """`y` with class names turned into class indices (`"background"` into -1).

    Integer labels (and anything but strings or objects) are returned as they are:
    the extension module checks them. An array of strings or objects is mapped through
    `names`, an unknown name being a `ValueError` that lists the known ones.
    """
    if y is None:
        return None
    if is_dataframe(y):
        raise ValueError(f"{what}: expected one label per row, got a 2-D table")
    a = np.asarray(y)
    if a.ndim != 1 or a.dtype.kind not in "USO":
        # Integers (and anything else) go to the extension module as they are: it
        # checks them with the messages of the command line.
        return y
    if n is not None and len(a) != n:
        raise ValueError(f"{what}: has {len(a)} rows but the logits have {n}")
    index = {c: i for i, c in enumerate(names)}
    index.setdefault(BACKGROUND, -1)
    out = np.empty(len(a), dtype=np.int64)
    for i, v in enumerate(a):
        if isinstance(v, (int, np.integer)) and not isinstance(v, (bool, np.bool_)):
            out[i] = int(v)
            continue
        if not isinstance(v, (str, np.str_)) or v not in index:
            raise ValueError(
                f"{what}: row index {i}: label {v!r} is not a class name "
                f"({', '.join(names)}) or {BACKGROUND!r}"
            )
        out[i] = index[v]
    return out


def _default_names(x: Any) -> List[str]:
    shape = np.shape(values(x))
    k = shape[1] if len(shape) == 2 and shape[1] <= 1 << 16 else 0
    return [f"class{i}" for i in range(k)]


def _named(y: Any) -> bool:
    """Whether `y` (labels, or a `(logits, labels, ...)` tuple) holds class names."""
    if isinstance(y, (tuple, list)) and len(y) >= 2 and not np.isscalar(y[0]):
        y = y[1]
    if y is None or is_dataframe(y):
        return False
    try:
        return np.asarray(y).dtype.kind in "USO"
    except Exception:
        return False


def _data_set(obj: Any, names: Optional[Sequence[str]], what: str) -> Any:
    """A `(logits, labels[, objectness])` tuple or bare logits, converted."""
    if isinstance(obj, (tuple, list)) and 1 <= len(obj) <= 3 and (
        is_dataframe(obj[0]) or hasattr(obj[0], "shape")
    ):
        parts = list(obj)
        parts[0] = same_columns(parts[0], names, f"{what}.logits")
        if len(parts) > 1:
            parts[1] = labels(parts[1], None, names or [], f"{what}.labels")
        return tuple(parts)
    return same_columns(obj, names, f"{what}.logits")


def accepting_frames(fn: _F) -> _F:
    """Wraps `fit`, `tune` or `evaluate` of the extension module so that their logits
    may be DataFrames and their labels class names. The signature (`inspect`,
    `help`) and docstring stay those of `fn`."""
    sig = inspect.signature(fn)
    has_table = "table" in sig.parameters

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        bound = sig.bind(*args, **kwargs)
        a = bound.arguments
        x = a.get("logits")
        classes = a.get("classes")
        if has_table:
            table = a.get("table")
            names = class_names(x, classes)
            if names is not None and classes is None:
                a["classes"] = names
            if names is None:
                names = list(getattr(table, "classes", []))
        else:
            names = class_names(x, classes)
            if names is not None:
                a["classes"] = names
        a["logits"] = values(x)
        n = len(a["logits"]) if hasattr(a["logits"], "__len__") else None
        if names is None and any(_named(a.get(key)) for key in ("labels", "val")):
            # Class-name labels of array logits without `classes`: the default names
            # (only then: a shape with absurdly many columns is refused downstream).
            names = _default_names(a["logits"])
        if "labels" in a:
            a["labels"] = labels(a["labels"], n, names or [])
        for key in ("val", "ood"):
            if a.get(key) is not None:
                a[key] = _data_set(a[key], names, key)
        if a.get("background") is not None:
            a["background"] = same_columns(a["background"], names, "background")
        out = fn(*bound.args, **bound.kwargs)
        if not has_table:
            warn_if_large(out[0] if isinstance(out, tuple) else out)
        return out

    wrapper.__doc__ = (fn.__doc__ or "") + _FRAMES_NOTE
    return wrapper  # type: ignore[return-value]


def report_frame(report: Any) -> Any:
    """A pandas DataFrame of a report of `evaluate` or `Evaluator.report`: a row per
    method (index `method`), a column per metric (`ece`, `mce`, ..., `ap_<class>`), an
    undefined metric as NaN. pandas is imported here, and only here."""
    import pandas as pd  # type: ignore[import-untyped]  # the one place mlmap needs pandas

    methods = report["methods"]
    df = pd.DataFrame.from_dict(
        {m: {k: (float("nan") if v is None else v) for k, v in values.items()}
         for m, values in methods.items()},
        orient="index",
    )
    df.index.name = "method"
    return df
