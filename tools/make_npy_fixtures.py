#!/usr/bin/env python3
"""Writes the small NPY directories under tests/fixtures/ read by tests/host_data/.

They are written by numpy itself, so the tests check that the reader accepts real
numpy output (header padding, dtypes, byte order), not only what the Rust writer emits.

    python3 tools/make_npy_fixtures.py        # rewrites tests/fixtures/npy_*/
"""
import os

import numpy as np

ROOT = os.path.join(os.path.dirname(__file__), "..", "tests", "fixtures")


def write(name, arrays, classes=None):
    d = os.path.join(ROOT, name)
    os.makedirs(d, exist_ok=True)
    for f in os.listdir(d):
        os.remove(os.path.join(d, f))
    for fname, a in arrays.items():
        np.save(os.path.join(d, fname), a)
    if classes is not None:
        with open(os.path.join(d, "classes.txt"), "w") as fh:
            fh.write("".join(c + "\n" for c in classes))


LOGITS = [[4.1, -2.3, -1.7], [1.2, 0.3, -0.4], [-1.0, 2.5, 0.5], [0.25, -0.5, 3.75],
          [2.0, 2.0, 2.0]]

# float32 logits, int16 labels, float64 objectness, class names.
write("npy_small", {
    "logits.npy": np.array(LOGITS, dtype=np.float32),
    "labels.npy": np.array([0, -1, 1, 2, 0], dtype=np.int16),
    "objectness.npy": np.array([0.93, 0.55, 1.0, 0.0, 0.5], dtype=np.float64),
}, classes=["car", "cyclist", "pedestrian"])

# Big-endian float64 logits, uint8 labels, no objectness, default class names.
write("npy_bigendian", {
    "logits.npy": np.array(LOGITS, dtype=">f8"),
    "labels.npy": np.array([0, 1, 2, 1, 0], dtype=np.uint8),
})

# Fortran-ordered logits: refused.
write("npy_fortran", {
    "logits.npy": np.asfortranarray(np.array(LOGITS, dtype=np.float64)),
})
