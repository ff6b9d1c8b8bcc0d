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
    let area = mask.saturating_mul(mask);
    h.saturating_mul(h).saturating_add(area.saturating_mul(3))
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
/// The images may be the sparse maps the list was collected from. Time is bounded: each
/// pixel without a point moves at most `mask` row cursors and visits at most `mask²`
/// points, `O(width · height · mask²)` in the worst case (a dense list) and about
/// `width · height · (mask + points per mask)` in practice; `scratch` needs
/// [`scratch_len`]`(mask)` values.
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
    if mask.is_multiple_of(2) || mask > MAX_MASK {
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
    for (dy, t) in table.chunks_exact_mut(side.max(1)).enumerate() {
        for (dx, g) in t.iter_mut().enumerate() {
            let d2 = (dx * dx + dy * dy) as f64;
            *g = (1.0 / (1.0 + libm::sqrt(d2))) as f32;
        }
    }
    let table: &[f32] = table;
    let mut cursors = [EMPTY; MAX_MASK];
    for row0 in 0..height {
        // Rows by index: a zip of exact chunks would keep a division (its size hint).
        let cols = row0 * width..(row0 + 1) * width;
        let (Some(rout), Some(fout)) = (range.get_mut(cols.clone()), reflectance.get_mut(cols))
        else {
            break;
        };
        let first = row0.saturating_sub(h);
        let rows = (row0 + h).min(height - 1) + 1 - first;
        let active = start(&mut cursors, pixels, table, side, first, rows, row0);
        let centre = active
            .iter()
            .find(|c| c.row == row0)
            .map_or(&[][..], |c| c.seg);
        let mut at = 0usize; // the centre row's first point at or right of col0
        for (col0, (ro, fo)) in rout.iter_mut().zip(fout.iter_mut()).enumerate() {
            while centre.get(at).is_some_and(|p| usize::from(p.col) < col0) {
                at += 1;
            }
            if let Some(p) = centre.get(at).filter(|p| usize::from(p.col) == col0) {
                (*ro, *fo) = (p.range, p.reflectance);
                continue;
            }
            let mut n = 0usize;
            let mut nearest = (usize::MAX, 0usize);
            for c in active.iter_mut() {
                while c
                    .seg
                    .get(c.lo)
                    .is_some_and(|p| usize::from(p.col) + h < col0)
                {
                    c.lo += 1;
                }
                while c
                    .seg
                    .get(c.hi)
                    .is_some_and(|p| usize::from(p.col) <= col0 + h)
                {
                    c.hi += 1;
                }
                for p in c.seg.get(c.lo..c.hi).unwrap_or(&[]) {
                    let dx = usize::from(p.col).abs_diff(col0);
                    let d2 = dx * dx + c.dy2;
                    if d2 < nearest.0 {
                        nearest = (d2, n);
                    }
                    if let (Some(g), Some(r), Some(f), Some(&t)) =
                        (gs.get_mut(n), rv.get_mut(n), fv.get_mut(n), c.trow.get(dx))
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
            (*ro, *fo) = filter(g, r, f, r0, nearest.1);
        }
    }
    Ok(())
}

/// One image row of the mask that holds points: its points, its row of the `G_s`
/// table, and the cursors of its points within `h` columns of the current pixel.
#[derive(Clone, Copy)]
struct Cursor<'a> {
    seg: &'a [Pixel],
    trow: &'a [f32],
    row: usize,
    dy2: usize,
    lo: usize,
    hi: usize,
}

/// A cursor over no points.
const EMPTY: Cursor<'static> = Cursor {
    seg: &[],
    trow: &[],
    row: 0,
    dy2: 0,
    lo: 0,
    hi: 0,
};

/// The cursors of the image rows `first..first + rows` that hold a point, around the
/// pixel row `row0`, at the start of their rows.
fn start<'a, 'c>(
    cursors: &'c mut [Cursor<'a>; MAX_MASK],
    pixels: &'a [Pixel],
    table: &'a [f32],
    side: usize,
    first: usize,
    rows: usize,
    row0: usize,
) -> &'c mut [Cursor<'a>] {
    let mut from = pixels.partition_point(|p| usize::from(p.row) < first);
    let mut n = 0;
    for row in first..first + rows {
        let rest = pixels.get(from..).unwrap_or(&[]);
        let len = rest.partition_point(|p| usize::from(p.row) <= row);
        from += len;
        if len == 0 {
            continue;
        }
        let dy = row.abs_diff(row0);
        if let Some(c) = cursors.get_mut(n) {
            *c = Cursor {
                seg: rest.get(..len).unwrap_or(&[]),
                trow: table.get(dy * side..(dy + 1) * side).unwrap_or(&[]),
                row,
                dy2: dy * dy,
                lo: 0,
                hi: 0,
            };
            n += 1;
        }
    }
    cursors.get_mut(..n).unwrap_or(&mut [])
}

/// Lanes of the partial sums: four, so that the loops vectorise.
const LANES: usize = 4;

/// `Σ a·b` and `Σ a·c` style sums in [`LANES`] interleaved partial sums, then added.
#[derive(Clone, Copy)]
struct Acc([f32; LANES]);

impl Acc {
    fn total(self) -> f32 {
        let [a, b, c, d] = self.0;
        (a + b) + (c + d)
    }
}

/// The filter at one pixel for both maps, from its mask's points (`G_s`, ranges and
/// reflectances, same order): 0 without points, else each `r̂₀` clamped to its points'
/// range of values. Sums run in [`LANES`] interleaved partial sums.
fn filter(gs: &[f32], rv: &[f32], fv: &[f32], r0: R0, nearest: usize) -> (f32, f32) {
    if gs.is_empty() {
        return (0.0, 0.0);
    }
    let (mut sg, mut sgr, mut sgf) = (Acc([0.0; LANES]), Acc([0.0; LANES]), Acc([0.0; LANES]));
    let mut lo = [f32::INFINITY; 2];
    let mut hi = [f32::NEG_INFINITY; 2];
    let lanes = |k: usize| k % LANES;
    for (k, ((&g, &r), &f)) in gs.iter().zip(rv).zip(fv).enumerate() {
        let l = lanes(k);
        if let (Some(a), Some(b), Some(c)) = (sg.0.get_mut(l), sgr.0.get_mut(l), sgf.0.get_mut(l)) {
            *a += g;
            *b += g * r;
            *c += g * f;
        }
        lo = [lo[0].min(r), lo[1].min(f)];
        hi = [hi[0].max(r), hi[1].max(f)];
    }
    let (r0r, r0f) = match r0 {
        R0::GsMean => {
            let sg = sg.total();
            (sgr.total() / sg, sgf.total() / sg)
        }
        R0::Nearest => (
            rv.get(nearest).copied().unwrap_or(0.0),
            fv.get(nearest).copied().unwrap_or(0.0),
        ),
    };
    let (mut swr, mut swrv) = (Acc([0.0; LANES]), Acc([0.0; LANES]));
    let (mut swf, mut swfv) = (Acc([0.0; LANES]), Acc([0.0; LANES]));
    let mut chunks = gs
        .chunks_exact(LANES)
        .zip(rv.chunks_exact(LANES))
        .zip(fv.chunks_exact(LANES));
    for ((g, r), f) in &mut chunks {
        for l in 0..LANES {
            if let (Some(&g), Some(&r), Some(&f)) = (g.get(l), r.get(l), f.get(l)) {
                let wr = g / (1.0 + (r0r - r).abs());
                let wf = g / (1.0 + (r0f - f).abs());
                if let (Some(a), Some(b), Some(c), Some(d)) = (
                    swr.0.get_mut(l),
                    swrv.0.get_mut(l),
                    swf.0.get_mut(l),
                    swfv.0.get_mut(l),
                ) {
                    *a += wr;
                    *b += wr * r;
                    *c += wf;
                    *d += wf * f;
                }
            }
        }
    }
    let done = gs.len() - gs.len() % LANES;
    for (l, ((&g, &r), &f)) in gs.iter().zip(rv).zip(fv).skip(done).enumerate() {
        let wr = g / (1.0 + (r0r - r).abs());
        let wf = g / (1.0 + (r0f - f).abs());
        if let (Some(a), Some(b), Some(c), Some(d)) = (
            swr.0.get_mut(l),
            swrv.0.get_mut(l),
            swf.0.get_mut(l),
            swfv.0.get_mut(l),
        ) {
            *a += wr;
            *b += wr * r;
            *c += wf;
            *d += wf * f;
        }
    }
    // Every weight is positive and normal, so no NaN; the clamp only undoes rounding.
    let out_r = (swrv.total() / swr.total()).max(lo[0]).min(hi[0]);
    let out_f = (swfv.total() / swf.total()).max(lo[1]).min(hi[1]);
    (out_r, out_f)
}
