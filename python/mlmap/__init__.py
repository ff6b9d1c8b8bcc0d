"""mlmap: the ML, MAP, Bayes and open probability layers for object detectors, from
Python.

A table is fitted from training logits (``mlmap.fit``), tuned on validation data
(``mlmap.tune``), saved as a ``.mlmap`` file for the firmware (``Table.save``), and
scores numpy arrays with the device's own ``f32`` code (``Table.ml``, ``Table.map``,
``Table.bayes``, ``Table.open``). ``mlmap.evaluate`` reports every calibration metric of
every method.

The open head (docs/DESIGN.md section 1.8) keeps the detector's own softmax, at a
temperature, and multiplies it by the probability that the detection is an object of a
known class, learnt from the Bayes head's histograms: it ranks and decides as the
detector does. ``mlmap.fit`` writes it untuned (temperature 1, epsilon 0);
``mlmap.tune`` fits both on validation data. Rows that are known not to be objects of
a class (logged false positives, classes the detector must not report) are given as
``background=`` to ``fit``, ``tune``, ``FitStats`` and ``FitCounts``.

Arrays: logits are ``(N, K)`` float32 or float64 (a PyTorch tensor via
``tensor.numpy()``); labels are ``(N,)`` integers, ``0 .. K-1`` a class (the table's
order) and ``-1`` background (a detection that matched no object); objectness is
``None`` (1.0), a number, or an ``(N,)`` float array in ``[0, 1]``. Any layout is
accepted: a C-contiguous, aligned array is read in place, and any other (Fortran order,
strided, reversed or unaligned views, fields of structured arrays, byte-swapped or other
dtypes of the same kind) is copied once, with the same result.

Bad input, an integer setting out of range included, raises ``ValueError`` with the
message the ``mlmap`` command prints for the same fault; a corrupt table raises
``mlmap.TableError``, a ``ValueError``; an argument of the wrong type raises
``TypeError``. A NaN score or logit given to ``decide`` is a ``ValueError``.

The drift monitor (docs/DESIGN.md section 7): ``monitor_fit`` chooses alarm thresholds on
in-distribution rows and returns the table file with its monitor section;
``Monitor.from_bytes(data)`` replays detections in order, one dict per window.

Conformal class sets (docs/DESIGN.md section 8): ``conformal_fit`` fits per-class
thresholds on labelled calibration rows and returns the table file with its conformal
section; ``Table.conformal_sets(logits, objectness)`` gives the ``(N, K)`` boolean sets.

Fitting across processes or machines (docs/SCALE.md): ``FitStats`` (pass a) of every
shard, merged (``+``, ``sum``); its ``edges(...)``; ``FitCounts`` (pass b) of every shard
over those edges, merged; ``finish(stats, counts)``: the bytes ``fit`` gives on all rows.

pandas: ``fit``, ``tune``, ``evaluate`` and ``Calibrator`` take a DataFrame of logits,
whose column names are the class names (``Table.classes``), and labels as class names
(``"background"`` for background rows) as well as integers; an unknown name raises
``ValueError``. pandas itself is optional (never imported by mlmap).

Evaluation in bounded memory: ``Evaluator(table)`` takes rows shard by shard
(``update``), merges (``merge``, ``+``, ``sum()``), pickles (Dask, multiprocessing) and
gives ``evaluate``'s report (``report()``); ``report_frame(report)`` is a report as a
pandas DataFrame (a row per method).

Quantized logits: ``Table.quantized_scores(head, codes, objectness)`` scores int8 or
int16 codes through the table file's quantized section (``mlmap quantize``), as
``mlmap apply --quantized``.

Size: ``fit`` and ``tune`` warn (``TableSizeWarning``) when the table is larger than
``TABLE_SIZE_WARNING`` bytes (1 MiB): the Bayes head grows as ``K * (K + 1)``
histograms; ``bayes=False`` or fewer Bayes bins shrink it.

scikit-learn: ``Calibrator(head="open", ...)`` is an estimator over ``fit`` and ``tune``
(``fit``, ``predict_proba``, ``predict``, ``get_params``, ``set_params``) that goes after a
model in a ``Pipeline``; a pandas DataFrame of logits names the classes by its columns,
and labels may be class names (``"background"`` for background rows).
"""

from . import _mlmap
from ._mlmap import (
    FORMAT_VERSION,
    Evaluator,
    FitCounts,
    FitEdges,
    FitStats,
    Monitor,
    Table,
    TableError,
    decide,
    finish,
    conformal_fit,
    monitor_fit,
)
from ._frames import (
    TABLE_SIZE_WARNING,
    TableSizeWarning,
    accepting_frames as _accepting_frames,
    report_frame,
)
from ._calibrator import Calibrator

# DataFrames and class-name labels (`_frames`); signatures and docstrings stay the
# extension module's.
fit = _accepting_frames(_mlmap.fit)
tune = _accepting_frames(_mlmap.tune)
evaluate = _accepting_frames(_mlmap.evaluate)

__all__ = [
    "Calibrator",
    "Evaluator",
    "FORMAT_VERSION",
    "HEADS",
    "FitCounts",
    "FitEdges",
    "FitStats",
    "Monitor",
    "Table",
    "TableError",
    "TABLE_SIZE_WARNING",
    "TableSizeWarning",
    "decide",
    "evaluate",
    "finish",
    "fit",
    "monitor_fit",
    "conformal_fit",
    "report_frame",
    "tune",
]

__version__ = "0.1.0"

#: The heads a table may hold, by the names ``Table.scores`` and reports use, in the
#: order of ``Table.heads``.
HEADS = ("ml", "map", "bayes", "open")
