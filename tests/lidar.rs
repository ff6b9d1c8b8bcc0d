//! The LiDAR maps of DESIGN §9: the device code against the numpy reference
//! (`tools/lidar_ref.py`, goldens written by `tools/lidar_goldens.py`), the filter's
//! properties on random sparse maps, and the readers' errors.

use std::path::{Path, PathBuf};

use mlmap::host::lidar::{
    maps, parse_calibration, parse_labels, parse_scan, read_calibration, read_scan,
};
use mlmap::lidar::{self, LidarError, Pixel, R0};
use proptest::prelude::*;

fn golden(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden/lidar")
        .join(name)
}

fn read_npy(name: &str) -> (Vec<u64>, Vec<f32>) {
    let bytes = std::fs::read(golden(name)).unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    let shape = npy.shape().to_vec();
    (shape, npy.into_vec::<f32>().unwrap())
}

/// `|a − b| ≤ 1e-5 max(|b|, 1e-30)`, element by element, with the first failure named.
fn assert_close(what: &str, got: &[f32], want: &[f32], width: usize) {
    assert_eq!(got.len(), want.len(), "{what}: length");
    for (i, (&g, &w)) in got.iter().zip(want).enumerate() {
        let tol = 1e-5 * w.abs().max(1e-30);
        assert!(
            (g - w).abs() <= tol,
            "{what}: pixel (row {}, col {}): {g} vs reference {w}",
            i / width,
            i % width
        );
    }
}

#[test]
fn small_frame_equals_the_numpy_reference() {
    let scan = read_scan(&golden("small.bin")).unwrap();
    let calib = read_calibration(&golden("small_calib.txt")).unwrap();
    let (w, h) = (96, 32);
    let cases = [
        ("m13", 13, R0::GsMean),
        ("m5", 5, R0::GsMean),
        ("m13_nearest", 13, R0::Nearest),
        ("m1", 1, R0::GsMean),
        ("m63", 63, R0::GsMean),
    ];
    for (name, mask, r0) in cases {
        let m = maps(&scan, &calib, w, h, mask, r0).unwrap();
        let (shape, sr) = read_npy("small_rav_sparse.npy");
        assert_eq!(shape, [32, 96]);
        // The projection is exact: same pixels, same f32 values.
        assert_eq!(m.sparse_range, sr, "sparse range");
        assert_eq!(m.sparse_reflectance, read_npy("small_rev_sparse.npy").1);
        assert_close(
            &format!("{name} range"),
            &m.range,
            &read_npy(&format!("{name}_rav.npy")).1,
            w,
        );
        assert_close(
            &format!("{name} reflectance"),
            &m.reflectance,
            &read_npy(&format!("{name}_rev.npy")).1,
            w,
        );
        assert_eq!(m.projected.pixels, sr.iter().filter(|&&v| v > 0.0).count());
    }
}

#[test]
fn nearest_wins_and_ties_keep_the_first() {
    // Camera looking along x; every point below is on the ray through the centre.
    let calib = parse_calibration(
        Path::new("c.txt"),
        "P2: 2 0 2 0 0 2 2 0 0 0 1 0\nR0_rect: 1 0 0 0 1 0 0 0 1\n\
         Tr_velo_to_cam: 0 -1 0 0 0 0 -1 0 1 0 0 0\n",
    )
    .unwrap();
    let scan = [
        [5.0f32, 0.0, 0.0, 0.1],
        [4.0, 0.0, 0.0, 0.2],
        [4.0, 0.0, 0.0, 0.3],
        [-4.0, 0.0, 0.0, 0.4], // behind
        [0.0, 0.0, 0.0, 0.5],  // origin
    ];
    let m = maps(&scan, &calib, 5, 5, 1, R0::GsMean).unwrap();
    assert_eq!(m.sparse_range[12], 4.0);
    assert_eq!(m.sparse_reflectance[12], 0.2);
    assert_eq!(m.projected.kept, 3);
    assert_eq!(m.projected.pixels, 1);
}

#[test]
fn upsampling_in_place_equals_separate_buffers() {
    let scan = read_scan(&golden("small.bin")).unwrap();
    let calib = read_calibration(&golden("small_calib.txt")).unwrap();
    let m = maps(&scan, &calib, 96, 32, 7, R0::GsMean).unwrap();
    let mut pixels = vec![Pixel::default(); m.projected.pixels];
    lidar::collect_pixels(&m.sparse_range, &m.sparse_reflectance, 96, 32, &mut pixels).unwrap();
    let (mut r, mut f) = (vec![7.0f32; 96 * 32], vec![-3.0f32; 96 * 32]);
    let mut scratch = vec![0.0; lidar::scratch_len(7)];
    lidar::upsample(&pixels, 96, 32, 7, R0::GsMean, &mut scratch, &mut r, &mut f).unwrap();
    assert_eq!(r, m.range);
    assert_eq!(f, m.reflectance);
}

#[test]
fn bad_arguments_are_errors() {
    let mut img = vec![0.0f32; 12];
    let mut img2 = vec![0.0f32; 12];
    let mut s = vec![0.0f32; lidar::scratch_len(3)];
    let p = |col, row, range| Pixel {
        col,
        row,
        range,
        reflectance: 0.5,
    };
    let up = |px: &[Pixel], mask, s: &mut [f32], a: &mut [f32], b: &mut [f32]| {
        lidar::upsample(px, 4, 3, mask, R0::GsMean, s, a, b)
    };
    assert_eq!(
        up(&[], 2, &mut s, &mut img, &mut img2),
        Err(LidarError::Mask { mask: 2 })
    );
    assert_eq!(
        up(&[], 65, &mut s, &mut img, &mut img2),
        Err(LidarError::Mask { mask: 65 })
    );
    assert!(matches!(
        up(&[], 5, &mut s, &mut img, &mut img2),
        Err(LidarError::Scratch { .. })
    ));
    for (bad, index) in [
        (vec![p(1, 0, 1.0), p(0, 0, 1.0)], 1),
        (vec![p(1, 0, 1.0), p(1, 0, 2.0)], 1),
        (vec![p(4, 0, 1.0)], 0),
        (vec![p(0, 3, 1.0)], 0),
        (vec![p(0, 0, 0.0)], 0),
        (vec![p(0, 0, f32::NAN)], 0),
        (vec![p(0, 0, f32::INFINITY)], 0),
    ] {
        assert_eq!(
            up(&bad, 3, &mut s, &mut img, &mut img2),
            Err(LidarError::Pixel { index })
        );
    }
    let mut short = vec![0.0f32; 11];
    assert!(matches!(
        up(&[], 3, &mut s, &mut short, &mut img2),
        Err(LidarError::ImageLen { .. })
    ));
    let proj = lidar::Projection::from_matrix([[1.0, 0.0, 0.0, 0.0]; 3]);
    let nan = [[0.0, f32::NAN, 0.0, 0.0]];
    assert_eq!(
        lidar::project(&nan, &proj, 4, 3, &mut img, &mut img2),
        Err(LidarError::Point { index: 0 })
    );
    assert!(matches!(
        lidar::project(&[], &proj, 0, 3, &mut [], &mut []),
        Err(LidarError::ImageSize { .. })
    ));
    let mut none: [Pixel; 0] = [];
    img[5] = 1.0;
    assert!(matches!(
        lidar::collect_pixels(&img, &img2, 4, 3, &mut none),
        Err(LidarError::PixelCapacity { needed: 1, got: 0 })
    ));
}

#[test]
fn integer_scalings() {
    assert_eq!(lidar::range_to_u16(0.0), 0);
    assert_eq!(lidar::range_to_u16(1.0), 256);
    assert_eq!(lidar::range_to_u16(1.0 / 512.0), 1);
    assert_eq!(lidar::range_to_u16(300.0), 65535);
    assert_eq!(lidar::range_to_u16(f32::NAN), 0);
    assert_eq!(lidar::reflectance_to_u16(0.5), 32768);
    assert_eq!(lidar::reflectance_to_u16(2.0), 65535);
    assert_eq!(lidar::reflectance_to_u16(-1.0), 0);
    assert_eq!(lidar::range_to_u8(40.0, 80.0), 128);
    assert_eq!(lidar::range_to_u8(100.0, 80.0), 255);
    assert_eq!(lidar::range_to_u8(1.0, 0.0), 0);
    assert_eq!(lidar::reflectance_to_u8(1.0), 255);
}

#[test]
fn scan_reader_errors_name_the_file_and_point() {
    let p = Path::new("scan.bin");
    let e = parse_scan(p, &[0u8; 33]).unwrap_err().to_string();
    assert!(
        e.starts_with("scan.bin: 33 bytes") && e.contains("truncated"),
        "{e}"
    );
    let mut b = vec![0u8; 32];
    b[16 + 8..16 + 12].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = parse_scan(p, &b).unwrap_err().to_string();
    assert!(e.contains("point 1 (bytes 16..32): z is NaN"), "{e}");
    b[24..28].copy_from_slice(&f32::INFINITY.to_le_bytes());
    assert!(parse_scan(p, &b)
        .unwrap_err()
        .to_string()
        .contains("z is inf"));
    assert_eq!(parse_scan(p, &[]).unwrap(), Vec::<[f32; 4]>::new());
}

#[test]
fn calibration_reader_errors_name_the_line_and_key() {
    let good = std::fs::read_to_string(golden("small_calib.txt")).unwrap();
    let p = Path::new("calib.txt");
    assert!(parse_calibration(p, &good).is_ok());
    let cases = [
        (
            good.replace("R0_rect", "R1_rect"),
            "calib.txt: no R0_rect line",
        ),
        (
            good.replace(" 0.003\n", "\n"),
            "calib.txt:2: P2 has 11 numbers; expected 12",
        ),
        (
            good.replace("-0.27", "nan"),
            "calib.txt:4: Tr_velo_to_cam: nan is not finite",
        ),
        (
            good.replace("-0.27", "x1"),
            "calib.txt:4: Tr_velo_to_cam: `x1` is not a number",
        ),
        (
            format!("{good}P2: 1 2 3 4 5 6 7 8 9 10 11 12\n"),
            "calib.txt:6: P2 is given twice (first on line 2)",
        ),
        (
            format!("{good}garbage\n"),
            "calib.txt:6: expected `KEY: numbers`",
        ),
    ];
    for (text, want) in cases {
        let e = parse_calibration(p, &text).unwrap_err().to_string();
        assert!(e.starts_with(want), "{e} vs {want}");
    }
}

#[test]
fn label_windows_and_errors() {
    let p = Path::new("label.txt");
    let text = "Car 0.00 0 -1.58 10.2 3.0 20.9 7.5 1.5 1.6 3.9 -0.6 1.7 13.4 -1.6\n\
                DontCare -1 -1 -10 0.0 0.0 5.0 5.0 -1 -1 -1 -1000 -1000 -1000 -10\n\
                \n\
                Pedestrian 0 0 0 90.0 -4.0 120.0 40.0 1.8 0.6 0.8 1 1 9 0 0.93\n";
    let boxes = parse_labels(p, text, 96, 32).unwrap();
    assert_eq!(boxes.len(), 2);
    assert_eq!((boxes[0].0.kind.as_str(), boxes[0].0.line), ("Car", 1));
    let w = boxes[0].1;
    assert_eq!((w.col0, w.row0, w.col1, w.row1), (10, 3, 21, 8));
    let w = boxes[1].1;
    assert_eq!((w.col0, w.row0, w.col1, w.row1), (90, 0, 96, 32));
    for (bad, want) in [
        ("Car 0 0 0 1 2 3\n", "label.txt:1: 7 fields"),
        (
            "Car 0 0 0 5 1 4 2 1 1 1 0 0 0 0\n",
            "label.txt:1: the box 5 1 4 2 has left > right",
        ),
        (
            "Car 0 0 0 100 1 140 2 1 1 1 0 0 0 0\n",
            "label.txt:1: the box 100 1 140 2 has no pixel",
        ),
        (
            "Car 0 0 0 1 1 nan 2 1 1 1 0 0 0 0\n",
            "label.txt:1: field 7: `nan` is not a finite",
        ),
        (
            "../x 0 0 0 1 1 2 2 1 1 1 0 0 0 0\n",
            "label.txt:1: the type `../x`",
        ),
    ] {
        let e = parse_labels(p, bad, 96, 32).unwrap_err().to_string();
        assert!(e.starts_with(want), "{e} vs {want}");
    }
}

/// A random sparse map: (width, height, pixels in row-major order).
fn sparse_maps() -> impl Strategy<Value = (usize, usize, Vec<Pixel>)> {
    (1usize..20, 1usize..14).prop_flat_map(|(w, h)| {
        let cells = proptest::collection::vec(
            (proptest::bool::weighted(0.15), 0.01f32..90.0, -1.0f32..2.0),
            w * h,
        );
        cells.prop_map(move |c| {
            let px = c
                .iter()
                .enumerate()
                .filter(|(_, (on, _, _))| *on)
                .map(|(i, &(_, r, f))| Pixel {
                    col: (i % w) as u16,
                    row: (i / w) as u16,
                    range: r,
                    reflectance: f,
                })
                .collect();
            (w, h, px)
        })
    })
}

proptest! {
    /// Pixels with a point keep it; a pixel without one gets 0 when its mask holds no
    /// point, else a value within the min and max of its mask's points and within
    /// 1e-5 of the definition computed directly in f64.
    #[test]
    fn filter_properties(
        (w, h, px) in sparse_maps(),
        half in 0usize..5,
        nearest in any::<bool>(),
    ) {
        let mask = 2 * half + 1;
        let r0 = if nearest { R0::Nearest } else { R0::GsMean };
        let (mut r, mut f) = (vec![0.0f32; w * h], vec![0.0f32; w * h]);
        let mut s = vec![0.0f32; lidar::scratch_len(mask)];
        lidar::upsample(&px, w, h, mask, r0, &mut s, &mut r, &mut f).unwrap();
        for row in 0..h {
            for col in 0..w {
                let i = row * w + col;
                let pts: Vec<&Pixel> = px
                    .iter()
                    .filter(|p| usize::from(p.col).abs_diff(col) <= half
                        && usize::from(p.row).abs_diff(row) <= half)
                    .collect();
                if let Some(p) = pts.iter().find(|p| usize::from(p.col) == col && usize::from(p.row) == row) {
                    prop_assert_eq!((r[i], f[i]), (p.range, p.reflectance));
                    continue;
                }
                if pts.is_empty() {
                    prop_assert_eq!((r[i], f[i]), (0.0, 0.0));
                    continue;
                }
                for (out, get) in [(r[i], (|p: &Pixel| p.range) as fn(&Pixel) -> f32), (f[i], |p: &Pixel| p.reflectance)] {
                    let lo = pts.iter().map(|p| get(p)).fold(f32::INFINITY, f32::min);
                    let hi = pts.iter().map(|p| get(p)).fold(f32::NEG_INFINITY, f32::max);
                    prop_assert!(out >= lo && out <= hi, "{} outside [{}, {}]", out, lo, hi);
                    // The definition, directly, in f64.
                    let gs = |p: &Pixel| {
                        let dx = usize::from(p.col).abs_diff(col) as f64;
                        let dy = usize::from(p.row).abs_diff(row) as f64;
                        1.0 / (1.0 + (dx * dx + dy * dy).sqrt())
                    };
                    let r0v = if nearest {
                        let d2 = |p: &Pixel| usize::from(p.col).abs_diff(col).pow(2) + usize::from(p.row).abs_diff(row).pow(2);
                        let best = pts.iter().min_by_key(|p| d2(p)).unwrap();
                        f64::from(get(best))
                    } else {
                        pts.iter().map(|p| gs(p) * f64::from(get(p))).sum::<f64>() / pts.iter().map(|p| gs(p)).sum::<f64>()
                    };
                    let wt = |p: &Pixel| gs(p) / (1.0 + (r0v - f64::from(get(p))).abs());
                    let want = pts.iter().map(|p| wt(p) * f64::from(get(p))).sum::<f64>() / pts.iter().map(|p| wt(p)).sum::<f64>();
                    let scale = pts.iter().map(|p| f64::from(get(p)).abs()).fold(0.0, f64::max);
                    prop_assert!((f64::from(out) - want).abs() <= 1e-5 * scale, "{} vs {}", out, want);
                }
            }
        }
    }
}
