//! Times the LiDAR maps of DESIGN §9 on one frame, in-process: the Rust side of
//! `tools/lidar_bench.py`.
//!
//! Reads the scan and calibration (not timed), then runs the device path over
//! preallocated buffers — [`lidar::project`], [`lidar::collect_pixels`] and
//! [`lidar::upsample`] — several times on one core, and prints the median and best time
//! of a whole frame on one `key=value` line:
//!
//! ```text
//! cargo run --release --features std --example lidar_timing -- VELODYNE CALIB [W H MASK REPS]
//! ```

use std::hint::black_box;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use mlmap::host::lidar::{read_calibration, read_scan};
use mlmap::lidar::{self, Pixel, R0};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(scan), Some(calib)) = (args.first(), args.get(1)) else {
        eprintln!("usage: lidar_timing VELODYNE CALIB [WIDTH HEIGHT MASK REPS]");
        return ExitCode::from(2);
    };
    let num = |i: usize, d: usize| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(d);
    let (w, h, mask, reps) = (num(2, 1242), num(3, 375), num(4, 13), num(5, 21));
    let (points, calib) = match (
        read_scan(Path::new(scan)),
        read_calibration(Path::new(calib)),
    ) {
        (Ok(p), Ok(c)) => (p, c),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("lidar_timing: {e}");
            return ExitCode::from(2);
        }
    };
    let proj = calib.projection();
    let (mut range, mut refl) = (vec![0.0f32; w * h], vec![0.0f32; w * h]);
    let mut pixels = vec![Pixel::default(); points.len()];
    let mut scratch = vec![0.0f32; lidar::scratch_len(mask)];
    let mut times = Vec::with_capacity(reps);
    let mut n = 0;
    for _ in 0..reps {
        let t0 = Instant::now();
        let mut run = || -> Result<usize, lidar::LidarError> {
            lidar::project(black_box(&points), &proj, w, h, &mut range, &mut refl)?;
            let n = lidar::collect_pixels(&range, &refl, w, h, &mut pixels)?;
            let px = pixels.get(..n).unwrap_or(&[]);
            lidar::upsample(
                px,
                w,
                h,
                mask,
                R0::GsMean,
                &mut scratch,
                &mut range,
                &mut refl,
            )?;
            Ok(n)
        };
        match run() {
            Ok(k) => n = k,
            Err(e) => {
                eprintln!("lidar_timing: {e}");
                return ExitCode::from(1);
            }
        }
        times.push(t0.elapsed().as_secs_f64());
        black_box(&range);
    }
    times.sort_by(f64::total_cmp);
    println!(
        "points={} pixels={n} width={w} height={h} mask={mask} reps={reps} median_ms={:.2} best_ms={:.2}",
        points.len(),
        1e3 * times[times.len() / 2],
        1e3 * times[0]
    );
    ExitCode::SUCCESS
}
