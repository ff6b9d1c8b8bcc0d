//! The LiDAR maps (DESIGN §9) of a generated frame against numpy's.

use super::*;

/// The LiDAR maps (DESIGN §9) of a 24 x 12 frame with a 5 x 5 mask against the numpy
/// reference, within 1e-5 relative; returns the largest relative deviation.
pub(crate) fn check_lidar(r: &mut Report) -> f64 {
    use lidar_expected::{HEIGHT, MASK, POINTS, PROJECTION, RANGE, REFLECTANCE, WIDTH};
    use mlmap::lidar::{self, Pixel, Projection, R0};
    const N: usize = WIDTH * HEIGHT;
    let mut range = [0.0f32; N];
    let mut refl = [0.0f32; N];
    let mut pixels = [Pixel::default(); POINTS.len()];
    let mut scratch = [0.0f32; lidar::scratch_len(MASK)];
    let proj = Projection::from_matrix(black_box(PROJECTION));
    let maps = lidar::project(
        black_box(&POINTS),
        &proj,
        WIDTH,
        HEIGHT,
        &mut range,
        &mut refl,
    )
    .and_then(|_| lidar::collect_pixels(&range, &refl, WIDTH, HEIGHT, &mut pixels))
    .and_then(|n| {
        let list = pixels.get(..n).unwrap_or(&[]);
        let r0 = R0::GsMean;
        lidar::upsample(
            list,
            WIDTH,
            HEIGHT,
            MASK,
            r0,
            &mut scratch,
            &mut range,
            &mut refl,
        )
    });
    if let Err(e) = maps {
        r.check(false, "lidar maps", format_args!("{e:?}"));
        return f64::NAN;
    }
    let mut worst = 0.0f64;
    for (what, got, want) in [
        ("range", &range, &RANGE),
        ("reflectance", &refl, &REFLECTANCE),
    ] {
        for (i, (&g, &w)) in got.iter().zip(want.iter()).enumerate() {
            let (g64, w64) = (f64::from(g), f64::from(w));
            let err = (g64 - w64).abs() / w64.abs().max(1e-30);
            worst = worst.max(err);
            r.check(
                err <= 1e-5,
                "lidar map",
                format_args!(
                    "{what} at row {}, col {}: got {g}, numpy {w}",
                    i / WIDTH,
                    i % WIDTH
                ),
            );
        }
    }
    worst
}
