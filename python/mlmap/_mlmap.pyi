"""Type stubs of the extension module `mlmap._mlmap` (re-exported by `mlmap`)."""

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

FORMAT_VERSION: int

HeadName = Literal["ml", "map", "bayes"]
#: `(N, K)` float32 or float64 logits (any memory order), or anything `numpy.asarray`
#: turns into such an array.
Logits = npt.ArrayLike
#: `None` (1.0 for every row), a number, or an `(N,)` float array, in `[0, 1]`.
Objectness = Union[None, float, npt.ArrayLike]
#: `(N,)` integers: `0 .. K-1` a class in the table's order, `-1` background.
Labels = npt.ArrayLike
PathLike = Union[str, "os.PathLike[str]"]

class TableError(ValueError):
    """A table that does not decode or breaks a table invariant."""

class Table:
    """A fitted mlmap table (any number of classes and bins), immutable.

    Scoring runs the device's `f32` code on every row: the scores are bit for bit those
    of the firmware and of `mlmap apply`.
    """

    @staticmethod
    def from_bytes(data: Union[bytes, bytearray]) -> "Table":
        """Decodes the bytes of a `.mlmap` file; raises `TableError` when invalid."""
    def to_bytes(self) -> bytes:
        """The table's bytes (the `.mlmap` file format)."""
    @staticmethod
    def load(path: PathLike) -> "Table":
        """Reads a `.mlmap` file (`FileNotFoundError`, `TableError`, ...)."""
    def save(self, path: PathLike) -> None:
        """Writes the table, through a temporary file renamed into place."""
    @property
    def classes(self) -> List[str]:
        """Class names, in column order."""
    @property
    def k(self) -> int:
        """Number of classes."""
    @property
    def heads(self) -> Tuple[str, ...]:
        """`("ml", "map")` or `("ml", "map", "bayes")`."""
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
        """Size of the encoded table in bytes."""
    def histogram(
        self, head: Literal["ml", "map"], cls: Union[int, str]
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """`(edges, frequencies)` of a class's histogram: `B + 1` edges, `B` values."""
    def ml(self, logits: Logits, objectness: Objectness = None) -> npt.NDArray[np.float32]:
        """`(N, K)` ML scores; each row sums to its objectness."""
    def map(self, logits: Logits, objectness: Objectness = None) -> npt.NDArray[np.float32]:
        """`(N, K)` MAP scores; each row sums to its objectness."""
    def bayes(self, logits: Logits, objectness: Objectness = None) -> npt.NDArray[np.float32]:
        """`(N, K)` Bayes scores; each row sums to at most its objectness."""
    def scores(
        self, head: HeadName, logits: Logits, objectness: Objectness = None
    ) -> npt.NDArray[np.float32]:
        """The scores of `head`, as `ml`."""
    def __eq__(self, other: object) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> Tuple[Any, Tuple[bytes]]: ...

def decide(scores: npt.ArrayLike, logits: Logits) -> npt.NDArray[np.int64]:
    """The decided class of every row: the largest score, ties to the larger logit."""

def evaluate(
    table: Table,
    logits: Logits,
    labels: Labels,
    objectness: Objectness = None,
    *,
    val: Optional[Sequence[Any]] = None,
    ood: Optional[Union[Logits, Sequence[Any]]] = None,
    ece_bins: int = 10,
    ece_binning: Literal["design", "default", "netcal", "torchmetrics"] = "design",
    classes: Optional[Sequence[str]] = None,
) -> Dict[str, Any]:
    """Every metric of every method, as `mlmap eval --format json` reports them."""
