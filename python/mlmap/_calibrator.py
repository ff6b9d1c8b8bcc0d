"""`mlmap.Calibrator`: a scikit-learn estimator over `mlmap.fit` and `mlmap.tune`.

The estimator takes a detector's logits, not raw features: a column per class, in the
order of ``classes_``. It goes after a model in a ``Pipeline`` (a step whose output is
the logits). scikit-learn is optional: without it the estimator keeps the same
``get_params`` / ``set_params`` contract through a small base class.
"""

import inspect
from typing import Dict, Optional, Sequence, Union

import numpy as np

from . import _frames
from ._mlmap import decide, fit as _raw_fit, tune as _raw_tune

_fit = _frames.accepting_frames(_raw_fit)
_tune = _frames.accepting_frames(_raw_tune)

try:  # pragma: no cover - which branch runs depends on the environment
    from sklearn.base import BaseEstimator as _Base, ClassifierMixin as _Mixin  # type: ignore[import-untyped]
    from sklearn.exceptions import NotFittedError as _NotFittedError  # type: ignore[import-untyped]

    _HAVE_SKLEARN = True
except ImportError:  # pragma: no cover
    _HAVE_SKLEARN = False

    class _NotFittedError(ValueError, AttributeError):  # type: ignore[no-redef]
        """The estimator is used before ``fit``."""

    class _Mixin:  # type: ignore[no-redef]
        pass

    class _Base:  # type: ignore[no-redef]
        """``get_params`` / ``set_params`` as scikit-learn's ``BaseEstimator`` gives them:
        the parameters are the constructor's keyword arguments, stored as attributes."""

        @classmethod
        def _get_param_names(cls):
            sig = inspect.signature(cls.__init__)
            return sorted(
                p.name
                for p in sig.parameters.values()
                if p.name != "self" and p.kind == p.POSITIONAL_OR_KEYWORD
            )

        def get_params(self, deep=True):
            return {name: getattr(self, name) for name in self._get_param_names()}

        def set_params(self, **params):
            valid = self._get_param_names()
            for name, value in params.items():
                if name not in valid:
                    raise ValueError(
                        f"Invalid parameter {name!r} for estimator {type(self).__name__}. "
                        f"Valid parameters are: {valid!r}."
                    )
                setattr(self, name, value)
            return self

        def __repr__(self):
            args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
            return f"{type(self).__name__}({args})"


_HEADS = ("ml", "map", "bayes", "open")
BACKGROUND = _frames.BACKGROUND
_is_dataframe = _frames.is_dataframe


def _logits_array(x, what="logits") -> np.ndarray:
    """A 2-D float array of at least two columns, or `ValueError`."""
    if _is_dataframe(x):
        x = x.to_numpy()
    if hasattr(x, "tocsr") or hasattr(x, "todense"):
        raise TypeError(f"{what}: sparse input is not supported: logits are a dense array")
    try:
        a = np.asarray(x)
    except Exception as e:  # ragged lists and the like
        raise ValueError(f"{what}: not an array of numbers: {e}") from None
    if a.dtype.kind == "c":
        raise ValueError(f"{what}: Complex data not supported")
    if a.dtype.kind not in "fiu" or a.dtype.kind == "b":
        raise ValueError(f"{what}: expected numbers, got an array of dtype {a.dtype}")
    if a.ndim != 2:
        raise ValueError(
            f"{what}: expected a 2-D array of shape (N, K) (a logit per class), "
            f"got {a.ndim} dimension(s); Reshape your data"
        )
    if a.shape[1] < 2:
        raise ValueError(
            f"{what}: expected at least 2 columns (a logit per class), got "
            f"{a.shape[1]} feature(s) (shape={a.shape}) while a minimum of 2 is required."
        )
    if a.shape[0] == 0:
        raise ValueError(f"{what}: no rows")
    if a.dtype.kind != "f":
        a = a.astype(np.float64)
    return a


def _objectness(o, n):
    if o is None or np.isscalar(o):
        return o
    a = np.asarray(o)
    if a.ndim != 1 or len(a) != n:
        raise ValueError(f"objectness: expected None, a number or {n} values, got shape {a.shape}")
    return a


class Calibrator(_Mixin, _Base):
    """The mlmap probability layer as a scikit-learn estimator.

    ``fit(logits, y, objectness=None)`` fits a table (``mlmap.fit``; ``mlmap.tune`` on
    a held-out split of the rows when ``tune=True``) and keeps it as ``table_``;
    ``predict_proba`` gives the scores of the chosen head (``Table.scores``: the
    device's own ``f32`` code, bit for bit), ``predict`` the decided class name
    (``mlmap.decide``: the largest score, ties to the larger logit).

    ``logits`` is an ``(N, K)`` array, a logit per class, or a pandas DataFrame whose
    column names are the class names. ``y`` holds integers (``0 .. K-1`` a class,
    ``-1`` background) or class names (``"background"`` for background rows).

    Parameters
    ----------
    head : {"ml", "map", "bayes", "open"}
        The head ``predict_proba`` and ``predict`` use. ``"bayes"`` and ``"open"``
        need ``bayes`` on.
    bins_ml, bins_map, lambda_ml, lambda_map, edges, tail, bayes :
        The settings of ``mlmap.fit`` (ignored when ``tune=True``: the search
        chooses bins and lambdas).
    classes : sequence of str, optional
        Class names, in column order, for array logits (a DataFrame's columns name
        them otherwise; both given must agree). Default ``class0 .. class{K-1}``.
    tune : bool
        Fit with ``mlmap.tune`` (bins, lambdas, the open head's temperature and
        epsilon), holding out ``val_size`` of the rows for validation.
    objective : {"ece", "nll", "brier"}
        ``mlmap.tune``'s objective.
    val_size : float
        The share of rows held out when ``tune=True``, in ``(0, 1)``.
    random_state : int
        The seed of the held-out split.

    Attributes
    ----------
    table_ : mlmap.Table
        The fitted table.
    classes_ : ndarray of str
        Class names, in column order (``table_.classes``).
    n_features_in_ : int
        ``K``, the number of logit columns.
    feature_names_in_ : ndarray of str
        The DataFrame's column names, when ``fit`` was given one.
    tune_report_ : dict
        ``mlmap.tune``'s report, when ``tune=True``.
    """

    def __init__(
        self,
        head: str = "open",
        bins_ml: int = 22,
        bins_map: int = 17,
        bayes: Union[bool, None, Dict[str, Union[int, float]]] = True,
        tune: bool = False,
        lambda_ml: Optional[float] = None,
        lambda_map: Optional[float] = None,
        edges: str = "linspace",
        tail: str = "zero",
        classes: Optional[Sequence[str]] = None,
        objective: str = "ece",
        val_size: float = 0.25,
        random_state: int = 0,
    ):
        self.head = head
        self.bins_ml = bins_ml
        self.bins_map = bins_map
        self.bayes = bayes
        self.tune = tune
        self.lambda_ml = lambda_ml
        self.lambda_map = lambda_map
        self.edges = edges
        self.tail = tail
        self.classes = classes
        self.objective = objective
        self.val_size = val_size
        self.random_state = random_state

    # -- input checking -------------------------------------------------------------

    def _class_names(self, logits, k):
        """The class names of a fit: the DataFrame's columns, `classes`, or None."""
        if self.classes is not None and len(self.classes) != k:
            raise ValueError(f"classes: {len(self.classes)} names for {k} logit columns")
        return _frames.class_names(logits, self.classes)

    def _labels(self, y, n, names):
        """`y` as class indices (-1 background)."""
        if y is None:
            raise ValueError(
                f"{type(self).__name__} requires y to be passed, but the target y is None"
            )
        if _is_dataframe(y):
            raise ValueError("y: expected one label per row, got a 2-D table")
        a = np.asarray(y)
        if a.ndim != 1:
            raise ValueError(f"y: expected a 1-D array of labels, got shape {a.shape}")
        if len(a) != n:
            raise ValueError(f"y: {len(a)} labels for {n} rows of logits")
        if a.dtype.kind in "iu":
            return a.astype(np.int64)
        if a.dtype.kind == "f":
            if not np.all(np.isfinite(a)) or not np.all(a == np.round(a)):
                raise ValueError(
                    "Unknown label type: y: float labels must be whole numbers (class indices)"
                )
            return a.astype(np.int64)
        if a.dtype.kind in "USO":
            return _frames.labels(a, n, names, "y")
        raise ValueError(f"y: expected integers or class names, got dtype {a.dtype}")

    def _check_params(self):
        if self.head not in _HEADS:
            raise ValueError(f"head: {self.head!r} is not one of {', '.join(_HEADS)}")
        if self.head in ("bayes", "open") and self.bayes in (False, None):
            raise ValueError(f"head {self.head!r} needs the Bayes head (bayes=True)")
        if self.tune and not (0.0 < float(self.val_size) < 1.0):
            raise ValueError(f"val_size: {self.val_size!r} is not in (0, 1)")

    # -- the estimator ---------------------------------------------------------------

    def fit(self, logits, y, objectness=None):
        """Fits the table on `(logits, y[, objectness])`; returns `self`."""
        self._check_params()
        x = _logits_array(logits)
        n, k = x.shape
        names = self._class_names(logits, k)
        default = [f"class{i}" for i in range(k)]
        labels = self._labels(y, n, names if names is not None else default)
        obj = _objectness(objectness, n)
        if self.tune:
            rng = np.random.default_rng(self.random_state)
            order = rng.permutation(n)
            n_val = int(round(n * float(self.val_size)))
            if n_val < 1 or n_val >= n:
                raise ValueError(f"val_size: {self.val_size!r} leaves no rows on one side of {n}")
            val, tr = np.sort(order[:n_val]), np.sort(order[n_val:])
            sub = (lambda o, idx: o if o is None or np.isscalar(o) else o[idx])
            val_set = (x[val], labels[val]) if obj is None else (x[val], labels[val], sub(obj, val))
            table, report = _tune(
                x[tr],
                labels[tr],
                val_set,
                sub(obj, tr),
                classes=names,
                objective=self.objective,
                bayes=self.bayes not in (False, None),
                edges=self.edges,
                tail=self.tail,
            )
            self.tune_report_ = report
        else:
            table = _fit(
                x,
                labels,
                obj,
                classes=names,
                bins_ml=self.bins_ml,
                lambda_ml=self.lambda_ml,
                bins_map=self.bins_map,
                lambda_map=self.lambda_map,
                edges=self.edges,
                tail=self.tail,
                bayes=self.bayes,
            )
        self.table_ = table
        self.classes_ = np.array(table.classes, dtype=object)
        self.n_features_in_ = k
        if _is_dataframe(logits):
            self.feature_names_in_ = np.array([str(c) for c in logits.columns], dtype=object)
        elif hasattr(self, "feature_names_in_"):
            del self.feature_names_in_
        return self

    def _check_fitted(self):
        if not hasattr(self, "table_"):
            raise _NotFittedError(
                f"This {type(self).__name__} instance is not fitted yet: call 'fit' first."
            )

    def _test_logits(self, logits):
        self._check_fitted()
        if _is_dataframe(logits) and hasattr(self, "feature_names_in_"):
            cols = [str(c) for c in logits.columns]
            if cols != list(self.feature_names_in_):
                raise ValueError(
                    f"logits: the DataFrame's columns {cols} are not the fitted "
                    f"columns {list(self.feature_names_in_)}"
                )
        x = _logits_array(logits)
        if x.shape[1] != self.n_features_in_:
            raise ValueError(
                f"logits: {x.shape[1]} columns, the calibrator was fitted on "
                f"{self.n_features_in_}"
            )
        return x

    def predict_proba(self, logits, objectness=None) -> np.ndarray:
        """The `(N, K)` float32 scores of the head (`table_.scores(head, ...)`)."""
        x = self._test_logits(logits)
        return self.table_.scores(self.head, x, _objectness(objectness, len(x)))

    def predict(self, logits, objectness=None) -> np.ndarray:
        """The decided class name of every row: the largest score, ties to the larger
        logit (`mlmap.decide`)."""
        x = self._test_logits(logits)
        scores = self.table_.scores(self.head, x, _objectness(objectness, len(x)))
        return self.classes_[decide(scores, x)]

    def score(self, logits, y, objectness=None, sample_weight=None) -> float:
        """The accuracy of `predict` on the rows labelled with a class (background
        rows have no right class and are left out); `y` as in `fit`."""
        x = self._test_logits(logits)
        labels = self._labels(y, len(x), list(self.classes_))
        scores = self.table_.scores(self.head, x, _objectness(objectness, len(x)))
        hit = (decide(scores, x) == labels).astype(np.float64)
        keep = labels >= 0
        if not np.any(keep):
            raise ValueError("y: no row is labelled with a class")
        w = None if sample_weight is None else np.asarray(sample_weight, dtype=np.float64)[keep]
        return float(np.average(hit[keep], weights=w))

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.required = True
        tags.input_tags.allow_nan = False
        return tags


__all__ = ["Calibrator"]
