//! LiDAR range-view and reflectance-view maps (docs/DESIGN.md §9): a point cloud
//! projected into the camera image, then filled by the bilateral filter of the paper.
//!
//! Everything works over caller buffers and never allocates or panics:
//!
//! 1. [`project`] writes the **sparse maps** (row-major `f32` images, 0 where no point
//!    falls) from a scan and a [`Projection`];
//! 2. [`collect_pixels`] lists the pixels that have a point, in row-major order;
//! 3. [`upsample`] writes the **dense maps** from that list. They may be the buffers of
//!    step 1: the list holds the values the filter reads.
//!
//! ```
//! # use mlmap_core as mlmap;
//! use mlmap::lidar::{self, Calibration, Pixel, R0};
//!
//! // A camera one metre behind the LiDAR looking along its x axis (KITTI's axes).
//! let calib = Calibration {
//!     p2: [[2.0, 0.0, 2.0, 0.0], [0.0, 2.0, 2.0, 0.0], [0.0, 0.0, 1.0, 0.0]],
//!     r0_rect: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
//!     tr_velo_to_cam: [[0.0, -1.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [1.0, 0.0, 0.0, 1.0]],
//! };
//! let scan = [[3.0f32, 0.0, 0.0, 0.5], [3.0, -3.0, 0.0, 0.25]];
//! let (w, h) = (5, 5);
//! let mut range = [0.0f32; 25];
//! let mut refl = [0.0f32; 25];
//! let mut pixels = [Pixel::default(); 2];
//! lidar::project(&scan, &calib.projection(), w, h, &mut range, &mut refl)?;
//! let n = lidar::collect_pixels(&range, &refl, w, h, &mut pixels)?;
//! assert_eq!(n, 2);
//! assert_eq!(range[2 * w + 2], 3.0); // the first point lands at the centre
//! let mut scratch = [0.0f32; lidar::scratch_len(3)];
//! lidar::upsample(&pixels[..n], w, h, 3, R0::GsMean, &mut scratch, &mut range, &mut refl)?;
//! assert_eq!(range[2 * w + 4], 3.0f32.hypot(3.0)); // the second, two pixels right
//! assert!(range[2 * w + 3] > 3.0 && range[2 * w + 3] < 3.0f32.hypot(3.0)); // filled
//! assert_eq!(range[0], 0.0); // no point within the 3 x 3 mask: no data
//! # Ok::<(), lidar::LidarError>(())
//! ```

mod upsample;

use core::fmt;

pub use upsample::{scratch_len, upsample, R0};

/// The largest mask side `c` (odd): 63 pixels.
pub const MAX_MASK: usize = 63;

/// The largest image side, in pixels.
pub const MAX_SIDE: usize = 65535;

/// The largest magnitude of a coordinate or reflectance of a point.
pub const MAX_ABS: f32 = 1e18;

/// The largest magnitude of a value in the pixel list ([`upsample`]): a range of a
/// point within [`MAX_ABS`] is below it.
pub const MAX_VALUE: f32 = 2e18;

/// The three matrices of a KITTI calibration file that the projection uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// `P2`: the left colour camera's 3 × 4 projection, row by row.
    pub p2: [[f64; 4]; 3],
    /// `R0_rect`: the 3 × 3 rectifying rotation.
    pub r0_rect: [[f64; 3]; 3],
    /// `Tr_velo_to_cam`: the 3 × 4 transform from the LiDAR to the camera frame.
    pub tr_velo_to_cam: [[f64; 4]; 3],
}

impl Calibration {
    /// The composed projection `M = (P2 · R0_rect) · Tr_velo_to_cam` of DESIGN §9.2,
    /// with `R0_rect` and `Tr_velo_to_cam` padded to 4 × 4.
    pub fn projection(&self) -> Projection {
        let mut r = [[0.0f64; 4]; 4];
        for (dst, src) in r.iter_mut().zip(&self.r0_rect) {
            dst[..3].copy_from_slice(src);
        }
        r[3][3] = 1.0;
        let mut t = [[0.0f64; 4]; 4];
        t[..3].copy_from_slice(&self.tr_velo_to_cam);
        t[3][3] = 1.0;
        let a = mul(&self.p2, &r);
        Projection { m: mul(&a, &t) }
    }
}

/// `a · b` for a 3 × 4 `a` and a 4 × 4 `b`, each entry summed over `k` increasing.
fn mul(a: &[[f64; 4]; 3], b: &[[f64; 4]; 4]) -> [[f64; 4]; 3] {
    let mut out = [[0.0f64; 4]; 3];
    for (o, ar) in out.iter_mut().zip(a) {
        for (j, oj) in o.iter_mut().enumerate() {
            let mut s = 0.0;
            for (aik, bk) in ar.iter().zip(b) {
                s += aik * bk.get(j).copied().unwrap_or(0.0);
            }
            *oj = s;
        }
    }
    out
}

/// A composed 3 × 4 projection from LiDAR coordinates to homogeneous pixel coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    m: [[f64; 4]; 3],
}

impl Projection {
    /// A projection from its matrix, row by row.
    pub const fn from_matrix(m: [[f64; 4]; 3]) -> Self {
        Self { m }
    }

    /// The matrix, row by row.
    pub const fn matrix(&self) -> &[[f64; 4]; 3] {
        &self.m
    }

    /// The pixel `(col, row)` of the point `(x, y, z)` in a `width × height` image:
    /// `None` behind the camera (`w ≤ 0`) or outside the image (DESIGN §9.2).
    pub fn pixel(
        &self,
        x: f32,
        y: f32,
        z: f32,
        width: usize,
        height: usize,
    ) -> Option<(usize, usize)> {
        let p = [f64::from(x), f64::from(y), f64::from(z), 1.0];
        let mut c = [0.0f64; 3];
        for (ci, row) in c.iter_mut().zip(&self.m) {
            let mut s = 0.0;
            for (mij, pj) in row.iter().zip(&p) {
                s += mij * pj;
            }
            *ci = s;
        }
        let [a, b, w] = c;
        if !(w > 0.0) {
            return None;
        }
        let col = libm::floor(a / w + 0.5);
        let row = libm::floor(b / w + 0.5);
        // NaN and infinities fail both comparisons.
        if col >= 0.0 && col < width as f64 && row >= 0.0 && row < height as f64 {
            Some((col as usize, row as usize))
        } else {
            None
        }
    }
}

/// The range of a point: its Euclidean distance to the LiDAR, computed in `f64` and
/// rounded to `f32` (DESIGN §9.2).
pub fn range_of(x: f32, y: f32, z: f32) -> f32 {
    let (x, y, z) = (f64::from(x), f64::from(y), f64::from(z));
    libm::sqrt(x * x + y * y + z * z) as f32
}

/// A pixel that has a point: its position and the winning point's range and reflectance.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pixel {
    /// Column, from 0 at the left.
    pub col: u16,
    /// Row, from 0 at the top.
    pub row: u16,
    /// The range (metres), positive.
    pub range: f32,
    /// The reflectance.
    pub reflectance: f32,
}

/// What a projection kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Projected {
    /// Points in front of the camera, inside the image, at a positive range.
    pub kept: usize,
    /// Pixels with a point (a kept point that lost to a nearer one is not counted).
    pub pixels: usize,
}

/// Why a LiDAR map could not be computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum LidarError {
    /// The image width or height is 0 or above [`MAX_SIDE`].
    ImageSize {
        /// The width given.
        width: usize,
        /// The height given.
        height: usize,
    },
    /// An image buffer's length is not `width × height`.
    ImageLen {
        /// `width × height`.
        expected: usize,
        /// The buffer's length.
        got: usize,
    },
    /// The mask side is even, 0 or above [`MAX_MASK`].
    Mask {
        /// The side given.
        mask: usize,
    },
    /// The scratch buffer is shorter than [`scratch_len`] of the mask.
    Scratch {
        /// The length needed.
        needed: usize,
        /// The buffer's length.
        got: usize,
    },
    /// A point has a coordinate or reflectance that is NaN, infinite or above [`MAX_ABS`].
    Point {
        /// The point's index in the scan.
        index: usize,
    },
    /// The pixel list is shorter than the number of pixels with a point.
    PixelCapacity {
        /// Pixels with a point.
        needed: usize,
        /// The list's length.
        got: usize,
    },
    /// A pixel list entry is outside the image, out of row-major order, repeated, or has
    /// a range that is not positive or a value that is not finite or above [`MAX_VALUE`].
    Pixel {
        /// The entry's index in the list.
        index: usize,
    },
}

impl LidarError {
    /// The one sentence describing the variant.
    pub const fn message(&self) -> &'static str {
        match self {
            Self::ImageSize { .. } => "the image size is 0 or above 65535",
            Self::ImageLen { .. } => "an image buffer's length is not width x height",
            Self::Mask { .. } => "the mask side must be odd, from 1 to 63",
            Self::Scratch { .. } => "the scratch buffer is too short for the mask",
            Self::Point { .. } => "a point has a value that is not finite or above 1e18",
            Self::PixelCapacity { .. } => "the pixel list is too short",
            Self::Pixel { .. } => {
                "the pixel list is not sorted, unique, inside the image and finite"
            }
        }
    }
}

impl fmt::Display for LidarError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = self.message();
        match *self {
            Self::ImageSize { width, height } => write!(f, "{m}: {width} x {height}"),
            Self::ImageLen { expected, got }
            | Self::Scratch {
                needed: expected,
                got,
            } => {
                write!(f, "{m}: {got} instead of {expected}")
            }
            Self::Mask { mask } => write!(f, "{m}: {mask}"),
            Self::Point { index } => write!(f, "{m}: point {index}"),
            Self::PixelCapacity { needed, got } => write!(f, "{m}: {got} for {needed} pixels"),
            Self::Pixel { index } => write!(f, "{m}: entry {index}"),
        }
    }
}

impl core::error::Error for LidarError {}

/// Checks the image size and the lengths of two image buffers.
fn check_images(width: usize, height: usize, a: usize, b: usize) -> Result<usize, LidarError> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(LidarError::ImageSize { width, height });
    }
    // At most 65535², below 2³²: no overflow even with a 32-bit `usize`.
    let Some(n) = width.checked_mul(height) else {
        return Err(LidarError::ImageSize { width, height });
    };
    for got in [a, b] {
        if got != n {
            return Err(LidarError::ImageLen { expected: n, got });
        }
    }
    Ok(n)
}

/// Projects a scan (`x, y, z, reflectance` per point) into the sparse range and
/// reflectance maps (DESIGN §9.2): both images are overwritten, 0 where no point falls.
/// Where points share a pixel, the smallest range wins, the first in the scan on ties.
///
/// # Errors
/// A bad image size or buffer length, or a point with a value that is not finite or
/// above [`MAX_ABS`] (checked for every point, kept or not; the images are then left
/// partly written).
pub fn project(
    points: &[[f32; 4]],
    projection: &Projection,
    width: usize,
    height: usize,
    range: &mut [f32],
    reflectance: &mut [f32],
) -> Result<Projected, LidarError> {
    check_images(width, height, range.len(), reflectance.len())?;
    range.fill(0.0);
    reflectance.fill(0.0);
    let mut kept = 0;
    for (index, &[x, y, z, f]) in points.iter().enumerate() {
        if [x, y, z, f].iter().any(|v| !(v.abs() <= MAX_ABS)) {
            return Err(LidarError::Point { index });
        }
        let Some((col, row)) = projection.pixel(x, y, z, width, height) else {
            continue;
        };
        let rho = range_of(x, y, z);
        if !(rho > 0.0) {
            continue;
        }
        kept += 1;
        let i = row * width + col;
        if let (Some(r), Some(v)) = (range.get_mut(i), reflectance.get_mut(i)) {
            if *r == 0.0 || rho < *r {
                *r = rho;
                *v = f;
            }
        }
    }
    let pixels = range.iter().filter(|&&r| r > 0.0).count();
    Ok(Projected { kept, pixels })
}

/// Lists the pixels of sparse maps that have a point (a positive range), in row-major
/// order, into `out`; returns how many. `out` needs room for [`Projected::pixels`]
/// entries (at most one per point of the scan).
///
/// # Errors
/// A bad image size or buffer length, or `out` too short.
pub fn collect_pixels(
    range: &[f32],
    reflectance: &[f32],
    width: usize,
    height: usize,
    out: &mut [Pixel],
) -> Result<usize, LidarError> {
    check_images(width, height, range.len(), reflectance.len())?;
    let mut n = 0usize;
    for row in 0..height {
        let cols = row * width..(row + 1) * width;
        let (Some(rr), Some(fr)) = (range.get(cols.clone()), reflectance.get(cols)) else {
            break;
        };
        for (col, (&r, &f)) in rr.iter().zip(fr).enumerate() {
            if r > 0.0 {
                if let Some(p) = out.get_mut(n) {
                    // Both below MAX_SIDE = u16::MAX.
                    *p = Pixel {
                        col: col as u16,
                        row: row as u16,
                        range: r,
                        reflectance: f,
                    };
                }
                n += 1;
            }
        }
    }
    if n > out.len() {
        return Err(LidarError::PixelCapacity {
            needed: n,
            got: out.len(),
        });
    }
    Ok(n)
}

/// `⌊x + ½⌋` clamped to `[0, max]`; NaN gives 0.
fn round_clamped(x: f32, max: f32) -> f32 {
    if x > 0.0 {
        libm::floorf(x + 0.5).min(max)
    } else {
        0.0
    }
}

/// A range as a 16-bit pixel: `256 ρ` rounded, clamped to 65535 (DESIGN §9.4).
pub fn range_to_u16(range: f32) -> u16 {
    round_clamped(range * 256.0, 65535.0) as u16
}

/// A reflectance as a 16-bit pixel: `65535 f` rounded, `f` clamped to `[0, 1]`.
pub fn reflectance_to_u16(reflectance: f32) -> u16 {
    round_clamped(reflectance.min(1.0) * 65535.0, 65535.0) as u16
}

/// A range as an 8-bit pixel: `255 min(ρ, max_range) / max_range` rounded (DESIGN §9.4);
/// 0 when `max_range` is not positive and finite.
pub fn range_to_u8(range: f32, max_range: f32) -> u8 {
    if !(max_range > 0.0 && max_range.is_finite()) {
        return 0;
    }
    round_clamped(255.0 * range.min(max_range) / max_range, 255.0) as u8
}

/// A reflectance as an 8-bit pixel: `255 f` rounded, `f` clamped to `[0, 1]`.
pub fn reflectance_to_u8(reflectance: f32) -> u8 {
    round_clamped(reflectance.min(1.0) * 255.0, 255.0) as u8
}
