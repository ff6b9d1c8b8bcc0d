//! `mlmap lidar-maps`: the range-view and reflectance-view maps of a KITTI scan
//! (DESIGN §9), as NPY arrays and 16-bit PNG images, with the crops of labelled objects.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use mlmap::host::lidar::{self, Maps, Window};
use mlmap::lidar::{range_to_u16, reflectance_to_u16, LidarError, MAX_MASK, MAX_SIDE, R0};
use npyz::WriterBuilder;

use crate::error::{CliError, Result};
use crate::output;

/// The value the range kernel compares with at a pixel without a point (DESIGN §9.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum R0Arg {
    /// The G_s-weighted mean of the mask's points.
    GsMean,
    /// The value of the mask's nearest point.
    Nearest,
}

/// Flags of `lidar-maps`.
#[derive(Debug, Args)]
pub struct LidarMapsArgs {
    /// The KITTI velodyne scan (x, y, z, reflectance as little-endian f32 per point).
    #[arg(long, value_name = "FILE")]
    pub velodyne: PathBuf,
    /// The KITTI calibration file (P2, R0_rect, Tr_velo_to_cam).
    #[arg(long, value_name = "FILE")]
    pub calib: PathBuf,
    /// Image width in pixels.
    #[arg(long, default_value_t = 1242, value_name = "N")]
    pub width: usize,
    /// Image height in pixels.
    #[arg(long, default_value_t = 375, value_name = "N")]
    pub height: usize,
    /// Side of the bilateral filter's square mask (odd, 1 to 63).
    #[arg(long, default_value_t = 13, value_name = "C")]
    pub mask: usize,
    /// r0 at a pixel without a point.
    #[arg(long, value_enum, default_value_t = R0Arg::GsMean)]
    pub r0: R0Arg,
    /// Also write the projection's sparse maps (rav_sparse.*, rev_sparse.*).
    #[arg(long)]
    pub sparse: bool,
    /// A KITTI label file: write the crop of both maps under every object's 2-D box.
    #[arg(long, value_name = "FILE")]
    pub boxes: Option<PathBuf>,
    /// The output directory (created if missing).
    #[arg(long, short, value_name = "DIR")]
    pub output: PathBuf,
}

pub fn run(a: &LidarMapsArgs) -> Result<()> {
    if a.mask.is_multiple_of(2) || a.mask > MAX_MASK {
        return Err(CliError::Input(format!(
            "--mask {} is out of range: expected an odd number from 1 to {MAX_MASK}",
            a.mask
        )));
    }
    for (flag, v) in [("width", a.width), ("height", a.height)] {
        if v == 0 || v > MAX_SIDE {
            return Err(CliError::Input(format!(
                "--{flag} {v} is out of range: expected 1 to {MAX_SIDE}"
            )));
        }
    }
    let mut inputs: Vec<&Path> = vec![&a.velodyne, &a.calib];
    if let Some(b) = &a.boxes {
        inputs.push(b);
    }
    let mut names = vec!["rav.npy", "rev.npy", "rav.png", "rev.png"];
    if a.sparse {
        names.extend([
            "rav_sparse.npy",
            "rev_sparse.npy",
            "rav_sparse.png",
            "rev_sparse.png",
        ]);
    }
    if a.output.exists() && !a.output.is_dir() {
        return Err(CliError::input(
            &a.output,
            "is not a directory; --output names the directory of the maps",
        ));
    }
    // A directory that does not exist yet holds no input; it is created after the maps
    // are computed, so a bad input leaves nothing behind.
    if a.output.is_dir() {
        for name in &names {
            output::check_outputs(&a.output.join(name), &inputs)?;
        }
    }
    let points = lidar::read_scan(&a.velodyne)?;
    let calib = lidar::read_calibration(&a.calib)?;
    let boxes = match &a.boxes {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| CliError::input(path, e))?;
            Some(lidar::parse_labels(path, &text, a.width, a.height)?)
        }
        None => None,
    };
    let r0 = match a.r0 {
        R0Arg::GsMean => R0::GsMean,
        R0Arg::Nearest => R0::Nearest,
    };
    let maps = lidar::maps(&points, &calib, a.width, a.height, a.mask, r0)
        .map_err(|e| lidar_error(&a.velodyne, e))?;
    std::fs::create_dir_all(&a.output)
        .map_err(|e| CliError::input(&a.output, format!("cannot create: {e}")))?;
    let (w, h) = (a.width, a.height);
    let mut written = Vec::new();
    let mut files: Vec<MapFile<'_>> = vec![
        ("rav", &maps.range, range_to_u16),
        ("rev", &maps.reflectance, reflectance_to_u16),
    ];
    if a.sparse {
        files.push(("rav_sparse", &maps.sparse_range, range_to_u16));
        files.push(("rev_sparse", &maps.sparse_reflectance, reflectance_to_u16));
    }
    for (stem, map, scale) in files {
        let npy = a.output.join(format!("{stem}.npy"));
        write_npy(&npy, &[h as u64, w as u64], map)?;
        let png = a.output.join(format!("{stem}.png"));
        write_png(&png, w, h, map, scale)?;
        written.extend([npy, png]);
    }
    if let Some(boxes) = &boxes {
        written.extend(write_crops(&a.output, &maps, boxes, &inputs)?);
    }
    let mut text = format!(
        "{}: {} points, {} in the {w} x {h} image, {} pixels with a point ({:.2} %); \
         mask {} x {}\n",
        a.velodyne.display(),
        points.len(),
        maps.projected.kept,
        maps.projected.pixels,
        100.0 * maps.projected.pixels as f64 / (w * h) as f64,
        a.mask,
        a.mask
    );
    for p in &written {
        let _ = writeln!(text, "wrote {}", p.display());
    }
    output::print(&text)
}

/// A map to write: its file stem, values and 16-bit scaling (DESIGN §9.4).
type MapFile<'a> = (&'a str, &'a [f32], fn(f32) -> u16);

/// A library error as the CLI reports it.
fn lidar_error(velodyne: &Path, e: LidarError) -> CliError {
    match e {
        LidarError::Point { index } => CliError::input(
            velodyne,
            format!("point {index}: a value is not finite or above 1e18"),
        ),
        e => CliError::Internal(format!("lidar-maps: {e}")),
    }
}

/// Writes a `f32` array of `shape` as NPY.
fn write_npy(path: &Path, shape: &[u64], data: &[f32]) -> Result<()> {
    let werr = |e: std::io::Error| CliError::internal(path, format!("cannot write: {e}"));
    output::write_atomic(path, |w| {
        let mut npy = npyz::WriteOptions::new()
            .default_dtype()
            .shape(shape)
            .writer(w)
            .begin_nd()
            .map_err(werr)?;
        npy.extend(data.iter().copied()).map_err(werr)?;
        npy.finish().map_err(werr)
    })
}

/// Writes a map as a 16-bit grayscale PNG through `scale` (DESIGN §9.4).
fn write_png(
    path: &Path,
    width: usize,
    height: usize,
    map: &[f32],
    scale: fn(f32) -> u16,
) -> Result<()> {
    let bytes: Vec<u8> = map.iter().flat_map(|&v| scale(v).to_be_bytes()).collect();
    let perr = |e: png::EncodingError| CliError::internal(path, format!("cannot write: {e}"));
    output::write_atomic(path, |w| {
        // Both sides are at most 65535 (checked by `run`).
        let mut enc = png::Encoder::new(w, width as u32, height as u32);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        let mut writer = enc.write_header().map_err(perr)?;
        writer.write_image_data(&bytes).map_err(perr)?;
        writer.finish().map_err(perr)
    })
}

/// Writes `crops/NNN_<type>.npy` for every object and `crops/crops.csv`.
fn write_crops(
    dir: &Path,
    maps: &Maps,
    boxes: &[(lidar::LabelBox, Window)],
    inputs: &[&Path],
) -> Result<Vec<PathBuf>> {
    let crops = dir.join("crops");
    std::fs::create_dir_all(&crops)
        .map_err(|e| CliError::input(&crops, format!("cannot create: {e}")))?;
    let mut csv = String::from("index,type,col0,row0,col1,row1\n");
    let mut written = Vec::new();
    for (i, (b, win)) in boxes.iter().enumerate() {
        let path = crops.join(format!("{i:03}_{}.npy", b.kind));
        output::check_outputs(&path, inputs)?;
        let shape = [
            2,
            (win.row1 - win.row0) as u64,
            (win.col1 - win.col0) as u64,
        ];
        write_npy(&path, &shape, &lidar::crop(maps, *win))?;
        let _ = writeln!(
            csv,
            "{i},{},{},{},{},{}",
            b.kind, win.col0, win.row0, win.col1, win.row1
        );
        written.push(path);
    }
    let index = crops.join("crops.csv");
    output::check_outputs(&index, inputs)?;
    output::write_bytes_atomic(&index, csv.as_bytes())?;
    written.push(index);
    Ok(written)
}
