#!/usr/bin/env python3
"""Reference fit in the `matlab` edge mode, independent of the Rust crate.

The edges follow MATLAB's bin picker for `histcounts(x, nbins)` as described in
host/src/fit.rs (module docs), written here again from that description in plain
Python floats; the histogram counts, moments and encoding reuse tools/mlmap_ref.py.
Used to write the golden table of tests/host_fit.rs:

    python3 tools/matlab_fit_ref.py examples/data/train.csv tests/golden/train_matlab.mlmap
"""
import math
import sys

import numpy as np

import mlmap_ref as ref


def matlab_range(xmin, xmax, nbins):
    """First and last edge of MATLAB's histcounts(x, nbins) for data in [xmin, xmax]."""
    n = float(nbins)
    scale = max(abs(xmin), abs(xmax))
    spread = xmax - xmin
    raw = max(spread / n, math.ulp(scale))  # math.ulp is MATLAB's eps for doubles
    if spread > max(math.sqrt(math.ulp(scale)), sys.float_info.min):
        p = 10.0 ** math.floor(math.log10(raw))
        w0 = p * math.floor(raw / p)
        left = min(w0 * math.floor(xmin / w0), xmin)
        if nbins > 1:
            lo = (xmax - left) / n
            hi = (xmax - left) / (n - 1.0)
            q = 10.0 ** math.floor(math.log10(hi - lo))
            width = q * math.ceil(lo / q)
        else:
            width = w0
        right = max(left + n * width, xmax)
    else:
        unit = max(1.0, math.ceil(n * math.ulp(scale)))
        left = math.floor(2.0 * (xmin - unit / 4.0)) / 2.0
        right = math.ceil(2.0 * (xmax + unit / 4.0)) / 2.0
    return np.float32(left), np.float32(right)


def histogram(v, nbins):
    lo, hi = matlab_range(float(np.min(v)), float(np.max(v)), nbins)
    edges = ref.edges_f32(lo, hi, nbins)
    counts, _ = np.histogram(np.asarray(v, dtype=np.float32), bins=edges)
    assert counts.sum() == len(v)
    return lo, hi, counts / len(v)


def fit(path, bins_ml=22, bins_map=17, lambda_ml=0.0055, lambda_map=0.00012):
    names, labels, x, _ = ref.read_csv(path)
    classes = []
    for c, name in enumerate(names):
        v = x[[lab == name for lab in labels], c]
        ml_lo, ml_hi, ml_f = histogram(v, bins_ml)
        map_lo, map_hi, map_f = histogram(v, bins_map)
        var = max(float(np.var(v, ddof=1)) if len(v) > 1 else 0.0, ref.VARIANCE_FLOOR)
        classes.append(dict(name=name, rows=len(v), mean=float(np.mean(v)), var=var,
                            ml_lo=ml_lo, ml_hi=ml_hi, ml_freqs=ml_f,
                            map_lo=map_lo, map_hi=map_hi, map_freqs=map_f))
    return ref.encode(classes, lambda_ml, lambda_map, edge_mode=1)


def main():
    if len(sys.argv) != 3:
        print(__doc__)
        sys.exit(2)
    # MathWorks' documented example: histcounts([2 3 5 7 11 13 17 19 23 29], 6)
    # has the edges 0, 4.9, ..., 29.4.
    assert np.allclose(matlab_range(2.0, 29.0, 6), (0.0, 29.4))
    with open(sys.argv[2], "wb") as fh:
        fh.write(fit(sys.argv[1]))


if __name__ == "__main__":
    main()
