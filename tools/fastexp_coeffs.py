#!/usr/bin/env python3
"""Coefficients of the polynomial in `FastMath`'s `exp` (core/src/math/fastmath.rs).

The minimax polynomial of degree N (default 5) for `e^r` on `|r| <= ln(2)/2`, widened by
1e-4 relative for the rounding of the reduction, in *relative* error, found with the
Remez exchange algorithm at 40 significant digits (mpmath), then rounded to float32:

    python3 tools/fastexp_coeffs.py [N]

Prints the coefficients C0..CN (as float32 literals) and the approximation's largest
relative error before and after that rounding. The error of the whole `exp` (reduction,
rounding of every operation) is measured exhaustively by the test `exp_exhaustive`.
"""
import struct
import sys

import mpmath as mp

mp.mp.dps = 40


def f32(x):
    return struct.unpack("f", struct.pack("f", float(x)))[0]


def rel_err(c, x):
    return (mp.polyval(c[::-1], x) - mp.exp(x)) / mp.exp(x)


def extrema(c, a, b, n=4000):
    """One (x, error) per run of equal sign of the error on a grid: its largest."""
    out, cur = [], None
    for i in range(n + 1):
        x = a + (b - a) * i / n
        e = rel_err(c, x)
        if cur is not None and mp.sign(e) == mp.sign(cur[1]):
            if abs(e) > abs(cur[1]):
                cur = (x, e)
        else:
            if cur is not None:
                out.append(cur)
            cur = (x, e)
    out.append(cur)
    return out


def remez(deg, a, b, iterations=25):
    m = deg + 2
    xs = [(a + b) / 2 - (b - a) / 2 * mp.cos(mp.pi * i / (m - 1)) for i in range(m)]
    for _ in range(iterations):
        # p(x_i) + (-1)^i E e^{x_i} = e^{x_i}: equioscillating relative error E.
        A = mp.matrix(m, m)
        y = mp.matrix(m, 1)
        for i, x in enumerate(xs):
            for j in range(deg + 1):
                A[i, j] = x**j
            A[i, deg + 1] = (-1) ** i * mp.exp(x)
            y[i] = mp.exp(x)
        sol = mp.lu_solve(A, y)
        c = [sol[j] for j in range(deg + 1)]
        ext = extrema(c, a, b)
        if len(ext) == m:
            xs = [x for x, _ in ext]
    return c


def main():
    deg = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    half = mp.log(2) / 2 * mp.mpf("1.0001")
    c = remez(deg, -half, half)
    c32 = [mp.mpf(f32(v)) for v in c]
    for j, v in enumerate(c32):
        print(f"C{j} = {repr(f32(v))}")
    grid = [-half + 2 * half * i / 20000 for i in range(20001)]
    print("max relative error, exact coefficients:",
          mp.nstr(max(abs(rel_err(c, x)) for x in grid), 3))
    print("max relative error, float32 coefficients:",
          mp.nstr(max(abs(rel_err(c32, x)) for x in grid), 3))


if __name__ == "__main__":
    main()
