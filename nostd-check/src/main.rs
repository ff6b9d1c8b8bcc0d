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
//! Running the binary also checks a few results, so a build that links but computes
//! nonsense does not pass: exit status 0 means every check held.
#![no_std]
#![no_main]

use core::ffi::{c_char, c_int};
use core::hint::black_box;

use mlmap::embedded::{EmbeddedTable, TABLE};
use mlmap::{InferError, Scores};

/// The table shipped with the crate, as firmware would read it from a flash sector.
static TABLE_BYTES: &[u8] = include_bytes!("../../tables/default.mlmap");

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

/// Scores one detection with every head of `table` (ML, MAP, Bayes) and checks the
/// results.
fn score(table: &EmbeddedTable, logits: &[f32; 3], os: f32) -> Result<u32, InferError> {
    let mut failed = 0;
    let ml = table.ml(logits, os)?;
    let map = table.map(logits, os)?;
    let bayes = table.bayes(logits, os)?;
    failed += u32::from(!sane(&ml, os)) + u32::from(!sane(&map, os));
    failed += u32::from(!sane_at_most(&bayes, os));
    failed += u32::from(ml.argmax() >= 3) + u32::from(table.class_name(map.argmax()).is_none());
    failed += u32::from(table.class_name(bayes.argmax()).is_none());
    #[cfg(feature = "micromath")]
    {
        let fast = table.map_with::<mlmap::FastMath>(logits, os)?;
        failed += u32::from(!sane(&fast, os));
        let fast = table.bayes_with::<mlmap::FastMath>(logits, os)?;
        failed += u32::from(!sane_at_most(&fast, os));
    }
    Ok(failed)
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
    for (logits, os) in &inputs {
        for table in [&decoded, embedded] {
            match score(table, logits, *os) {
                Ok(f) => failed += f,
                Err(_) => failed += 1,
            }
        }
    }
    // Invalid inputs are errors, not panics.
    let nan = black_box([f32::NAN, 0.0, 0.0]);
    failed += u32::from(decoded.ml(&nan, 1.0).is_ok() || decoded.map(&nan, 1.0).is_ok());
    failed += u32::from(decoded.bayes(&nan, 1.0).is_ok());
    failed += u32::from(decoded.ml(&[0.0; 3], black_box(1.5)).is_ok());
    failed += u32::from(embedded.bayes(&[0.0; 3], black_box(1.5)).is_ok());

    // Batches into caller-provided buffers.
    let logits: [[f32; 3]; 4] = black_box(inputs.map(|(l, _)| l));
    let os: [f32; 4] = black_box(inputs.map(|(_, o)| o));
    let mut out = [[0.0f32; 3]; 4];
    failed += u32::from(decoded.ml_batch(&logits, Some(&os), &mut out).is_err());
    failed += u32::from(embedded.map_batch(&logits, None, &mut out).is_err());
    failed += u32::from(decoded.bayes_batch(&logits, Some(&os), &mut out).is_err());
    #[cfg(feature = "micromath")]
    {
        failed += u32::from(
            decoded
                .map_batch_with::<mlmap::FastMath>(&logits, Some(&os), &mut out)
                .is_err(),
        );
    }
    failed += u32::from(decoded.ml_batch(&logits, Some(&os[..3]), &mut out).is_ok());
    black_box(&out);

    #[cfg(feature = "canary")]
    {
        // A bounds check the optimiser cannot remove: the link must fail.
        failed += u32::from(TABLE_BYTES[black_box(usize::MAX)]);
    }
    failed
}

/// Entry point, called by the C runtime's startup code.
#[no_mangle]
pub extern "C" fn main(_argc: c_int, _argv: *const *const c_char) -> c_int {
    let failed = run();
    c_int::try_from(failed).unwrap_or(c_int::MAX)
}
