//! The LiDAR maps of DESIGN §9 on the host: the KITTI file readers (velodyne scans,
//! calibration files, object labels), the maps computed by the device code of
//! [`mlmap_core::lidar`], and the crops of labelled objects.
//!
//! Every reader checks all of its input and names the file (and line) of the first
//! problem; nothing here panics on bad input.
//!
//! ```
//! use std::path::Path;
//! use mlmap_host::lidar::{maps, parse_calibration, parse_scan};
//! use mlmap_core::lidar::R0;
//!
//! let calib = parse_calibration(
//!     Path::new("calib.txt"),
//!     "P2: 2 0 2 0 0 2 2 0 0 0 1 0\nR0_rect: 1 0 0 0 1 0 0 0 1\n\
//!      Tr_velo_to_cam: 0 -1 0 0 0 0 -1 0 1 0 0 1\n",
//! )?;
//! let mut bytes = Vec::new();
//! for v in [3.0f32, 0.0, 0.0, 0.5] {
//!     bytes.extend_from_slice(&v.to_le_bytes());
//! }
//! let scan = parse_scan(Path::new("scan.bin"), &bytes)?;
//! let m = maps(&scan, &calib, 5, 5, 3, R0::GsMean).map_err(|e| e.to_string())?;
//! assert_eq!(m.range[2 * 5 + 2], 3.0);
//! assert_eq!(m.range[2 * 5 + 3], 3.0); // one point in the mask: its value
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fs;
use std::path::Path;

use mlmap_core::lidar::{
    collect_pixels, project, scratch_len, upsample, Calibration, LidarError, Pixel, Projected,
    MAX_ABS, R0,
};

use super::HostError;

/// Bytes per point of a velodyne scan: `x, y, z, reflectance` as little-endian `f32`.
pub const POINT_BYTES: usize = 16;

/// Reads a KITTI velodyne scan ([`parse_scan`]).
pub fn read_scan(path: &Path) -> Result<Vec<[f32; 4]>, HostError> {
    let bytes = fs::read(path).map_err(|e| HostError::input(path, e))?;
    parse_scan(path, &bytes)
}

/// The points of a KITTI velodyne scan (DESIGN §9.1): `N × 16` bytes, each point four
/// little-endian `f32`. A length that is not a multiple of 16, or a value that is NaN,
/// infinite or above `1e18` in magnitude, is an error naming `path` and the point.
pub fn parse_scan(path: &Path, bytes: &[u8]) -> Result<Vec<[f32; 4]>, HostError> {
    if !bytes.len().is_multiple_of(POINT_BYTES) {
        return Err(HostError::input(
            path,
            format!(
                "{} bytes is not a whole number of points (16 bytes each: x, y, z, \
                 reflectance as little-endian f32); the scan is truncated",
                bytes.len()
            ),
        ));
    }
    let mut points = Vec::with_capacity(bytes.len() / POINT_BYTES);
    for (i, rec) in bytes.chunks_exact(POINT_BYTES).enumerate() {
        let mut p = [0.0f32; 4];
        for (v, b) in p.iter_mut().zip(rec.chunks_exact(4)) {
            let mut word = [0u8; 4];
            word.copy_from_slice(b);
            *v = f32::from_le_bytes(word);
        }
        let names = ["x", "y", "z", "reflectance"];
        if let Some((name, v)) = names.iter().zip(p).find(|(_, v)| !(v.abs() <= MAX_ABS)) {
            return Err(HostError::input(
                path,
                format!(
                    "point {i} (bytes {}..{}): {name} is {v}; expected a finite value of \
                     magnitude at most 1e18",
                    i * POINT_BYTES,
                    (i + 1) * POINT_BYTES
                ),
            ));
        }
        points.push(p);
    }
    Ok(points)
}

/// Reads a KITTI calibration file ([`parse_calibration`]).
pub fn read_calibration(path: &Path) -> Result<Calibration, HostError> {
    let bytes = fs::read(path).map_err(|e| HostError::input(path, e))?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|e| HostError::input(path, format!("not UTF-8 text: {e}")))?;
    parse_calibration(path, text)
}

/// The keys of a calibration file the projection reads, and their number counts.
const CALIB_KEYS: [(&str, usize); 3] = [("P2", 12), ("R0_rect", 9), ("Tr_velo_to_cam", 12)];

/// The matrices `P2`, `R0_rect` and `Tr_velo_to_cam` of a KITTI calibration file
/// (DESIGN §9.1): one `KEY: numbers` per line, other keys and blank lines ignored. A
/// missing or repeated key, a wrong count, a number that does not parse or is not
/// finite is an error naming `path`, the line and the key.
pub fn parse_calibration(path: &Path, text: &str) -> Result<Calibration, HostError> {
    let mut found: [Option<(usize, Vec<f64>)>; 3] = [None, None, None];
    for (i, line) in text.lines().enumerate() {
        let lineno = i + 1;
        let at = |msg: String| HostError::Input(format!("{}:{lineno}: {msg}", path.display()));
        let Some((key, rest)) = line.split_once(':') else {
            if line.trim().is_empty() {
                continue;
            }
            return Err(at(format!(
                "expected `KEY: numbers`, found `{}`",
                super::escape::visible(line.trim())
            )));
        };
        let key = key.trim();
        let Some(((name, count), slot)) = CALIB_KEYS
            .iter()
            .zip(found.iter_mut())
            .find(|((k, _), _)| *k == key)
        else {
            continue;
        };
        let (name, count) = (*name, *count);
        let mut values = Vec::with_capacity(count);
        for tok in rest.split_whitespace() {
            let v: f64 = tok.parse().map_err(|_| {
                at(format!(
                    "{name}: `{}` is not a number",
                    super::escape::visible(tok)
                ))
            })?;
            if !v.is_finite() {
                return Err(at(format!("{name}: {tok} is not finite")));
            }
            values.push(v);
        }
        if values.len() != count {
            return Err(at(format!(
                "{name} has {} numbers; expected {count}",
                values.len()
            )));
        }
        if let Some((first, _)) = slot {
            return Err(at(format!("{name} is given twice (first on line {first})")));
        }
        *slot = Some((lineno, values));
    }
    let mut mats: [Vec<f64>; 3] = [vec![], vec![], vec![]];
    for ((slot, (name, _)), m) in found.into_iter().zip(CALIB_KEYS).zip(&mut mats) {
        let Some((_, values)) = slot else {
            return Err(HostError::input(
                path,
                format!(
                    "no {name} line; a KITTI calibration file needs P2, R0_rect and \
                     Tr_velo_to_cam"
                ),
            ));
        };
        *m = values;
    }
    let [p2, r0, tr] = &mats;
    let mut c = Calibration {
        p2: [[0.0; 4]; 3],
        r0_rect: [[0.0; 3]; 3],
        tr_velo_to_cam: [[0.0; 4]; 3],
    };
    for (row, src) in c.p2.iter_mut().zip(p2.chunks_exact(4)) {
        row.copy_from_slice(src);
    }
    for (row, src) in c.r0_rect.iter_mut().zip(r0.chunks_exact(3)) {
        row.copy_from_slice(src);
    }
    for (row, src) in c.tr_velo_to_cam.iter_mut().zip(tr.chunks_exact(4)) {
        row.copy_from_slice(src);
    }
    Ok(c)
}

/// The sparse and dense maps of one scan (DESIGN §9), each row-major, `height` rows of
/// `width`.
#[derive(Debug, Clone, PartialEq)]
pub struct Maps {
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// The projection's range map (0 where no point falls).
    pub sparse_range: Vec<f32>,
    /// The projection's reflectance map.
    pub sparse_reflectance: Vec<f32>,
    /// The dense range map (RaV).
    pub range: Vec<f32>,
    /// The dense reflectance map (ReV).
    pub reflectance: Vec<f32>,
    /// What the projection kept.
    pub projected: Projected,
}

/// Projects and upsamples a scan: the device code of [`mlmap_core::lidar`] over buffers
/// allocated here.
///
/// # Errors
/// A bad image size or mask side, or a point out of range.
pub fn maps(
    points: &[[f32; 4]],
    calib: &Calibration,
    width: usize,
    height: usize,
    mask: usize,
    r0: R0,
) -> Result<Maps, LidarError> {
    let n = width.saturating_mul(height);
    if width == 0
        || height == 0
        || width > mlmap_core::lidar::MAX_SIDE
        || height > mlmap_core::lidar::MAX_SIDE
    {
        return Err(LidarError::ImageSize { width, height });
    }
    let mut sparse_range = vec![0.0f32; n];
    let mut sparse_reflectance = vec![0.0f32; n];
    let projected = project(
        points,
        &calib.projection(),
        width,
        height,
        &mut sparse_range,
        &mut sparse_reflectance,
    )?;
    let mut pixels = vec![Pixel::default(); projected.pixels];
    collect_pixels(
        &sparse_range,
        &sparse_reflectance,
        width,
        height,
        &mut pixels,
    )?;
    let mut range = sparse_range.clone();
    let mut reflectance = sparse_reflectance.clone();
    let mut scratch = vec![0.0f32; scratch_len(mask)];
    upsample(
        &pixels,
        width,
        height,
        mask,
        r0,
        &mut scratch,
        &mut range,
        &mut reflectance,
    )?;
    Ok(Maps {
        width,
        height,
        sparse_range,
        sparse_reflectance,
        range,
        reflectance,
        projected,
    })
}

/// One object of a KITTI label file: its type and 2-D box (pixels).
#[derive(Debug, Clone, PartialEq)]
pub struct LabelBox {
    /// The line of the label file (from 1).
    pub line: usize,
    /// The object type (`Car`, `Pedestrian`, ...).
    pub kind: String,
    /// Left, top, right, bottom, in pixels.
    pub bbox: [f64; 4],
}

/// The pixel window of a crop: columns `col0..col1`, rows `row0..row1` (ends exclusive).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Window {
    /// First column.
    pub col0: usize,
    /// First row.
    pub row0: usize,
    /// One past the last column.
    pub col1: usize,
    /// One past the last row.
    pub row1: usize,
}

/// The objects of a KITTI label file other than `DontCare`, each with its pixel window in
/// a `width × height` image (DESIGN §9.5). Lines have 15 or 16 fields; a bad field, a
/// box with a non-finite coordinate, `left > right`, `top > bottom` or no pixel inside
/// the image, or a type other than letters, digits, `_` and `-`, is an error naming
/// `path` and the line.
pub fn parse_labels(
    path: &Path,
    text: &str,
    width: usize,
    height: usize,
) -> Result<Vec<(LabelBox, Window)>, HostError> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let lineno = i + 1;
        let at = |msg: String| HostError::Input(format!("{}:{lineno}: {msg}", path.display()));
        let fields: Vec<&str> = line.split_whitespace().collect();
        let Some((&kind, rest)) = fields.split_first() else {
            continue;
        };
        if fields.len() != 15 && fields.len() != 16 {
            return Err(at(format!(
                "{} fields; a KITTI label line has 15 (or 16 with a score)",
                fields.len()
            )));
        }
        if !kind
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        {
            return Err(at(format!(
                "the type `{}` is not letters, digits, `_` and `-`",
                super::escape::visible(kind)
            )));
        }
        let mut nums = [0.0f64; 15];
        for (k, (v, tok)) in nums.iter_mut().zip(rest).enumerate() {
            *v = tok
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    at(format!(
                        "field {}: `{}` is not a finite number",
                        k + 2,
                        super::escape::visible(tok)
                    ))
                })?;
        }
        if kind == "DontCare" {
            continue;
        }
        let [_, _, _, left, top, right, bottom, ..] = nums;
        let bbox = [left, top, right, bottom];
        if left > right || top > bottom {
            return Err(at(format!(
                "the box {left} {top} {right} {bottom} has left > right or top > bottom"
            )));
        }
        let span = |lo: f64, hi: f64, n: usize| -> Option<(usize, usize)> {
            let a = lo.floor().max(0.0);
            let b = (hi.floor() + 1.0).min(n as f64);
            (a < b).then_some((a as usize, b as usize))
        };
        let (Some((col0, col1)), Some((row0, row1))) =
            (span(left, right, width), span(top, bottom, height))
        else {
            return Err(at(format!(
                "the box {left} {top} {right} {bottom} has no pixel inside the \
                 {width} x {height} image"
            )));
        };
        out.push((
            LabelBox {
                line: lineno,
                kind: kind.to_string(),
                bbox,
            },
            Window {
                col0,
                row0,
                col1,
                row1,
            },
        ));
    }
    Ok(out)
}

/// The crop of both dense maps under a window: `(2, rows, cols)` row-major, the range
/// then the reflectance.
pub fn crop(maps: &Maps, w: Window) -> Vec<f32> {
    let mut out = Vec::with_capacity(2 * (w.row1 - w.row0) * (w.col1 - w.col0));
    for map in [&maps.range, &maps.reflectance] {
        for row in w.row0..w.row1 {
            let start = row * maps.width;
            out.extend_from_slice(map.get(start + w.col0..start + w.col1).unwrap_or(&[]));
        }
    }
    out
}
