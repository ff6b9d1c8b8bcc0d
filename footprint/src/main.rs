//! The smallest firmware that decodes a table and scores a detection with both heads,
//! for measuring mlmap's footprint on a Cortex-M4F (`.ci/footprint.sh`).
//!
//! Built for `thumbv7em-none-eabihf` (opt-level "s", LTO, panic abort) in three
//! variants with the same skeleton and the same inputs, which the optimiser cannot see
//! ([`black_box`]):
//!
//! * default: [`Table::from_bytes`](mlmap::Table::from_bytes) (CRC, postcard, every
//!   invariant), then [`Table::ml`](mlmap::Table::ml) and
//!   [`Table::map`](mlmap::Table::map) (libm's `expf`) on one detection;
//! * feature `decode-only`: the decoding alone;
//! * feature `baseline`: no mlmap call at all;
//! * feature `quantized`: [`QTable::from_bytes`](mlmap::QTable::from_bytes) of the int8
//!   section of `tables/default_q8.mlmap` (CRC and every check), then
//!   [`QTable::ml`](mlmap::QTable::ml) and [`QTable::map`](mlmap::QTable::map) on one
//!   detection; with `quantized-bayes` also [`QTable::bayes`](mlmap::QTable::bayes);
//! * features `map-fastmath`, `map-micromath`: the default variant with the MAP head's
//!   `exp` from `FastMath` or `Micromath` instead of libm.
//!
//! The differences of the images are the footprints of decoding and of inference. The
//! binary is never run; it only has to link. Decoding and scoring are functions of
//! their own, so that `-Z emit-stack-sizes` reports their frames separately.
#![no_std]
#![no_main]

use core::hint::black_box;

use cortex_m_rt::entry;

/// The table shipped with the crate (K = 3, 22 ML bins, 17 MAP bins), as firmware keeps
/// it in a calibration flash sector.
#[cfg(not(feature = "quantized"))]
static TABLE_BYTES: &[u8] = include_bytes!("../../tables/default.mlmap");

/// The shipped table with its int8 quantized section (scale 0.08).
#[cfg(feature = "quantized")]
static QUANTIZED_BYTES: &[u8] = include_bytes!("../../tables/default_q8.mlmap");

#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {}
}

/// The shape of the shipped table.
#[cfg(not(any(feature = "baseline", feature = "quantized")))]
type Calibration = mlmap::Table<3, 22, 17, 22, 4>;

/// Decoding at start-up; the caller keeps the table.
#[cfg(not(any(feature = "baseline", feature = "quantized")))]
#[inline(never)]
fn decode(bytes: &[u8]) -> Result<Calibration, mlmap::DecodeError> {
    Calibration::from_bytes(bytes)
}

/// Both heads on one detection.
#[cfg(not(any(feature = "baseline", feature = "decode-only", feature = "quantized")))]
#[inline(never)]
fn score(table: &Calibration) {
    let (logits, objectness) = black_box(([4.2f32, -1.5, 0.3], 0.9f32));
    black_box(table.ml(&logits, objectness).ok());
    #[cfg(not(any(feature = "map-fastmath", feature = "map-micromath")))]
    black_box(table.map(&logits, objectness).ok());
    #[cfg(feature = "map-fastmath")]
    black_box(table.map_with::<mlmap::FastMath>(&logits, objectness).ok());
    #[cfg(feature = "map-micromath")]
    black_box(table.map_with::<mlmap::Micromath>(&logits, objectness).ok());
}

#[cfg(feature = "decode-only")]
#[inline(never)]
fn score(table: &Calibration) {
    black_box(table);
    black_box(([4.2f32, -1.5, 0.3], 0.9f32));
}

#[cfg(not(any(feature = "baseline", feature = "quantized")))]
#[inline(never)]
fn layer() {
    let decoded = decode(black_box(TABLE_BYTES));
    if let Ok(table) = &decoded {
        score(black_box(table));
    }
    black_box(decoded.err());
}

#[cfg(feature = "baseline")]
#[inline(never)]
fn layer() {
    black_box(TABLE_BYTES);
    black_box(([4.2f32, -1.5, 0.3], 0.9f32));
}

/// The quantized section read at start-up; the caller keeps it.
#[cfg(feature = "quantized")]
#[inline(never)]
fn decode(bytes: &'static [u8]) -> Result<mlmap::QTable<'static, 3, i8>, mlmap::QTableError> {
    mlmap::QTable::from_bytes(bytes)
}

/// The quantized heads on one detection.
#[cfg(feature = "quantized")]
#[inline(never)]
fn score(q: &mlmap::QTable<'static, 3, i8>) {
    let (codes, objectness) = black_box(([52i8, -19, 4], 0.9f32));
    black_box(q.ml(&codes, objectness).ok());
    black_box(q.map(&codes, objectness).ok());
    #[cfg(feature = "quantized-bayes")]
    black_box(q.bayes(&codes, objectness).ok());
}

#[cfg(feature = "quantized")]
#[inline(never)]
fn layer() {
    let decoded = decode(black_box(QUANTIZED_BYTES));
    if let Ok(q) = &decoded {
        score(black_box(q));
    }
    black_box(decoded.err());
}

#[entry]
fn main() -> ! {
    layer();
    loop {
        black_box(());
    }
}
