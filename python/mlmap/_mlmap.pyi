"""Type stubs of the extension module `mlmap._mlmap` (re-exported by `mlmap`)."""

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "FORMAT_VERSION",
    "FitCounts",
    "FitEdges",
    "FitStats",
    "Evaluator",
    "Monitor",
    "Table",
    "TableError",
    "conformal_fit",
    "decide",
    "evaluate",
    "finish",
    "fit",
    "monitor_fit",
    "tune",
]

FORMAT_VERSION: int

_HeadName = Literal["ml", "map", "bayes", "open"]
#: `(N, K)` float logits, or anything `numpy.asarray` turns into such an array. A
#: C-contiguous, aligned float32 or float64 array is read in place; any other layout
#: (Fortran order, strided, reversed or unaligned views, fields of structured arrays,
#: byte-swapped or other float dtypes) is copied once, with the same result.
_Logits = npt.ArrayLike
#: `None` (1.0 for every row), a number, or an `(N,)` float array, in `[0, 1]`.
_Objectness = Union[None, float, npt.ArrayLike]
#: `(N,)` integers of any width and byte order, any layout: `0 .. K-1` a class in the
#: table's order, `-1` background.
_Labels = npt.ArrayLike
#: The bytes of a file: `bytes`, `bytearray`, a `memoryview` or any C-contiguous buffer
#: of single bytes (a numpy `uint8` array); anything else raises `TypeError`.
_Buffer = Union[bytes, bytearray, memoryview, npt.NDArray[np.uint8]]
_PathLike = Union[str, "os.PathLike[str]"]

class TableError(ValueError):
    """A table that does not decode or breaks a table invariant."""

@final
class Table:
    """A fitted mlmap table (any number of classes and bins), immutable.

    Scoring (`ml`, `map`, `bayes`, `open`, `scores`) runs the device's `f32` code on
    every row: the scores are bit for bit those of the firmware and of `mlmap apply`.

    A file with a quantized section (`mlmap quantize`) keeps it: the section is checked,
    described by `quantized`, and written back unchanged by `to_bytes`, `save` and
    pickling; scoring runs the float table.
    """

    @staticmethod
    def from_bytes(data: _Buffer) -> "Table":
        """Decodes the bytes of a `.mlmap` file (a quantized section is checked and
        kept); raises `TableError` when invalid, `TypeError` for a non-buffer or a
        non-contiguous buffer."""
    def to_bytes(self) -> bytes:
        """The file's bytes (the `.mlmap` file format): the table, then its quantized
        section when it was read with one."""
    @staticmethod
    def load(path: _PathLike) -> "Table":
        """Reads a `.mlmap` file, keeping a quantized section (`FileNotFoundError`,
        `TableError`, ...)."""
    def save(self, path: _PathLike) -> None:
        """Writes the file (with its quantized section, if any), through a temporary
        file renamed into place."""
    @property
    def classes(self) -> List[str]:
        """Class names, in column order."""
    @property
    def k(self) -> int:
        """Number of classes."""
    @property
    def heads(self) -> Tuple[str, ...]:
        """`("ml", "map")`, `("ml", "map", "bayes")` or `("ml", "map", "bayes", "open")`
        (format version 3)."""
    @property
    def bins_ml(self) -> int: ...
    @property
    def bins_map(self) -> int: ...
    @property
    def bins_bayes(self) -> Optional[int]:
        """Bins per logit of the Bayes head; `None` without that head."""
    @property
    def lambda_ml(self) -> float: ...
    @property
    def lambda_map(self) -> float: ...
    @property
    def lambda_bayes(self) -> Optional[float]: ...
    @property
    def open_params(self) -> Optional[Dict[str, float]]:
        """The open head's `{"temperature": T, "epsilon": epsilon}` (the stored `f32`
        values); `None` without that head (a version-1 or version-2 table)."""
    @property
    def edges(self) -> Literal["linspace", "matlab"]: ...
    @property
    def upper_tail(self) -> Literal["zero", "clamp"]: ...
    @property
    def training_rows(self) -> List[int]:
        """Training rows per class (the fit's provenance)."""
    @property
    def categories(self) -> Optional[List[str]]:
        """The Bayes head's categories (classes, then `"background"` if learnt)."""
    @property
    def priors(self) -> List[Tuple[float, float]]:
        """`(mean, variance)` of the MAP head's Gaussian prior, per class."""
    @property
    def size(self) -> int:
        """`len(to_bytes())`: the encoded table and its quantized section, if any."""
    @property
    def quantized(self) -> Optional[Dict[str, Any]]:
        """The quantized section the table was read with: `None`, or `{"bits": 8 or 16,
        "size": bytes, "heads": ("ml", "map"[, "bayes"])}`."""
    @property
    def conformal(self) -> Optional[Dict[str, Any]]:
        """The conformal section (docs/DESIGN.md section 8): `None`, or `{"head", "alpha",
        "thresholds", "calibration_rows"}`."""
    def conformal_sets(
        self, logits: _Logits, objectness: _Objectness = None
    ) -> npt.NDArray[np.bool_]:
        """The `(N, K)` conformal sets: `True` where the class is in the row's set."""
    def histogram(
        self, head: Literal["ml", "map"], cls: Union[int, str]
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """`(edges, frequencies)` of a class's histogram: `B + 1` edges, `B` values.
        A class index outside `0 .. K-1`, or the head `"bayes"` or `"open"` (no
        per-class histogram), raises `ValueError`."""
    def ml(self, logits: _Logits, objectness: _Objectness = None) -> npt.NDArray[np.float32]:
        """`(N, K)` ML scores; each row sums to its objectness (before the head's
        recalibration map, if the table holds one: see `recal_map`)."""
    def map(self, logits: _Logits, objectness: _Objectness = None) -> npt.NDArray[np.float32]:
        """`(N, K)` MAP scores; each row sums to its objectness."""
    def bayes(self, logits: _Logits, objectness: _Objectness = None) -> npt.NDArray[np.float32]:
        """`(N, K)` Bayes scores; each row sums to at most its objectness. A table
        without that head raises `ValueError`."""
    def open(self, logits: _Logits, objectness: _Objectness = None) -> npt.NDArray[np.float32]:
        """`(N, K)` open-head scores, `OS * q * softmax(logits / T)`: the detector's
        softmax at the table's temperature times the probability `q` that the
        detection is of a known class; each row sums to at most its objectness and
        ranks the classes as the logits do. A table without that head (version 1 or
        2) raises `ValueError`."""
    def scores(
        self, head: _HeadName, logits: _Logits, objectness: _Objectness = None
    ) -> npt.NDArray[np.float32]:
        """The scores of `head`, as `ml`."""
    def quantized_scores(
        self, head: _HeadName, codes: npt.ArrayLike, objectness: _Objectness = None
    ) -> npt.NDArray[np.float32]:
        """`(N, K)` float32 scores of `head` for integer logit codes (int8 for an 8-bit
        section, int16 for a 16-bit one, or any integer array of codes in range),
        through the table's quantized section (`mlmap quantize`): those of `mlmap apply
        --quantized`, bit for bit. No section, a head the section lacks or a code out
        of range raise `ValueError`; a non-integer array `TypeError`."""
    def recal_map(self, head: _HeadName) -> Optional[List[Tuple[float, float]]]:
        """The recalibration map of `head` as its knots `(x, y)`, or `None` when the
        table holds none for it. Every scoring method applies it: the head's top
        score `t` becomes `g(t)` and the other scores keep their ratios to it (a row
        then no longer sums to its objectness)."""
    def without_maps(self) -> "Table":
        """The same table without recalibration maps: every head's own scores. A
        quantized section is not kept."""
    def __eq__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> Tuple[Any, Tuple[bytes]]: ...

def decide(scores: npt.ArrayLike, logits: _Logits) -> npt.NDArray[np.int64]:
    """The decided class of every row: the largest score, ties to the larger logit.
    A NaN score or logit raises `ValueError` (no class can be said to win)."""

def evaluate(
    table: Table,
    logits: _Logits,
    labels: _Labels,
    objectness: _Objectness = None,
    *,
    val: Optional[Sequence[Any]] = None,
    ood: Optional[Union[_Logits, Sequence[Any]]] = None,
    ece_bins: int = 10,
    ece_binning: Literal["design", "default", "netcal", "torchmetrics"] = "design",
    classes: Optional[Sequence[str]] = None,
    group_by: Optional[Sequence[Any]] = None,
) -> Dict[str, Any]:
    """Every metric of every method, as `mlmap eval --format json` reports them.
    `ece_bins` outside `1 .. 2**20` raises `ValueError`. `group_by` (one value per test
    row, taken by `str()`) adds the metrics per value under `"groups"`, as
    `mlmap eval --group-by`."""

@final
class Evaluator:
    """The metrics of `evaluate` for every method, accumulated shard by shard in
    bounded memory: `update` rows, `merge` (or `+`, `sum()`) evaluators of shards in
    any order, pickle them (Dask, multiprocessing), and `report()`.

    Methods: sigmoid, softmax, temperature (with `temperature=T`) and the table's
    heads. `ece`, `mce`, `nll`, `brier`, `accuracy`, `tp_*` and `fp_*` equal
    `evaluate`'s up to the order of floating-point additions; `auroc` and
    `ap_<class>` count scores within `1 / rank_levels` of each other as tied. Memory:
    per method `(K + 1) * (rank_levels + 1)` pairs of counts.
    """

    def __new__(
        cls,
        table: Table,
        *,
        ece_bins: int = 10,
        ece_binning: Literal["design", "default", "netcal", "torchmetrics"] = "design",
        temperature: Optional[float] = None,
        rank_levels: int = 65536,
    ) -> "Evaluator": ...
    def update(self, logits: _Logits, labels: _Labels, objectness: _Objectness = None) -> None:
        """Adds rows (checked as `evaluate` checks them; an empty shard adds nothing)."""
    def merge(self, other: "Evaluator") -> "Evaluator":
        """A new evaluator holding the rows of both."""
    def __add__(self, other: Union["Evaluator", int], /) -> "Evaluator": ...
    def __radd__(self, other: Union["Evaluator", int], /) -> "Evaluator": ...
    @property
    def rows(self) -> int:
        """Rows added."""
    def report(self) -> Dict[str, Any]:
        """`evaluate`'s dict for the rows added (`"methods"`, `"rows"`, `"classes"`,
        `"ece_bins"`, `"ece_binning"`, `"rank_levels"`); no rows raise `ValueError`."""
    def to_bytes(self) -> bytes:
        """The state as bytes (the table, the settings, every count and sum)."""
    @staticmethod
    def from_bytes(data: _Buffer) -> "Evaluator":
        """Reads `to_bytes`'s output; anything else raises `ValueError`."""
    def __reduce__(self) -> Tuple[Any, Tuple[bytes]]: ...

#: The `bayes` keyword: `True` (the default head: 22 bins, lambda 1e-3), `False` or
#: `None` (no Bayes head), or `{"bins": int, "lambda": float}`.
_BayesSetting = Union[bool, None, Dict[str, Union[int, float]]]

def fit(
    logits: _Logits,
    labels: _Labels,
    objectness: _Objectness = None,
    *,
    background: Optional[_Logits] = None,
    classes: Optional[Sequence[str]] = None,
    bins_ml: int = 22,
    lambda_ml: Optional[float] = None,
    bins_map: int = 17,
    lambda_map: Optional[float] = None,
    edges: Literal["linspace", "matlab"] = "linspace",
    tail: Literal["zero", "clamp"] = "zero",
    bayes: _BayesSetting = True,
) -> Table:
    """Fits a table (the bytes `mlmap fit` writes on the same rows). `background` is
    an `(N_b, K)` float array of more rows taken as background whatever they are (the
    rows of `mlmap fit --background FILE`): they enter only the Bayes head's
    `background` category, and so the open head. With the Bayes head the table holds
    the untuned open head (temperature 1, epsilon 0). Lambdas default to 0.0055 (ML)
    and 0.00012 (MAP); classes to `class0` .. `class{K-1}`. A bin count outside
    `1 .. 65535` (negative ones too) raises `ValueError`."""

def tune(
    logits: _Logits,
    labels: _Labels,
    val: Sequence[Any],
    objectness: _Objectness = None,
    *,
    ood: Optional[Union[_Logits, Sequence[Any]]] = None,
    background: Optional[_Logits] = None,
    classes: Optional[Sequence[str]] = None,
    objective: Literal["ece", "nll", "brier"] = "ece",
    bins_ml: Optional[Sequence[int]] = None,
    bins_map: Optional[Sequence[int]] = None,
    bins_bayes: Optional[Sequence[int]] = None,
    bayes: bool = True,
    lambda_min: float = 1e-8,
    lambda_max: float = 1.0,
    lambdas_per_decade: int = 3,
    lambda_bayes_min: Optional[float] = None,
    lambda_bayes_max: Optional[float] = None,
    max_accuracy_loss: float = 0.005,
    max_map_loss: float = 0.01,
    edges: Literal["linspace", "matlab"] = "linspace",
    tail: Literal["zero", "clamp"] = "zero",
    top: int = 5,
    maps: bool = True,
    objectness_feature: bool = False,
) -> Tuple[Table, Dict[str, Any]]:
    """Searches bins (default 4..40 per head) and lambdas on `val=(logits, labels[,
    objectness])`; returns the table and the report of `mlmap tune --format json`.
    With the Bayes head it also tunes the open head: the temperature by NLL on the
    labelled validation rows, then epsilon on `mlmap tune`'s grid (the report's
    `"open"` candidates and `validation.methods.open` give both). `ood` joins the
    validation rows as never-seen objects; `background` takes more training rows as
    background, as in `fit`. Bin counts outside `1 .. 65535`, `lambdas_per_decade`
    outside `1 .. 1000`, a negative `top` and a grid of too many candidates raise
    `ValueError`. `maps=True` fits a recalibration map per head, kept where it lowers
    the cross-fitted ECE within the guards; the report's `"maps"` gives each head's
    verdict (`kept`, `cv_ece_without`, `cv_ece_with`, `within_guards`, `knots`).
    `maps=False` fits none and the report has no `"maps"`."""

@final
class FitStats:
    """Pass (a) of a fit over some rows; merges exactly (`merge`, `+`, `sum`), pickles."""

    def __new__(
        cls,
        logits: _Logits,
        labels: _Labels,
        objectness: _Objectness = None,
        *,
        classes: Optional[Sequence[str]] = None,
        background: Optional[_Logits] = None,
    ) -> "FitStats":
        """The statistics of the rows, and of the rows `background` takes as background
        (as `fit` takes them)."""
    @classmethod
    def empty(cls, classes: Sequence[str]) -> "FitStats": ...
    @property
    def classes(self) -> List[str]: ...
    @property
    def rows(self) -> int: ...
    @property
    def class_rows(self) -> List[int]: ...
    def edges(
        self,
        *,
        bins_ml: int = 22,
        lambda_ml: Optional[float] = None,
        bins_map: int = 17,
        lambda_map: Optional[float] = None,
        edges: Literal["linspace", "matlab"] = "linspace",
        tail: Literal["zero", "clamp"] = "zero",
        bayes: _BayesSetting = True,
    ) -> "FitEdges":
        """The edges pass (b) counts against, for a fit with these settings."""
    def finish(self, counts: "FitCounts") -> Table: ...
    def merge(self, other: "FitStats") -> "FitStats": ...
    def __add__(self, other: Union["FitStats", int], /) -> "FitStats": ...
    def __radd__(self, other: Union["FitStats", int], /) -> "FitStats": ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(data: _Buffer) -> "FitStats": ...
    def __eq__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...

@final
class FitEdges:
    """The edges of every histogram and the fit settings; pickles."""

    @property
    def classes(self) -> List[str]: ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(data: _Buffer) -> "FitEdges": ...
    def __eq__(self, other: object, /) -> bool: ...

@final
class FitCounts:
    """Pass (b) of a fit over some rows; merges by addition, pickles."""

    def __new__(
        cls,
        edges: FitEdges,
        logits: _Logits,
        labels: _Labels,
        objectness: _Objectness = None,
        *,
        background: Optional[_Logits] = None,
    ) -> "FitCounts":
        """The counts of the rows over `edges`, and of the rows `background` takes as
        background (give a shard the same rows as for its `FitStats`)."""
    @classmethod
    def empty(cls, edges: FitEdges) -> "FitCounts": ...
    @property
    def rows(self) -> int: ...
    def merge(self, other: "FitCounts") -> "FitCounts": ...
    def __add__(self, other: Union["FitCounts", int], /) -> "FitCounts": ...
    def __radd__(self, other: Union["FitCounts", int], /) -> "FitCounts": ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(data: _Buffer) -> "FitCounts": ...
    def __eq__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...

def finish(stats: FitStats, counts: FitCounts) -> Table:
    """The table of merged statistics and merged counts of the same rows."""

@final
class Monitor:
    """A drift monitor (docs/DESIGN.md section 7) over a table file's monitor section."""

    @staticmethod
    def from_bytes(data: bytes | bytearray | memoryview, window: int | None = None) -> Monitor: ...
    @staticmethod
    def load(path: str | os.PathLike[str], window: int | None = None) -> Monitor: ...
    @property
    def window(self) -> int: ...
    @property
    def alpha(self) -> float: ...
    @property
    def thresholds(self) -> dict[str, float]: ...
    @property
    def fitted(self) -> bool: ...
    def push(
        self, logits: npt.ArrayLike, objectness: npt.ArrayLike | float | None = None
    ) -> list[dict[str, Any]]: ...
    def finish(self) -> dict[str, Any] | None: ...
    def to_bytes(self) -> bytes: ...

def monitor_fit(
    table: Table,
    logits: npt.ArrayLike,
    objectness: npt.ArrayLike | float | None = None,
    *,
    window: int,
    false_alarm: float,
    windows: int = 2000,
    seed: int = 0,
) -> bytes: ...

def conformal_fit(
    table: Table,
    logits: _Logits,
    labels: _Labels,
    objectness: _Objectness = None,
    *,
    alpha: float,
    head: Literal["ml", "map", "bayes", "open"] = "map",
) -> bytes: ...
