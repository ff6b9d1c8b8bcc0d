//! The bin placement of MATLAB's `histcounts(x, nbins)` and `histogram(x, nbins)`, the
//! `matlab` edge mode of DESIGN §1.1.
//!
//! The paper's authors built their tables with MATLAB's `histogram(x, nbins)`. With a
//! bin count given, MATLAB keeps exactly `nbins` equal bins but moves them to round
//! numbers. The rule, as MathWorks' bin picker applies it to data with smallest value
//! `xmin`, largest `xmax`, range `r = xmax - xmin` and `eps(s)` the spacing of doubles
//! at `s = max(|xmin|, |xmax|)`:
//!
//! 1. **Nearly constant data** (`r <= max(sqrt(eps(s)), smallest normal double)`): the
//!    bins cover the data plus a quarter unit on each side, widened to half-integers:
//!    `left = floor(2 (xmin - u/4)) / 2`, `right = ceil(2 (xmax + u/4)) / 2` with
//!    `u = max(1, ceil(nbins eps(s)))`, and `width = (right - left) / nbins`.
//!    A constant 5 gives `[4.5, 5.5]`; a constant 0.3 gives `[0, 1]`.
//! 2. **Otherwise** a provisional width is taken from `raw = max(r / nbins, eps(s))`:
//!    with `p = 10^floor(log10(raw))`, it is `w0 = p floor(raw / p)`, i.e. `raw`
//!    truncated to its leading decimal digit. The left edge is the multiple of `w0` at
//!    or below `xmin`: `left = min(w0 floor(xmin / w0), xmin)`.
//! 3. With `nbins > 1` the final width lies between the width that puts `xmax` on the
//!    last edge, `lo = (xmax - left) / nbins`, and the one that puts it on the last
//!    bin's left edge, `hi = (xmax - left) / (nbins - 1)`: it is the smallest multiple
//!    of `q = 10^floor(log10(hi - lo))` that is at least `lo`, `width = q ceil(lo / q)`,
//!    so `xmax` falls inside the last bin. With `nbins = 1`, `width = w0`.
//! 4. `right = max(left + nbins width, xmax)`; the inner edges are `left + k width`.
//!
//! So the width is *not* limited to 1, 2, 2.5 or 5 times a power of ten (that set
//! belongs to MATLAB's automatic rules, used when no bin count is given): it is any
//! multiple of a power of ten fine enough to fit `nbins` bins. MathWorks' documented
//! example, `histcounts([2 3 5 7 11 13 17 19 23 29], 6)`, gives the edges
//! `0 4.9 9.8 14.7 19.6 24.5 29.4`: `raw = 27/6 = 4.5`, `w0 = 4`, `left = 0`,
//! `lo = 29/6 = 4.83`, `hi = 29/5 = 5.8`, `q = 10^floor(log10 0.97) = 0.1`,
//! `width = 0.1 ceil(48.3) = 4.9`.
//!
//! Every step is computed in `f64` in the order above, so the same doubles come out as
//! in MATLAB (whose `min` and `max` ignore NaN, like [`f64::min`] and [`f64::max`]).

/// The outcome of the bin picker: first edge, bin width and last edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Picked {
    pub(crate) left: f64,
    pub(crate) width: f64,
    pub(crate) right: f64,
}

/// MATLAB's `eps(x)`: the distance from `|x|` to the next larger double, for finite `x`.
fn eps(x: f64) -> f64 {
    let a = x.abs();
    if a < f64::MIN_POSITIVE {
        // Subnormal or zero: the spacing is the smallest subnormal, 2^-1074.
        return f64::from_bits(1);
    }
    // 2^floor(log2 |x|) (the exponent bits alone), times 2^-52; exact.
    f64::from_bits(a.to_bits() & 0x7ff0_0000_0000_0000) * f64::EPSILON
}

/// `10^e` for an integral `e`: exact (or correctly rounded for negative `e`) for
/// `|e| <= 22`, where every practical bin width lies.
fn pow10(e: f64) -> f64 {
    if e.abs() <= 22.0 {
        let n = e.abs() as u32;
        let mut p = 1.0f64;
        for _ in 0..n {
            p *= 10.0; // exact: 10^22 < 2^53 * 2^22
        }
        if e < 0.0 {
            1.0 / p
        } else {
            p
        }
    } else {
        10f64.powf(e)
    }
}

/// The edges MATLAB's `histcounts(x, nbins)` picks for data spanning `[xmin, xmax]`
/// (finite, `xmin <= xmax`, `nbins >= 1`). See the module docs for the rule.
pub(crate) fn pick(xmin: f64, xmax: f64, nbins: usize) -> Picked {
    let n = nbins as f64;
    let scale = xmin.abs().max(xmax.abs());
    let range = xmax - xmin;
    let raw = (range / n).max(eps(scale));
    if range > eps(scale).sqrt().max(f64::MIN_POSITIVE) {
        let p = pow10(raw.log10().floor());
        let w0 = p * (raw / p).floor();
        let left = (w0 * (xmin / w0).floor()).min(xmin).max(-f64::MAX);
        let width = if nbins > 1 {
            let lo = (xmax - left) / n;
            let hi = (xmax - left) / (n - 1.0);
            let q = pow10((hi - lo).log10().floor());
            q * (lo / q).ceil()
        } else {
            w0
        };
        let right = (left + n * width).max(xmax).min(f64::MAX);
        Picked { left, width, right }
    } else {
        let unit = (n * eps(scale)).ceil().max(1.0);
        let left = (2.0 * (xmin - unit / 4.0)).floor() / 2.0;
        let right = (2.0 * (xmax + unit / 4.0)).ceil() / 2.0;
        Picked {
            left,
            width: (right - left) / n,
            right,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Largest allowed difference between our edges and the ones MATLAB prints (it
    /// prints 4 decimals).
    const PRINT_TOL: f64 = 5e-5;

    fn edges(p: Picked, n: usize) -> std::vec::Vec<f64> {
        (0..=n)
            .map(|k| {
                if k == n {
                    p.right
                } else {
                    p.left + k as f64 * p.width
                }
            })
            .collect()
    }

    #[test]
    fn mathworks_histcounts_example() {
        // MathWorks' histcounts documentation, "Specify Number of Bins":
        // X = [2 3 5 7 11 13 17 19 23 29]; [N,edges] = histcounts(X,6)
        // N = 2 2 2 2 1 1; edges = 0 4.9000 9.8000 14.7000 19.6000 24.5000 29.4000
        let p = pick(2.0, 29.0, 6);
        let want = [0.0, 4.9, 9.8, 14.7, 19.6, 24.5, 29.4];
        for (got, want) in edges(p, 6).iter().zip(want) {
            assert!((got - want).abs() < PRINT_TOL, "edge {got}, want {want}");
        }
    }

    #[test]
    fn hand_worked_cases() {
        // (xmin, xmax, nbins, left, width, right), worked by hand in the comments.
        let cases: &[(f64, f64, usize, f64, f64, f64)] = &[
            // Primes again, 3 bins: raw 9, w0 9, left 0; lo 29/3 = 9.67, hi 14.5,
            // q = 10^floor(log10 4.83) = 1, width ceil(9.67) = 10 -> 0 10 20 30.
            (2.0, 29.0, 3, 0.0, 10.0, 30.0),
            // [-3.7, 4.3], 4 bins: raw 2, w0 2, left = 2 floor(-1.85) = -4;
            // lo 8.3/4 = 2.075, hi 8.3/3 = 2.77, q = 0.1, width 0.1 ceil(20.75) = 2.1,
            // right -4 + 8.4 = 4.4.
            (-3.7, 4.3, 4, -4.0, 2.1, 4.4),
            // [0.3, 0.9], 1 bin: raw = 0.9 - 0.3 = 0.6000000000000001 in doubles,
            // p 0.1, w0 = 0.6, left = 0.6 floor(0.5) = 0, width w0,
            // right = max(0.6, 0.9) = 0.9.
            (0.3, 0.9, 1, 0.0, 0.6, 0.9),
            // [12, 95], 22 bins: raw 3.77, w0 3, left 12 (3 * 4); lo 83/22 = 3.773,
            // hi 83/21 = 3.952, q = 10^floor(log10 0.18) = 0.1, width 3.8,
            // right 12 + 83.6 = 95.6.
            (12.0, 95.0, 22, 12.0, 3.8, 95.6),
            // Constant 5: u = 1, left floor(2 * 4.75)/2 = 4.5, right ceil(10.5)/2 = 5.5.
            (5.0, 5.0, 17, 4.5, 1.0 / 17.0, 5.5),
            // Constant 0.3: left floor(0.1)/2 = 0, right ceil(1.1)/2 = 1.
            (0.3, 0.3, 2, 0.0, 0.5, 1.0),
            // Constant -2.2: left floor(-4.9)/2 = -2.5, right ceil(-3.9)/2 = -1.5.
            (-2.2, -2.2, 4, -2.5, 0.25, -1.5),
            // Nearly constant (range 1e-9 < sqrt(eps(1)) = 1.5e-8): same as constant 1.
            (1.0, 1.0 + 1e-9, 3, 0.5, 1.0 / 3.0, 1.5),
        ];
        for &(xmin, xmax, n, left, width, right) in cases {
            let p = pick(xmin, xmax, n);
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
            assert!(
                close(p.left, left) && close(p.width, width) && close(p.right, right),
                "pick({xmin}, {xmax}, {n}) = {p:?}, want ({left}, {width}, {right})"
            );
            assert!(
                p.left <= xmin && p.right >= xmax,
                "{p:?} must cover the data"
            );
        }
    }

    #[test]
    fn max_falls_in_the_last_bin_and_bins_are_honoured() {
        let spans = [
            (-7.31, 12.9),
            (0.001, 0.0173),
            (-1e6, 3.2e6),
            (1e-3, 1e-3 + 1e-6),
            (2.0, 2.5),
        ];
        for &(xmin, xmax) in &spans {
            for n in 2..=64 {
                let p = pick(xmin, xmax, n);
                let last_left = p.left + (n - 1) as f64 * p.width;
                assert!(
                    last_left <= xmax && xmax <= p.right,
                    "pick({xmin}, {xmax}, {n}) = {p:?}"
                );
                assert!(p.left <= xmin && p.width > 0.0);
            }
        }
    }

    #[test]
    fn eps_matches_matlab() {
        assert_eq!(eps(1.0), f64::EPSILON);
        assert_eq!(eps(-1.5), f64::EPSILON);
        assert_eq!(eps(2.0), 2.0 * f64::EPSILON);
        assert_eq!(eps(0.0), f64::from_bits(1));
        assert_eq!(eps(1000.0), 512.0 * f64::EPSILON);
    }

    #[test]
    fn powers_of_ten() {
        assert_eq!(pow10(0.0), 1.0);
        assert_eq!(pow10(3.0), 1000.0);
        assert_eq!(pow10(-1.0), 0.1);
        assert_eq!(pow10(-4.0), 1e-4);
        assert_eq!(pow10(22.0), 1e22);
        assert_eq!(pow10(-22.0), 1e-22);
    }
}
