#!/usr/bin/env python3
"""Independent reference values for mlmap's host metrics and baselines.

Written from docs/DESIGN.md §1.4-§1.5 and §1.7 with numpy, scipy and scikit-learn only; it shares no
code with the Rust crate, so agreement between the two is evidence for both. It builds
small adversarial cases (ties in conf, empty ECE bins, confidences exactly on the bin
edges 0.1 .. 1.0, conf 0 and 1, background rows, a class without positives, a single
row, tied top scores decided by the logits) and one larger random case, computes every metric, and writes inputs and expected
outputs to tests/golden/metrics/, read by tests/metrics_golden.rs.

Regenerate (from the repository root):

    python3 tools/metrics_reference.py

Every metric is computed twice where a library offers it: by scikit-learn
(roc_auc_score, average_precision_score, brier_score_loss, log_loss) and by a direct
numpy transcription of the definition; the script stops if they disagree. Each of the
three ECE bin conventions (DESIGN default, netcal, torchmetrics) is likewise computed by
two different numpy implementations of its rule. The temperature fit is checked by a
dense grid search over log T (no scipy optimiser). The isotonic baseline is
scikit-learn's IsotonicRegression, checked against a plain-Python pool-adjacent-violators
with numpy.interp; ood_auroc and ood_fpr95 are roc_auc_score and roc_curve, checked
against direct counts; the energy score is scipy's logsumexp.

JSON conventions: non-finite floats are the strings "inf" / "-inf"; undefined metrics
are null; a background label is null.
"""
import json
import math
import os
import sys

import numpy as np
import scipy
import sklearn
from scipy.stats import binned_statistic_dd
from scipy.special import logsumexp
from sklearn.isotonic import IsotonicRegression
from sklearn.metrics import (
    average_precision_score,
    brier_score_loss,
    log_loss,
    roc_auc_score,
    roc_curve,
)

OUT_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "golden", "metrics")
NLL_FLOOR = 1e-12
EPS = np.finfo(np.float64).eps


def close(a, b, rel=1e-12, what=""):
    if a is None or b is None:
        assert a is None and b is None, (what, a, b)
        return
    assert abs(a - b) <= rel * max(abs(a), abs(b)) + 1e-15, (what, a, b)


# ---------------------------------------------------------------------------
# ECE bin conventions, each implemented twice.


def design_bins_masks(conf, m):
    """((j-1)/M, j/M] with conf = 0 in the first bin, edges j/M in float64."""
    idx = np.full(conf.shape, -1)
    for j in range(1, m + 1):
        lo, hi = (j - 1) / m, j / m
        inside = (conf > lo) & (conf <= hi)
        if j == 1:
            inside |= conf == 0.0
        idx[inside] = j - 1
    assert (idx >= 0).all()
    return idx


def design_bins_search(conf, m):
    edges = np.arange(m + 1) / m
    return np.minimum(np.searchsorted(edges[1:], conf, side="left"), m - 1)


def netcal_ece_mce(conf, correct, m):
    """netcal's procedure: clip to [eps, 1 - eps], histogramdd / binned_statistic_dd."""
    x = np.clip(conf, EPS, 1.0 - EPS).reshape(-1, 1)
    bounds = [np.linspace(0.0, 1.0, m + 1)]
    counts, _ = np.histogramdd(x, bins=bounds)
    acc, _, _ = binned_statistic_dd(x, correct.astype(float), statistic="mean", bins=bounds)
    cnf, _, _ = binned_statistic_dd(x, conf, statistic="mean", bins=bounds)
    acc, cnf = np.nan_to_num(acc), np.nan_to_num(cnf)
    gap = np.abs(acc - cnf)
    return float(np.sum(gap * counts / len(conf))), float(np.max(gap)), counts.astype(int)


def netcal_bins_digitize(conf, m):
    x = np.clip(conf, EPS, 1.0 - EPS)
    return np.minimum(np.digitize(x, np.linspace(0.0, 1.0, m + 1)) - 1, m - 1)


def torch_edges(m):
    """torch.linspace(0, 1, m + 1) in float32, as torch's CPU kernel computes it."""
    f = np.float32
    steps = m + 1
    step = f(1.0) / f(m)
    half = steps // 2
    return np.array(
        [step * f(i) if i < half else f(1.0) - step * f(steps - i - 1) for i in range(steps)],
        dtype=np.float32,
    )


def torch_bins_bucketize(conf, m):
    # torch.bucketize(x, b, right=True) == numpy.searchsorted(b, x, side="right").
    return np.searchsorted(torch_edges(m), conf.astype(np.float32), side="right") - 1


def torch_bins_masks(conf, m):
    e = torch_edges(m)
    c = conf.astype(np.float32)
    idx = np.full(conf.shape, -1)
    for j in range(m):
        idx[(c >= e[j]) & (c < e[j + 1])] = j
    idx[c >= e[m]] = m
    assert (idx >= 0).all()
    return idx


def ece_mce_from_bins(idx, conf, correct, nbins):
    n = len(conf)
    ece, mce = 0.0, 0.0
    counts = np.zeros(nbins, dtype=int)
    for b in range(nbins):
        sel = idx == b
        counts[b] = sel.sum()
        if counts[b] == 0:
            continue
        gap = abs(correct[sel].mean() - conf[sel].mean())
        ece += counts[b] / n * gap
        mce = max(mce, gap)
    return ece, mce, counts


def calibration(conf, correct, m):
    out = {}
    a = design_bins_masks(conf, m)
    assert (a == design_bins_search(conf, m)).all()
    out["design"] = ece_mce_from_bins(a, conf, correct, m)

    a = netcal_bins_digitize(conf, m)
    e1 = ece_mce_from_bins(a, conf, correct, m)
    e2 = netcal_ece_mce(conf, correct, m)
    assert (e1[2] == e2[2]).all(), (e1[2], e2[2])
    # netcal averages the clipped confidences: equal up to eps.
    close(e1[0], e2[0], 1e-12, "netcal ece")
    close(e1[1], e2[1], 1e-12, "netcal mce")
    out["netcal"] = e1

    a = torch_bins_bucketize(conf, m)
    assert (a == torch_bins_masks(conf, m)).all()
    out["torchmetrics"] = ece_mce_from_bins(a, conf, correct, m + 1)
    return {
        k: {"ece": float(v[0]), "mce": float(v[1]), "counts": [int(c) for c in v[2]]}
        for k, v in out.items()
    }


# ---------------------------------------------------------------------------
# The other metrics.


def decide(scores, logits):
    """DESIGN §1.7: the class of the largest score; among classes whose scores tie at the
    top, the one with the largest logit; the lowest index if those tie too (or without
    logits). numpy.argmax returns the first maximum: the lowest index on ties."""
    top = scores == scores.max(axis=1, keepdims=True)
    if logits is None:
        return np.argmax(top, axis=1)
    assert np.isfinite(logits).all()
    return np.argmax(np.where(top, logits, -np.inf), axis=1)


def decide_loop(scores, logits):
    """The same rule, row by row in plain Python (a second implementation)."""
    out = []
    for r, row in enumerate(scores):
        best = max(row)
        tied = [i for i, v in enumerate(row) if v == best]
        if logits is not None:
            top = max(logits[r][i] for i in tied)
            tied = [i for i in tied if logits[r][i] == top]
        out.append(tied[0])
    return np.array(out, dtype=int)


def auroc_pairs(conf_tp, conf_fp):
    greater = (conf_tp[:, None] > conf_fp[None, :]).sum()
    ties = (conf_tp[:, None] == conf_fp[None, :]).sum()
    return (greater + 0.5 * ties) / (len(conf_tp) * len(conf_fp))


def ap_stepwise(y, s):
    order = np.argsort(-s, kind="stable")
    s, y = s[order], y[order]
    total = y.sum()
    ap, prev_r, tp, seen = 0.0, 0.0, 0, 0
    i = 0
    while i < len(s):
        j = i
        while j < len(s) and s[j] == s[i]:
            j += 1
        tp += int(y[i:j].sum())
        seen += j - i
        r = tp / total
        ap += (r - prev_r) * (tp / seen)
        prev_r = r
        i = j
    return ap


def metrics(scores, labels, k, m, logits=None):
    n = scores.shape[0]
    lab = np.array([-1 if l is None else l for l in labels])
    conf = scores.max(axis=1)
    pred = decide(scores, logits)
    assert (pred == decide_loop(scores, logits)).all()
    assert (conf == scores[np.arange(n), pred]).all()
    correct = (lab >= 0) & (pred == lab)
    out = {"conf": conf.tolist(), "correct": correct.tolist(), "bins": calibration(conf, correct, m)}

    labelled = lab >= 0
    if labelled.any():
        s_label = scores[labelled, lab[labelled]]
        nll = float(np.mean(-np.log(np.maximum(s_label, NLL_FLOOR))))
        rows_sum_to_one = np.allclose(scores[labelled].sum(axis=1), 1.0, rtol=0, atol=1e-15)
        if rows_sum_to_one and s_label.min() >= NLL_FLOOR:
            # log_loss clips at eps and renormalises; on such rows it is our definition.
            ll = log_loss(lab[labelled], scores[labelled], labels=list(range(k)))
            close(nll, ll, 1e-12, "log_loss")
            out["log_loss_checked"] = True
        out["nll"] = nll
    else:
        out["nll"] = None

    y = np.zeros_like(scores)
    y[labelled, lab[labelled]] = 1.0
    brier = float(np.mean(np.sum((scores - y) ** 2, axis=1)))
    per_class = sum(
        brier_score_loss(y[:, c].astype(int), scores[:, c], labels=[0, 1]) for c in range(k)
    )
    close(brier, per_class, 1e-12, "brier")
    out["brier"] = brier

    for name, sel in (("tp", correct), ("fp", ~correct)):
        if sel.any():
            out[name + "_mean"] = float(np.mean(conf[sel]))
            out[name + "_var"] = float(np.var(conf[sel]))  # population (ddof = 0)
        else:
            out[name + "_mean"] = out[name + "_var"] = None

    if correct.any() and (~correct).any():
        auc = float(roc_auc_score(correct.astype(int), conf))
        if n <= 5000:
            close(auc, auroc_pairs(conf[correct], conf[~correct]), 1e-12, "auroc")
        out["auroc"] = auc
    else:
        out["auroc"] = None

    aps = []
    for c in range(k):
        yc = (lab == c).astype(int)
        if yc.sum() == 0:
            aps.append(None)
            continue
        ap = float(average_precision_score(yc, scores[:, c]))
        close(ap, ap_stepwise(yc, scores[:, c]), 1e-12, "ap")
        aps.append(ap)
    out["ap"] = aps

    labelled = lab >= 0
    if labelled.any():
        acc = float(np.mean(pred[labelled] == lab[labelled]))
        close(acc, correct.sum() / labelled.sum(), 1e-15, "accuracy")
        out["accuracy"] = acc
    else:
        out["accuracy"] = None
    return out


def ood(scores):
    conf = scores.max(axis=1)
    return {"ood_mean": float(conf.mean()), "ood_over_0_9": float(np.mean(conf > 0.9))}


# ---------------------------------------------------------------------------
# Baselines and the temperature fit.


def sigmoid(x):
    with np.errstate(over="ignore"):
        e = np.exp(-np.abs(x))
    return np.where(x >= 0, 1.0 / (1.0 + e), e / (1.0 + e))


def softmax_rows(x, t=1.0):
    if np.isfinite(x).all():
        e = np.exp((x - x.max(axis=1, keepdims=True)) / t)
        return e / e.sum(axis=1, keepdims=True)
    out = np.empty_like(x)
    for r, row in enumerate(x):
        top = row.max()
        if np.isinf(top):
            hit = row == top
            out[r] = hit / hit.sum()
        else:
            e = np.exp((row - top) / t)
            out[r] = e / e.sum()
    return out


def mean_nll_at(logits, lab, os_, t):
    s = os_[:, None] * softmax_rows(logits, t)
    return float(np.mean(-np.log(np.maximum(s[np.arange(len(lab)), lab], NLL_FLOOR))))


def grid_fit(logits, labels, os_):
    """Dense grid over ln T in [ln 1e-6, ln 1e6], refined around the best point."""
    lab = np.array([-1 if l is None else l for l in labels])
    keep = lab >= 0
    logits, lab, os_ = logits[keep], lab[keep], os_[keep]
    lo, hi = math.log(1e-6), math.log(1e6)
    grid = np.linspace(lo, hi, 2001)
    for _ in range(7):
        vals = [mean_nll_at(logits, lab, os_, math.exp(u)) for u in grid]
        best = int(np.argmin(vals))
        width = grid[1] - grid[0]
        a, b = max(lo, grid[best] - width), min(hi, grid[best] + width)
        grid = np.linspace(a, b, 201)
    vals = [mean_nll_at(logits, lab, os_, math.exp(u)) for u in grid]
    best = int(np.argmin(vals))
    return math.exp(grid[best]), vals[best]


# ---------------------------------------------------------------------------
# Cases.


def edge_case():
    """Confidences exactly on the edges, their numpy.linspace and float32 neighbours."""
    confs = [j / 10 for j in range(11)]
    confs += [j * 0.1 for j in (3, 6, 7)]  # 0.30000000000000004, 0.6000000000000001, ...
    confs += [float(np.float32(j / 10)) for j in (1, 3, 7, 9)]
    confs += [np.nextafter(j / 10, 0.0) for j in (2, 5, 10)]
    confs += [np.nextafter(j / 10, 1.0) for j in (0, 4, 8)]
    rows, labels = [], []
    for i, c in enumerate(confs):
        rows.append([c, c / 2, c / 4])
        labels.append([0, 1, None][i % 3])
    return "bin_edges", np.array(rows), labels, ["car", "cyclist", "pedestrian"], 10


def ties_case():
    rows = [[0.5, 0.3], [0.5, 0.4], [0.5, 0.5], [0.8, 0.1], [0.8, 0.1], [0.1, 0.8], [0.3, 0.3]]
    labels = [0, 1, 0, 0, None, 1, 1]
    return "ties", np.array(rows), labels, ["a", "b"], 10


def tied_logits_case():
    """The ties case with logits (DESIGN §1.7): row 2 ties at 0.5 and goes to class 1
    (logit 1 > 0), row 6 ties at 0.3 and goes to class 1 (0.9 > 0.2)."""
    _, scores, labels, classes, m = ties_case()
    logits = np.array([[2.0, 1.0], [3.0, 1.0], [0.0, 1.0], [5.0, -1.0], [1.0, 1.0], [-1.0, 2.0],
                       [0.2, 0.9]])
    return "tied_logits", scores, labels, classes, m, logits


def unknown_rows_case():
    """Rows that every histogram calls "I don't know": OS / K for every class, so the
    logits alone decide; some rows tie in the logits too (lowest index)."""
    rng = np.random.default_rng(17)
    n, k = 60, 3
    os_ = np.round(rng.uniform(0.3, 1.0, size=n), 2)
    scores = np.repeat((os_ / k)[:, None], k, axis=1)
    scores[:20] = softmax_rows(rng.normal(size=(20, k)) * 2.0) * os_[:20, None]
    logits = np.round(rng.normal(size=(n, k)) * 3.0, 0)
    lab = rng.integers(-1, k, size=n)
    labels = [None if v < 0 else int(v) for v in lab]
    return "unknown_rows", scores, labels, ["car", "cyclist", "pedestrian"], 10, logits


def empty_bins_case():
    rows = [[0.05, 0.01], [0.95, 0.02], [0.95, 0.0], [0.04, 0.05], [0.96, 0.01]]
    labels = [0, 0, 1, 1, None]
    return "empty_bins", np.array(rows), labels, ["a", "b"], 10


def missing_class_case():
    rng = np.random.default_rng(11)
    x = rng.normal(size=(40, 4)) * 2.0
    scores = softmax_rows(x) * rng.uniform(0.2, 1.0, size=(40, 1))
    # Draws of 3 become background, so class 3 has no positives.
    labels = [None if v == 3 else int(v) for v in rng.integers(0, 4, size=40)]
    return "missing_class", scores, labels, ["car", "cyclist", "pedestrian", "truck"], 10


def zero_one_case():
    rows = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 0.0],
            [0.0, 0.0, 0.0], [0.2, 0.2, 0.6]]
    labels = [0, 0, 0, 2, 1, None, 1]
    return "zero_and_one", np.array(rows), labels, ["a", "b", "c"], 10


def seven_bins_case():
    confs = [j / 7 for j in range(8)] + [float(np.float32(j / 7)) for j in range(1, 7)]
    rows = [[c, 1.0 - c] if c >= 0.5 else [c, c / 3] for c in confs]
    labels = [0, 1, None, 0, 0, 1, 0, 0, 1, 1, 0, None, 0, 1]
    return "seven_bins", np.array(rows), labels, ["a", "b"], 7


def large_case():
    rng = np.random.default_rng(2024)
    n, k = 3000, 3
    logits = rng.normal(size=(n, k)) * rng.uniform(0.5, 4.0, size=(n, 1))
    os_ = rng.uniform(0.3, 1.0, size=(n, 1))
    scores = softmax_rows(logits) * os_
    # Ties: a third of the rows rounded to two decimals.
    tie = rng.uniform(size=n) < 0.33
    scores[tie] = np.round(scores[tie], 2)
    lab = rng.integers(-1, k, size=n)
    labels = [None if v < 0 else int(v) for v in lab]
    # Logits that decide the tied rows: the detector's ranking, rounded to tie at times.
    decided = np.round(logits + rng.normal(size=(n, k)) * 0.1, 1)
    return "large_random", scores, labels, ["car", "cyclist", "pedestrian"], 10, decided


def classifier_case():
    """Objectness 1 softmax scores: log_loss agrees with nll here."""
    rng = np.random.default_rng(5)
    x = rng.normal(size=(60, 3)) * 3.0
    labels = [int(v) for v in rng.integers(0, 3, size=60)]
    return "classifier", softmax_rows(x), labels, ["a", "b", "c"], 10


def metric_cases():
    cases = [
        edge_case(),
        ties_case(),
        tied_logits_case(),
        unknown_rows_case(),
        empty_bins_case(),
        missing_class_case(),
        zero_one_case(),
        seven_bins_case(),
        large_case(),
        classifier_case(),
        ("single_row", np.array([[0.7, 0.2]]), [0], ["a", "b"], 10),
        ("single_background_row", np.array([[0.7, 0.2]]), [None], ["a", "b"], 10),
        ("all_background", np.array([[0.9, 0.1], [0.2, 0.3]]), [None, None], ["a", "b"], 10),
    ]
    out = []
    for name, scores, labels, classes, m, *rest in cases:
        logits = rest[0] if rest else None
        assert ((scores >= 0) & (scores <= 1)).all(), name
        exp = metrics(scores, labels, len(classes), m, logits)
        if name == "classifier":
            assert exp.get("log_loss_checked"), "log_loss cross-check did not run"
        exp.pop("log_loss_checked", None)
        out.append({
            "name": name,
            "classes": classes,
            "bins": m,
            "scores": scores.tolist(),
            "labels": labels,
            **({} if logits is None else {"logits": logits.tolist()}),
            "expected": exp,
        })
    return out


def ood_cases():
    rng = np.random.default_rng(7)
    a = np.array([[0.95, 0.0], [0.9, 0.05], [0.3, 0.2], [np.nextafter(0.9, 1.0), 0.0]])
    b = softmax_rows(rng.normal(size=(500, 3)) * 3.0) * rng.uniform(0.5, 1.0, size=(500, 1))
    return [{"name": n, "scores": s.tolist(), "expected": ood(s)} for n, s in (("small", a), ("random", b))]


def baseline_cases():
    rng = np.random.default_rng(3)
    logits = np.concatenate([
        rng.normal(size=(20, 3)) * 5.0,
        np.array([
            [0.0, 0.0, 0.0],
            [700.0, -700.0, 1e-3],
            [-1e300, 1e300, 0.0],
            [np.inf, 1.0, np.inf],
            [-np.inf, -np.inf, -np.inf],
            [-np.inf, 2.0, -np.inf],
            [40.0, 40.0, -40.0],
        ]),
    ])
    os_ = np.concatenate([rng.uniform(0.0, 1.0, size=20), [1.0, 0.5, 1.0, 0.25, 0.9, 0.0, 1.0]])
    cases = []
    for t in (0.37, 1.0, 2.5):
        with np.errstate(over="ignore", invalid="ignore"):
            sig = os_[:, None] * sigmoid(logits)
            soft = os_[:, None] * softmax_rows(logits)
            temp = os_[:, None] * softmax_rows(logits, t)
        cases.append({
            "t": t,
            "logits": logits.tolist(),
            "objectness": os_.tolist(),
            "sigmoid": sig.tolist(),
            "softmax": soft.tolist(),
            "temperature": temp.tolist(),
        })
    return cases


def temperature_cases():
    out = []
    for name, seed, n, scale, t_true in (
        ("overconfident", 1, 400, 6.0, 3.0),
        ("underconfident", 2, 300, 0.8, 0.5),
        ("outside_first_bracket", 3, 200, 300.0, 700.0),
    ):
        rng = np.random.default_rng(seed)
        logits = rng.normal(size=(n, 3)) * scale
        p = softmax_rows(logits, t_true)
        lab = np.array([rng.choice(3, p=row) for row in p])
        lab[rng.uniform(size=n) < 0.15] = -1  # background rows, ignored by the fit
        labels = [None if v < 0 else int(v) for v in lab]
        os_ = rng.uniform(0.5, 1.0, size=n)
        t, nll = grid_fit(logits, labels, os_)
        out.append({
            "name": name,
            "logits": logits.tolist(),
            "labels": labels,
            "objectness": os_.tolist(),
            "t": t,
            "nll": nll,
        })
    return out


# ---------------------------------------------------------------------------
# Known rows against unseen ones (ood_auroc, ood_fpr95), the isotonic baseline and
# the energy score (DESIGN §1.4, §1.5).


def separation(known, unseen):
    """AUROC and FPR at 95 % TPR of known (positive) against unseen (negative) values,
    by scikit-learn and by a direct count."""
    known, unseen = np.asarray(known, float), np.asarray(unseen, float)
    if len(known) == 0 or len(unseen) == 0:
        return None, None
    y = np.r_[np.ones(len(known)), np.zeros(len(unseen))]
    v = np.r_[known, unseen]
    auroc = float(roc_auc_score(y, v))
    pairs = (known[:, None] > unseen[None, :]).sum() + 0.5 * (known[:, None] == unseen[None, :]).sum()
    close(auroc, float(pairs / (len(known) * len(unseen))), what="auroc pairs")
    fpr, tpr, _ = roc_curve(y, v, drop_intermediate=False)
    fpr95 = float(fpr[np.argmax(tpr >= 0.95)])
    # Directly: the smallest threshold among the known values that keeps 95 % of them.
    for t in np.sort(np.unique(known))[::-1]:
        if (known >= t).mean() >= 0.95:
            direct = float((unseen >= t).mean())
            break
    close(fpr95, direct, what="fpr95 direct")
    return auroc, fpr95


def separation_cases():
    rng = np.random.default_rng(31)
    cases = [
        ("by_hand", [3.0, 1.0, -1.0], [1.0, -2.0]),
        ("twenty_known", list(range(1, 21)), [0.0, 2.0, 5.0, 1.5]),
        ("twenty_one_known", list(range(1, 22)), [0.0, 2.0, 5.0, 1.5]),
        ("one_known", [-3.0], [-3.0, -4.0]),
        ("all_tied", [0.5] * 7, [0.5] * 3),
        ("rounded_scores", list(np.round(rng.beta(5, 2, size=400), 2)),
         list(np.round(rng.beta(2, 3, size=250), 2))),
        ("energies", list(rng.normal(4.0, 2.0, size=300)), list(rng.normal(2.5, 1.5, size=123))),
    ]
    out = []
    for name, known, unseen in cases:
        auroc, fpr95 = separation(known, unseen)
        out.append({"name": name, "known": known, "unseen": unseen,
                    "expected": {"auroc": auroc, "fpr95": fpr95}})
    return out


def pav(x, y):
    """Pool-adjacent-violators in plain Python on (score, 0/1) points, equal scores
    pooled first; the fitted value at each distinct score."""
    order = sorted(range(len(x)), key=lambda i: x[i])
    distinct = []
    for i in order:
        if distinct and distinct[-1][0] == x[i]:
            distinct[-1][1] += y[i]
            distinct[-1][2] += 1
        else:
            distinct.append([x[i], y[i], 1])
    blocks = []
    for _, pos, n in distinct:
        cur = [pos, n, 1]
        while blocks and blocks[-1][0] * cur[1] > cur[0] * blocks[-1][1]:
            p = blocks.pop()
            cur = [p[0] + cur[0], p[1] + cur[1], p[2] + cur[2]]
        blocks.append(cur)
    xs = [d[0] for d in distinct]
    ys = [b[0] / b[1] for b in blocks for _ in range(b[2])]
    return np.array(xs), np.array(ys)


def isotonic_scores(val_logits, val_labels, val_os, logits, os_):
    """Per class c: sklearn's IsotonicRegression of [label = c] on OS * softmax(x)_c over
    the validation rows, applied to OS * softmax(x)_c of the test rows (linear between
    the fitted points, clipped outside them); checked against pav + numpy.interp."""
    lab = np.array([-1 if l is None else l for l in val_labels])
    sv = val_os[:, None] * softmax_rows(val_logits)
    st = os_[:, None] * softmax_rows(logits)
    out = np.empty_like(st)
    for c in range(st.shape[1]):
        target = (lab == c).astype(float)
        ir = IsotonicRegression(increasing=True, out_of_bounds="clip").fit(sv[:, c], target)
        out[:, c] = ir.predict(st[:, c])
        xs, ys = pav(list(sv[:, c]), list((lab == c).astype(int)))
        direct = np.interp(st[:, c], xs, ys)
        for a, b in zip(out[:, c], direct):
            close(float(a), float(b), rel=1e-12, what="isotonic pav")
    return out


def isotonic_cases():
    out = []
    for name, seed, n, scale, ties in (
        ("detector", 41, 300, 3.0, False),
        ("rounded_logits", 42, 200, 2.0, True),
        ("classifier", 43, 150, 4.0, False),
    ):
        rng = np.random.default_rng(seed)
        k = 3
        def draw(m):
            x = rng.normal(size=(m, k)) * scale
            if ties:
                x = np.round(x)
            lab = [int(v) if v >= 0 else None for v in rng.integers(-1, k, size=m)]
            if name == "classifier":
                lab = [int(np.argmax(r + rng.normal(size=k) * scale)) for r in x]
                os_ = np.ones(m)
            else:
                os_ = np.round(rng.uniform(0.2, 1.0, size=m), 3 if not ties else 1)
            return x, lab, os_
        vx, vl, vo = draw(n)
        tx, _, to = draw(n // 2)
        scores = isotonic_scores(vx, vl, vo, tx, to)
        energy = logsumexp(tx, axis=1)
        assert np.allclose(energy, np.log(np.exp(tx).sum(axis=1)), rtol=1e-13)
        out.append({
            "name": name,
            "val_logits": vx.tolist(),
            "val_labels": vl,
            "val_objectness": vo.tolist(),
            "logits": tx.tolist(),
            "objectness": to.tolist(),
            "isotonic": scores.tolist(),
            "negative_energy": energy.tolist(),
        })
    return out


def encode(x):
    if isinstance(x, float):
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        assert not math.isnan(x)
        return x
    if isinstance(x, (np.floating,)):
        return encode(float(x))
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.bool_,)):
        return bool(x)
    if isinstance(x, dict):
        return {k: encode(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [encode(v) for v in x]
    return x


def write(name, cases):
    doc = {
        "generator": "tools/metrics_reference.py",
        "versions": {
            "python": sys.version.split()[0],
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "scikit-learn": sklearn.__version__,
        },
    }
    path = os.path.join(OUT_DIR, name)
    # One case per line: readable diffs without a megabyte of indentation.
    head = json.dumps(doc, allow_nan=False)[:-1]
    lines = [json.dumps(c, allow_nan=False) for c in encode(cases)]
    with open(path, "w") as f:
        f.write(head + ', "cases": [\n' + ",\n".join(lines) + "\n]}\n")
    print("wrote", os.path.relpath(path))


def main():
    os.makedirs(OUT_DIR, exist_ok=True)
    write("metrics.json", metric_cases())
    write("ood.json", ood_cases())
    write("baselines.json", baseline_cases())
    write("temperature.json", temperature_cases())
    write("separation.json", separation_cases())
    write("isotonic.json", isotonic_cases())


if __name__ == "__main__":
    main()
