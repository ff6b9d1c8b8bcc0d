//! The bilateral upsampling of DESIGN §9.3, over the list of pixels with a point.
//!
//! For each image row, the rows of the mask are slices of the (row-major) list; as the
//! mask slides right, two cursors per row keep the points within `h` columns. Only the
//! mask's points are visited, each once to gather it (with its `G_s` from a table of
//! the `(h + 1)²` offsets) and then twice per map: the sums of `r₀`, then those of `r̂₀`.

use super::{check_images, LidarError, Pixel, MAX_MASK, MAX_VALUE};

/// The value `r₀` the range kernel `G_r` compares the mask's points with, at a pixel
/// without a point (DESIGN §9.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum R0 {
    /// The `G_s`-weighted mean of the mask's points (one step): the default.
    #[default]
    GsMean,
    /// The value of the mask's point nearest the pixel, ties to the first in row-major
    /// order.
    Nearest,
}

/// The `f32` scratch [`upsample`] needs for a `mask × mask` mask: the `G_s` table and
/// the gathered points, `(h + 1)² + 3 mask²` with `h = (mask − 1) / 2`.
pub const fn scratch_len(mask: usize) -> usize {
    let h = mask / 2 + 1;
    h * h + 3 * mask * mask
}

/// Checks that the list is inside the image, strictly row-major and has valid values.
fn check_pixels(pixels: &[Pixel], width: usize, height: usize) -> Result<(), LidarError> {
    let mut last: Option<usize> = None;
    for (index, p) in pixels.iter().enumerate() {
        let (col, row) = (usize::from(p.col), usize::from(p.row));
        let key = row * width + col;
        let ok = col < width
            && row < height
            && last.is_none_or(|l| key > l)
            && p.range > 0.0
            && p.range <= MAX_VALUE
            && p.reflectance.abs() <= MAX_VALUE;
        if !ok {
            return Err(LidarError::Pixel { index });
        }
        last = Some(key);
    }
    Ok(())
}

/// Writes the dense range and reflectance maps (DESIGN §9.3) from the pixels that have
/// a point (row-major, as [`collect_pixels`](super::collect_pixels) lists them): those
/// pixels keep their values, every other pixel gets the bilateral filter of the
/// `mask × mask` window centred on it, 0 when no point is in it.
///
/// The images may be the sparse maps the list was collected from. Time is bounded by
/// `O(width · height · mask + pixels)`; `scratch` needs [`scratch_len`]`(mask)` values.
///
/// # Errors
/// A bad image size, buffer length, mask side or scratch length, or a list that is not
/// strictly row-major inside the image with positive ranges and finite values up to
/// [`MAX_VALUE`]. Nothing is written then.
#[allow(clippy::too_many_arguments)]
pub fn upsample(
    pixels: &[Pixel],
    width: usize,
    height: usize,
    mask: usize,
    r0: R0,
    scratch: &mut [f32],
    range: &mut [f32],
    reflectance: &mut [f32],
) -> Result<(), LidarError> {
    check_images(width, height, range.len(), reflectance.len())?;
    if mask % 2 == 0 || mask > MAX_MASK {
        return Err(LidarError::Mask { mask });
    }
    let needed = scratch_len(mask);
    let bad_scratch = LidarError::Scratch {
        needed,
        got: scratch.len(),
    };
    check_pixels(pixels, width, height)?;
    let h = mask / 2;
    let side = h + 1;
    let area = mask * mask;
    let (table, rest) = scratch
        .split_at_mut_checked(side * side)
        .ok_or(bad_scratch)?;
    let (gs, rest) = rest.split_at_mut_checked(area).ok_or(bad_scratch)?;
    let (rv, rest) = rest.split_at_mut_checked(area).ok_or(bad_scratch)?;
    let fv = rest.get_mut(..area).ok_or(bad_scratch)?;
    for (dy, t) in table.chunks_exact_mut(side).enumerate() {
        for (dx, g) in t.iter_mut().enumerate() {
            let d2 = (dx * dx + dy * dy) as f64;
            *g = (1.0 / (1.0 + libm::sqrt(d2))) as f32;
        }
    }
    let mut window = Window {
        seg: [&[]; MAX_MASK],
        lo: [0; MAX_MASK],
        hi: [0; MAX_MASK],
    };
    for (row0, (rout, fout)) in range
        .chunks_exact_mut(width)
        .zip(reflectance.chunks_exact_mut(width))
        .enumerate()
    {
        let first = row0.saturating_sub(h);
        let rows = (row0 + h).min(height - 1) + 1 - first;
        window.start(pixels, first, rows);
        let centre = window.seg.get(row0 - first).copied().unwrap_or(&[]);
        let mut at = 0usize; // the centre row's first point at or right of col0
        for (col0, (ro, fo)) in rout.iter_mut().zip(fout.iter_mut()).enumerate() {
            while centre.get(at).is_some_and(|p| usize::from(p.col) < col0) {
                at += 1;
            }
            if let Some(p) = centre.get(at).filter(|p| usize::from(p.col) == col0) {
                (*ro, *fo) = (p.range, p.reflectance);
                continue;
            }
            window.slide(col0, h, rows);
            let mut n = 0usize;
            let mut nearest = (usize::MAX, 0usize);
            for (k, seg) in window.seg.iter().take(rows).enumerate() {
                let dy = (first + k).abs_diff(row0);
                let trow = table.get(dy * side..(dy + 1) * side).unwrap_or(&[]);
                let (lo, hi) = (window.lo.get(k), window.hi.get(k));
                let pts = match (lo, hi) {
                    (Some(&lo), Some(&hi)) => seg.get(lo..hi).unwrap_or(&[]),
                    _ => &[],
                };
                for p in pts {
                    let dx = usize::from(p.col).abs_diff(col0);
                    let d2 = dx * dx + dy * dy;
                    if d2 < nearest.0 {
                        nearest = (d2, n);
                    }
                    if let (Some(g), Some(r), Some(f), Some(&t)) =
                        (gs.get_mut(n), rv.get_mut(n), fv.get_mut(n), trow.get(dx))
                    {
                        (*g, *r, *f) = (t, p.range, p.reflectance);
                        n += 1;
                    }
                }
            }
            let (g, r, f) = (
                gs.get(..n).unwrap_or(&[]),
                rv.get(..n).unwrap_or(&[]),
                fv.get(..n).unwrap_or(&[]),
            );
            *ro = filter(g, r, r0, nearest.1);
            *fo = filter(g, f, r0, nearest.1);
        }
    }
    Ok(())
}

/// The rows of the mask: each a slice of the list, and the cursors of the points within
/// `h` columns of the current pixel.
struct Window<'a> {
    seg: [&'a [Pixel]; MAX_MASK],
    lo: [usize; MAX_MASK],
    hi: [usize; MAX_MASK],
}

impl<'a> Window<'a> {
    /// The `rows` image rows from `first`, cursors at their start.
    fn start(&mut self, pixels: &'a [Pixel], first: usize, rows: usize) {
        let mut from = pixels.partition_point(|p| usize::from(p.row) < first);
        for (k, ((seg, lo), hi)) in self
            .seg
            .iter_mut()
            .zip(&mut self.lo)
            .zip(&mut self.hi)
            .enumerate()
        {
            if k >= rows {
                break;
            }
            let rest = pixels.get(from..).unwrap_or(&[]);
            let len = rest.partition_point(|p| usize::from(p.row) <= first + k);
            *seg = rest.get(..len).unwrap_or(&[]);
            (*lo, *hi) = (0, 0);
            from += len;
        }
    }

    /// Moves the cursors to the points with `|col − col0| ≤ h`.
    fn slide(&mut self, col0: usize, h: usize, rows: usize) {
        for ((seg, lo), hi) in self
            .seg
            .iter()
            .zip(&mut self.lo)
            .zip(&mut self.hi)
            .take(rows)
        {
            while seg.get(*lo).is_some_and(|p| usize::from(p.col) + h < col0) {
                *lo += 1;
            }
            while seg.get(*hi).is_some_and(|p| usize::from(p.col) <= col0 + h) {
                *hi += 1;
            }
        }
    }
}

/// The filter at one pixel from its mask's points (`G_s` and values, same order): 0
/// without points, else `r̂₀` clamped to the points' range of values.
fn filter(gs: &[f32], v: &[f32], r0: R0, nearest: usize) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    let (mut sg, mut sgv) = (0.0f32, 0.0f32);
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for (&g, &x) in gs.iter().zip(v) {
        sg += g;
        sgv += g * x;
        lo = lo.min(x);
        hi = hi.max(x);
    }
    let r0 = match r0 {
        R0::GsMean => sgv / sg,
        R0::Nearest => v.get(nearest).copied().unwrap_or(0.0),
    };
    let (mut sw, mut swv) = (0.0f32, 0.0f32);
    for (&g, &x) in gs.iter().zip(v) {
        let w = g / (1.0 + (r0 - x).abs());
        sw += w;
        swv += w * x;
    }
    let out = swv / sw;
    // NaN cannot occur (every weight is positive and normal); `max` would pick `lo`.
    out.max(lo).min(hi)
}
