//! Any bytes through the LiDAR readers (DESIGN §9.1) give points and matrices that the
//! maps accept, or an error that names the file; never a panic.
//!
//! The first byte picks the reader: even, the velodyne scan reader on the rest; odd, the
//! calibration reader on the rest as text, whose matrices then project and upsample a
//! fixed scan. When a scan reads, it is projected with a fixed calibration and upsampled
//! on a 40 x 12 image; every dense value must be 0 or within the range of the kept
//! points' values, and pixels with a point keep it.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use mlmap::host::lidar::{maps, parse_calibration, parse_scan};
use mlmap::lidar::{Calibration, R0};

const CALIB: &str = "P2: 10 0 20 0 0 10 6 0 0 0 1 0\nR0_rect: 1 0 0 0 1 0 0 0 1\n\
                     Tr_velo_to_cam: 0 -1 0 0 0 0 -1 0 1 0 0 0\n";
const SCAN: [[f32; 4]; 4] = [
    [5.0, 0.0, 0.0, 0.5],
    [6.0, 1.0, 0.5, 0.1],
    [7.0, -2.0, -0.5, 0.9],
    [-3.0, 0.0, 0.0, 0.2],
];

fn check(points: &[[f32; 4]], calib: &Calibration) {
    let m = maps(points, calib, 40, 12, 5, R0::GsMean).expect("valid points and sizes");
    let (lo, hi) = points
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p[3]), hi.max(p[3]))
        });
    for i in 0..m.range.len() {
        if m.sparse_range[i] > 0.0 {
            assert_eq!(m.range[i], m.sparse_range[i], "pixel {i} lost its point");
            assert_eq!(m.reflectance[i], m.sparse_reflectance[i]);
        } else if m.range[i] != 0.0 {
            assert!(
                m.range[i] > 0.0 && m.range[i].is_finite(),
                "pixel {i}: range {}",
                m.range[i]
            );
            assert!(
                m.reflectance[i] >= lo && m.reflectance[i] <= hi,
                "pixel {i}: reflectance"
            );
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    if mode % 2 == 0 {
        match parse_scan(Path::new("fuzz.bin"), rest) {
            Ok(points) => {
                assert_eq!(points.len() * 16, rest.len());
                let calib = parse_calibration(Path::new("c.txt"), CALIB).expect("valid");
                check(&points, &calib);
            }
            Err(e) => assert!(e.to_string().starts_with("fuzz.bin: "), "{e}"),
        }
    } else {
        let Ok(text) = std::str::from_utf8(rest) else {
            return;
        };
        match parse_calibration(Path::new("fuzz.txt"), text) {
            Ok(calib) => check(&SCAN, &calib),
            Err(e) => assert!(e.to_string().starts_with("fuzz.txt"), "{e}"),
        }
    }
});
