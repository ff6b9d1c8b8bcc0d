#!/usr/bin/env python3
"""An independent numpy implementation of mlmap's conformal class sets (docs/DESIGN.md
section 8) and of the LAC baseline it is compared with.

It shares no code with the Rust crate: the table is decoded by tools/mlmap_ref.py, each
head's scores are computed there in float64 (from the logits rounded to float32, as the
layer reads them), and

* t_c = the floor((n_c + 1) alpha)-th smallest score of class c over the n_c calibration
  rows labelled c (alpha rounded to float32 first), -inf when that rank is 0;
* a row's set = {c : s_c >= t_c};
* LAC: p = OS * softmax(z) (the logits as read, float64); qhat = the ceil((n + 1)(1 - alpha))-th smallest 1 - p_y over
  every row labelled with a class (+inf past n); set = {c : 1 - p_c <= qhat}.

    python3 tools/conformal_ref.py goldens tests/golden/conformal

writes the goldens the Rust tests compare with (tests/conformal/), and a CSV of the
sets of a few detections for the C tests and the firmware.
"""
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mlmap_ref  # noqa: E402

HEADS = {"ml": mlmap_ref.ml, "map": mlmap_ref.map_, "bayes": mlmap_ref.bayes,
         "open": mlmap_ref.open_}


def read(path, names):
    cols, labels, x, os_ = mlmap_ref.read_csv(path)
    assert cols == names, (cols, names)
    raw = (x, os_)
    x = x.astype(np.float32).astype(np.float64)
    os_ = os_.astype(np.float32).astype(np.float64)
    y = np.array([names.index(l) if l in names else -1 for l in labels])
    return x, os_, y, raw


def scores(t, head, x, os_):
    f = HEADS[head]
    return np.array([f(t, row, o) for row, o in zip(x, os_)])


def rank(n, alpha):
    return int(math.floor((n + 1) * float(np.float32(alpha))))


def thresholds(s, y, k, alpha):
    out = []
    for c in range(k):
        v = np.sort(s[y == c, c])
        r = rank(len(v), alpha)
        out.append((len(v), -math.inf if r == 0 else float(v[r - 1])))
    return out


def sets(s, t):
    return s >= np.array([tc for _, tc in t])[None, :]


def softmax_os(x, os_):
    z = x - x.max(axis=1, keepdims=True)
    e = np.exp(z)
    return os_[:, None] * e / e.sum(axis=1, keepdims=True)


def lac_qhat(p, y, alpha):
    s = np.sort(1.0 - p[y >= 0, y[y >= 0]])
    n = len(s)
    r = math.ceil((n + 1) * (1.0 - alpha))
    return (math.inf if r > n else float(s[r - 1])), n


def coverage(in_set, y, k, unseen=None):
    known = y >= 0
    per = [float(in_set[y == c, c].mean()) for c in range(k)]
    size = in_set[known].sum(axis=1)
    out = dict(coverage=per, rows=[int((y == c).sum()) for c in range(k)],
               mean_size=float(size.mean()), empty_known=float((size == 0).mean()))
    if unseen is not None:
        out["empty_unseen"] = float((unseen.sum(axis=1) == 0).mean())
    return out


def goldens(outdir, table_path="tables/default.mlmap"):
    os.makedirs(outdir, exist_ok=True)
    t = mlmap_ref.decode(open(table_path, "rb").read())
    names = [c["name"] for c in t["classes"]]
    k = len(names)
    val = read("examples/data/val.csv", names)
    test = read("examples/data/test.csv", names)
    ood = read("examples/data/ood.csv", names)
    # A subset of the test and unseen rows keeps the goldens small; the coverage below
    # is over every row.
    n_test, n_ood = 300, 150
    out = dict(numpy=np.__version__, table=table_path, val="examples/data/val.csv",
               test="examples/data/test.csv", ood="examples/data/ood.csv",
               test_rows=n_test, ood_rows=n_ood, cases=[])
    for head in ("map", "open", "ml", "bayes"):
        s_val = scores(t, head, *val[:2])
        s_test = scores(t, head, *test[:2])
        s_ood = scores(t, head, *ood[:2])
        for alpha in (0.1, 0.05):
            th = thresholds(s_val, val[2], k, alpha)
            tv = np.array([tc for _, tc in th])
            case = dict(head=head, alpha=alpha, rows=[n for n, _ in th],
                        thresholds=[None if math.isinf(v) else v for _, v in th],
                        test_sets=sets(s_test[:n_test], th).astype(int).tolist(),
                        test_margin=[float(f"{v:.3g}") for v in np.abs(s_test[:n_test] - tv).min(axis=1)],
                        ood_sets=sets(s_ood[:n_ood], th).astype(int).tolist(),
                        ood_margin=[float(f"{v:.3g}") for v in np.abs(s_ood[:n_ood] - tv).min(axis=1)],
                        eval=coverage(sets(s_test, th), test[2], k, sets(s_ood, th)))
            out["cases"].append(case)
    # The softmax baseline reads the logits in float64, as the host does.
    p_val, p_test, p_ood = (softmax_os(*d[3]) for d in (val, test, ood))
    lac = []
    for alpha in (0.1, 0.05):
        # LAC is fitted at the section's alpha, which is stored as float32.
        a = float(np.float32(alpha))
        q, n = lac_qhat(p_val, val[2], a)
        lac.append(dict(alpha=alpha, qhat=q, rows=n,
                        eval=coverage(1.0 - p_test <= q, test[2], k, 1.0 - p_ood <= q)))
    out["lac"] = lac
    with open(os.path.join(outdir, "reference.json"), "w") as fh:
        json.dump(out, fh, indent=1)
    # The sets of a few detections for the C tests and the firmware: the open head at
    # alpha 0.1, the first 12 test rows.
    case = next(c for c in out["cases"] if c["head"] == "open" and c["alpha"] == 0.1)
    with open(os.path.join(outdir, "sets_open_0.1.csv"), "w") as fh:
        fh.write(f"# tools/conformal_ref.py, numpy {np.__version__}: {table_path}, open head, "
                 "alpha 0.1 fitted on examples/data/val.csv; rows of examples/data/test.csv\n")
        fh.write("row,mask,margin," + ",".join(f"t_{n}" for n in names) + "\n")
        for i in range(12):
            mask = sum(b << c for c, b in enumerate(case["test_sets"][i]))
            fh.write(f"{i},{mask},{case['test_margin'][i]!r},"
                     + ",".join(repr(v) for v in case["thresholds"]) + "\n")


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "goldens":
        goldens(sys.argv[2])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
