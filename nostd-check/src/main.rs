//! Link-time proofs that mlmap's decode and inference need neither std nor an allocator,
//! and that no panic path survives optimisation.
//!
//! * **No std**: the crate is `#![no_std]` and links against `core` and the C library's
//!   startup code only.
//! * **No allocator**: `.ci/nostd.sh` checks that `nm -u` of the binary lists no
//!   `malloc`, `calloc`, `realloc` or `free`.
//! * **No panic**: the panic handler calls [`mlmap_panic_path_reachable`], a symbol that
//!   exists nowhere. Every input reaches the library through [`black_box`], so the
//!   optimiser cannot prove anything about it; if any panic path (a bounds check, an
//!   `unwrap`, an overflow, a formatting panic) survives in decode or inference, the
//!   handler is referenced and the link fails with an undefined symbol.
//!
//! Every head is linked: ML, MAP, Bayes and the open head (DESIGN §1.8), per detection,
//! in batches and through the run-time shaped [`TableView`](mlmap::TableView) with
//! slices of opaque lengths, on the shipped table and on a small table whose open head
//! has an unknown category (epsilon > 0).
//!
//! Running the binary also checks a few results, so a build that links but computes
//! nonsense does not pass: exit status 0 means every check held.
#![no_std]
#![no_main]

use core::ffi::{c_char, c_int};
use core::hint::black_box;

use mlmap::embedded::{EmbeddedTable, TABLE};
use mlmap::{FastMath, Head, InferError, Libm, Scores, Table};

/// The table shipped with the crate, as firmware would read it from a flash sector.
static TABLE_BYTES: &[u8] = include_bytes!("../../tables/default.mlmap");

/// A small table whose open head has an unknown category (temperature 1.75, epsilon
/// 0.05; K = 3, 4 ML bins, 2 MAP bins, 4 Bayes bins, 4 categories).
static SMALL_OPEN_BYTES: &[u8] = include_bytes!("../../tests/golden/layer/small_open.mlmap");

/// The same classes and Bayes head in format version 2: no open head.
static SMALL_V2_BYTES: &[u8] = include_bytes!("../../tests/golden/layer/small_bayes.mlmap");

/// The small tables' type.
type SmallOpen = Table<3, 4, 2, 4, 4>;

/// The small open table with a recalibration map on every head (DESIGN §1.9).
static SMALL_MAPS_BYTES: &[u8] = include_bytes!("../../tests/golden/layer/small_maps.mlmap");

/// Its type: room for maps of up to `MAX_KNOTS` knots per head.
type SmallMaps = Table<3, 4, 2, 4, 4, { mlmap::MAX_KNOTS }>;

extern "C" {
    /// Deliberately defined nowhere: referencing it fails the link.
    fn mlmap_panic_path_reachable() -> !;
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    // SAFETY: never executed; a reachable call makes the link fail.
    unsafe { mlmap_panic_path_reachable() }
}

/// The sum of the scores, or NaN when one is not finite and in `[0, os]`.
fn checked_sum<const K: usize>(s: &Scores<K>, os: f32) -> f32 {
    let mut sum = 0.0f32;
    for &v in s.as_array() {
        if !(v >= 0.0 && v <= os) {
            return f32::NAN;
        }
        sum += v;
    }
    sum
}

/// `true` when the scores are finite, in `[0, os]` and sum to `os`.
fn sane<const K: usize>(s: &Scores<K>, os: f32) -> bool {
    (checked_sum(s, os) - os).abs() <= 1e-5
}

/// `true` when the scores are finite, in `[0, os]` and sum to at most `os` (the Bayes
/// head of a table with a background category keeps the background's share out).
fn sane_at_most<const K: usize>(s: &Scores<K>, os: f32) -> bool {
    checked_sum(s, os) <= os + 1e-5
}

/// The index of the largest logit, the lower among equal ones: the open head's decision.
fn largest(logits: &[f32; 3]) -> usize {
    let (mut best, mut top) = (0, logits[0]);
    for (i, &x) in logits.iter().enumerate() {
        if x > top {
            (best, top) = (i, x);
        }
    }
    best
}

/// Scores one detection with the open head of `table` (FastMath, the default, and libm)
/// and checks the results: in `[0, os]`, summing to at most `os`, the decision the
/// largest logit.
fn score_open<const B_ML: usize, const B_MAP: usize, const BB: usize, const C: usize>(
    table: &Table<3, B_ML, B_MAP, BB, C>,
    logits: &[f32; 3],
    os: f32,
) -> Result<u32, InferError> {
    let mut failed = 0;
    for open in [
        table.open(logits, os)?,
        table.open_with::<Libm>(logits, os)?,
    ] {
        failed += u32::from(!sane_at_most(&open, os));
        failed += u32::from(open.decide(logits) != largest(logits));
    }
    Ok(failed)
}

/// Scores one detection with every head of the table with maps and of the same table
/// without them (`raw`), and checks what a map keeps: the scores in `[0, 1]`, the top
/// score `g(top)` of the head's map, and the decision.
fn score_mapped(
    table: &SmallMaps,
    raw: &SmallOpen,
    logits: &[f32; 3],
    os: f32,
) -> Result<u32, InferError> {
    let mut failed = 0;
    for (head, mapped, own) in [
        (Head::Ml, table.ml(logits, os)?, raw.ml(logits, os)?),
        (Head::Map, table.map(logits, os)?, raw.map(logits, os)?),
        (
            Head::Bayes,
            table.bayes(logits, os)?,
            raw.bayes(logits, os)?,
        ),
        (Head::Open, table.open(logits, os)?, raw.open(logits, os)?),
    ] {
        let Some(g) = table.recal_map(head) else {
            failed += 1;
            continue;
        };
        let top = own.as_array().iter().fold(0.0f32, |m, &v| m.max(v));
        let want = if top > 0.0 { g.eval(top) } else { 0.0 };
        failed += u32::from(mapped.as_array().iter().fold(0.0f32, |m, &v| m.max(v)) != want);
        failed += u32::from(!mapped.as_array().iter().all(|&v| (0.0..=1.0).contains(&v)));
        failed += u32::from(mapped.decide(logits) != own.decide(logits));
    }
    Ok(failed)
}

/// Scores one detection with every head of `table` (ML, MAP, Bayes, open) and checks
/// the results.
fn score(table: &EmbeddedTable, logits: &[f32; 3], os: f32) -> Result<u32, InferError> {
    let mut failed = 0;
    let ml = table.ml(logits, os)?;
    let map = table.map(logits, os)?;
    let bayes = table.bayes(logits, os)?;
    failed += u32::from(!sane(&ml, os)) + u32::from(!sane(&map, os));
    failed += u32::from(!sane_at_most(&bayes, os));
    failed += score_open(table, logits, os)?;
    failed += u32::from(ml.argmax() >= 3) + u32::from(table.class_name(map.argmax()).is_none());
    failed += u32::from(table.class_name(bayes.argmax()).is_none());
    #[cfg(feature = "micromath")]
    {
        let fast = table.map_with::<mlmap::Micromath>(logits, os)?;
        failed += u32::from(!sane(&fast, os));
        let fast = table.bayes_with::<mlmap::Micromath>(logits, os)?;
        failed += u32::from(!sane_at_most(&fast, os));
    }
    Ok(failed)
}

/// A NaN logit the optimiser cannot see.
fn nan_input() -> [f32; 3] {
    black_box([f32::NAN, 0.0, 0.0])
}

/// All checks; returns the number that failed.
fn run() -> u32 {
    let mut failed = 0;

    // Way 1: decode at start-up, CRC and invariants checked.
    let decoded = match EmbeddedTable::from_bytes(black_box(TABLE_BYTES)) {
        Ok(t) => t,
        Err(_) => return 100,
    };
    // Decoding must reject a corrupted copy, never panic.
    let mut corrupt = [0u8; EmbeddedTable::MAX_ENCODED_LEN];
    let n = TABLE_BYTES.len().min(corrupt.len());
    corrupt[..n].copy_from_slice(&TABLE_BYTES[..n]);
    if let Some(b) = corrupt.get_mut(black_box(n / 2)) {
        *b ^= black_box(0x10);
    }
    failed += u32::from(EmbeddedTable::from_bytes(black_box(&corrupt[..n])).is_ok());

    // Way 2: the table embedded at build time must equal the decoded one.
    let embedded: &EmbeddedTable = black_box(&TABLE);
    failed += u32::from(*embedded != decoded);

    // Encoding round trip into a static-sized buffer.
    let mut buf = [0u8; EmbeddedTable::MAX_ENCODED_LEN];
    match decoded.to_slice(black_box(&mut buf)) {
        Ok(bytes) => failed += u32::from(*bytes != *TABLE_BYTES),
        Err(_) => failed += 1,
    }

    // Inference, per detection, on opaque inputs.
    let inputs: [([f32; 3], f32); 4] = black_box([
        ([5.1, -2.0, -1.3], 0.93),
        ([-1.0, 3.2, -0.5], 1.0),
        ([1e6, -1e6, f32::INFINITY], 0.5),
        ([0.0, 0.0, 0.0], 0.0),
    ]);
    // The small table with an unknown category: its open head, decoded at run time.
    let small = match SmallOpen::from_bytes(black_box(SMALL_OPEN_BYTES)) {
        Ok(t) => t,
        Err(_) => return 101,
    };
    for (logits, os) in &inputs {
        for table in [&decoded, embedded] {
            match score(table, logits, *os) {
                Ok(f) => failed += f,
                Err(_) => failed += 1,
            }
        }
        match score_open(&small, logits, *os) {
            Ok(f) => failed += f,
            Err(_) => failed += 1,
        }
    }
    // The same table with a map on every head, decoded at run time: every head after
    // its map, one detection at a time and in batches.
    let maps = match SmallMaps::from_bytes(black_box(SMALL_MAPS_BYTES)) {
        Ok(t) => t,
        Err(_) => return 102,
    };
    for (logits, os) in &inputs {
        match score_mapped(&maps, &small, logits, *os) {
            Ok(f) => failed += f,
            Err(_) => failed += 1,
        }
    }
    failed += u32::from(maps.open(&nan_input(), 1.0).is_ok());
    failed += u32::from(SmallOpen::from_bytes(black_box(SMALL_MAPS_BYTES)).is_ok());
    {
        let logits: [[f32; 3]; 4] = black_box(inputs.map(|(l, _)| l));
        let os: [f32; 4] = black_box(inputs.map(|(_, o)| o));
        let mut out = [[0.0f32; 3]; 4];
        failed += u32::from(maps.ml_batch(&logits, Some(&os), &mut out).is_err());
        failed += u32::from(maps.map_batch(&logits, Some(&os), &mut out).is_err());
        failed += u32::from(maps.bayes_batch(&logits, Some(&os), &mut out).is_err());
        failed += u32::from(maps.open_batch(&logits, Some(&os), &mut out).is_err());
    }
    // Far outside every Bayes axis the unknown category outweighs the known ones: the
    // open head's scores are far below the objectness.
    match small.open(&black_box([-1e3, 1e3, -1e3]), 1.0) {
        Ok(s) => failed += u32::from(s.confidence() >= 0.01 || s.decide(&[-1e3, 1e3, -1e3]) != 1),
        Err(_) => failed += 1,
    }
    // A version-2 table has no open head: asking is an error, not a panic.
    match SmallOpen::from_bytes(black_box(SMALL_V2_BYTES)) {
        Ok(t) => failed += u32::from(t.open(&[0.0; 3], 1.0) != Err(InferError::NoOpenHead)),
        Err(_) => failed += 1,
    }

    // The run-time shaped view, with slices of lengths the optimiser cannot see: a
    // length that does not fit is an error, never an out-of-bounds access.
    let view = decoded.view();
    let x = black_box([5.1f32, -2.0, -1.3, 0.5]);
    let mut out = [0.0f32; 4];
    let mut scratch = [0.0f32; 5];
    let (nx, no, ns) = black_box((3usize, 3usize, 4usize));
    let (x, o, s) = (
        x.get(..nx).unwrap_or(&[]),
        out.get_mut(..no).unwrap_or(&mut []),
        scratch.get_mut(..ns).unwrap_or(&mut []),
    );
    failed += u32::from(view.open_into::<FastMath>(x, 0.9, o, s).is_err());
    failed += u32::from(
        view.score_into(black_box(Head::Open), x, 0.9, o, s)
            .is_err(),
    );
    let short = black_box(2usize);
    failed += u32::from(
        view.open_into::<FastMath>(x, 0.9, o, s.get_mut(..short).unwrap_or(&mut []))
            .is_ok(),
    );
    failed += u32::from(
        view.open_into::<Libm>(x.get(..short).unwrap_or(&[]), 0.9, o, s)
            .is_ok(),
    );
    // Invalid inputs are errors, not panics.
    let nan = black_box([f32::NAN, 0.0, 0.0]);
    failed += u32::from(decoded.ml(&nan, 1.0).is_ok() || decoded.map(&nan, 1.0).is_ok());
    failed += u32::from(decoded.bayes(&nan, 1.0).is_ok());
    failed += u32::from(decoded.open(&nan, 1.0).is_ok() || small.open(&nan, 1.0).is_ok());
    failed += u32::from(small.open(&[0.0; 3], black_box(f32::NAN)).is_ok());
    failed += u32::from(decoded.ml(&[0.0; 3], black_box(1.5)).is_ok());
    failed += u32::from(embedded.bayes(&[0.0; 3], black_box(1.5)).is_ok());

    // Batches into caller-provided buffers.
    let logits: [[f32; 3]; 4] = black_box(inputs.map(|(l, _)| l));
    let os: [f32; 4] = black_box(inputs.map(|(_, o)| o));
    let mut out = [[0.0f32; 3]; 4];
    failed += u32::from(decoded.ml_batch(&logits, Some(&os), &mut out).is_err());
    failed += u32::from(embedded.map_batch(&logits, None, &mut out).is_err());
    failed += u32::from(decoded.bayes_batch(&logits, Some(&os), &mut out).is_err());
    failed += u32::from(decoded.open_batch(&logits, Some(&os), &mut out).is_err());
    failed += u32::from(small.open_batch(&logits, None, &mut out).is_err());
    failed += u32::from(
        embedded
            .open_batch(&logits, Some(&os[..3]), &mut out)
            .is_ok(),
    );
    #[cfg(feature = "micromath")]
    {
        failed += u32::from(
            decoded
                .map_batch_with::<mlmap::Micromath>(&logits, Some(&os), &mut out)
                .is_err(),
        );
    }
    failed += u32::from(decoded.ml_batch(&logits, Some(&os[..3]), &mut out).is_ok());
    black_box(&out);

    failed += lidar_maps();

    #[cfg(feature = "canary")]
    {
        // A bounds check the optimiser cannot remove: the link must fail.
        failed += u32::from(TABLE_BYTES[black_box(usize::MAX)]);
    }
    failed
}

/// The LiDAR maps (DESIGN §9): projection, the pixel list and the upsampling of a
/// 16 x 8 frame with opaque sizes, mask and buffers; returns the failed checks.
fn lidar_maps() -> u32 {
    use mlmap::lidar::{self, Calibration, Pixel, R0};
    let mut failed = 0;
    // A camera looking along the LiDAR's x axis, focal length 4 px, centre (8, 4).
    let calib = black_box(Calibration {
        p2: [
            [4.0, 0.0, 8.0, 0.0],
            [0.0, 4.0, 4.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        r0_rect: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        tr_velo_to_cam: [
            [0.0, -1.0, 0.0, 0.0],
            [0.0, 0.0, -1.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
        ],
    });
    let points: [[f32; 4]; 4] = black_box([
        [4.0, 0.0, 0.0, 0.5],
        [4.0, 2.0, 0.0, 0.25],
        [-4.0, 0.0, 0.0, 1.0],
        [8.0, -4.0, 2.0, 0.75],
    ]);
    let (w, h, mask) = black_box((16usize, 8usize, 5usize));
    let mut range = [0.0f32; 128];
    let mut refl = [0.0f32; 128];
    let mut pixels = [Pixel::default(); 4];
    let mut scratch = [0.0f32; lidar::scratch_len(5)];
    let proj = calib.projection();
    let len = black_box(128usize);
    let (Some(r), Some(f)) = (range.get_mut(..len), refl.get_mut(..len)) else {
        return 1;
    };
    let buffers = (r, f);
    let n = match lidar::project(&points, &proj, w, h, buffers.0, buffers.1)
        .and_then(|_| lidar::collect_pixels(buffers.0, buffers.1, w, h, &mut pixels))
    {
        Ok(n) => n,
        Err(_) => return 1,
    };
    failed += u32::from(n != 3);
    let list = pixels.get(..n).unwrap_or(&[]);
    let r0 = black_box(R0::GsMean);
    match lidar::upsample(list, w, h, mask, r0, &mut scratch, buffers.0, buffers.1) {
        // The centre keeps its point; its right neighbour lies between its mask's two
        // points (ranges 4 and sqrt(84)).
        Ok(()) => {
            let c = buffers.0.get(black_box(4 * 16 + 8)).copied();
            let right = buffers.0.get(black_box(4 * 16 + 9)).copied().unwrap_or(0.0);
            failed += u32::from(c != Some(4.0) || !(right > 4.0 && right < 9.17));
            failed += u32::from(lidar::range_to_u16(c.unwrap_or(0.0)) != 1024);
        }
        Err(_) => failed += 1,
    }
    let bad = black_box(4usize);
    failed +=
        u32::from(lidar::upsample(list, w, h, bad, r0, &mut scratch, buffers.0, buffers.1).is_ok());
    failed
}

/// Entry point, called by the C runtime's startup code.
#[no_mangle]
pub extern "C" fn main(_argc: c_int, _argv: *const *const c_char) -> c_int {
    let failed = run();
    c_int::try_from(failed).unwrap_or(c_int::MAX)
}
