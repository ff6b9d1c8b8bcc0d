//! The C entry points give the Rust layer's scores bit for bit (the fixed-size
//! `Table` of the shipped table's shape), for every head, per detection and in batches.
//! Run with `cargo test --features std` (the library's own panic handler is for
//! `no_std` builds).

use mlmap::Table;
use mlmap_ffi::*;

const SHIPPED: &[u8] = include_bytes!("../../tables/default.mlmap");

#[repr(C, align(8))]
struct Storage([u8; 128 * 1024]);

fn detections() -> Vec<([f32; 3], f32)> {
    let mut v = Vec::new();
    let mut s = 0x2545_f491_4f6c_dd1du64;
    for i in 0..5000 {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        let x = |t: u64| ((t % 6000) as f32 - 3000.0) / 300.0;
        v.push(([x(s), x(s >> 20), x(s >> 40)], (i % 21) as f32 / 20.0));
    }
    v.push(([f32::INFINITY, f32::NEG_INFINITY, 0.0], 1.0));
    v
}

#[test]
fn c_api_scores_equal_the_rust_layer_bit_for_bit() {
    let rust = Table::<3, 22, 17, 22, 4>::from_bytes(SHIPPED).unwrap();
    let mut storage = Box::new(Storage([0; 128 * 1024]));
    let t = storage.0.as_mut_ptr().cast::<mlmap_table_t>();
    let size = storage.0.len();
    // SAFETY: `size` bytes of 8-aligned storage, and the table's bytes.
    let status = unsafe { mlmap_table_decode(t, size, SHIPPED.as_ptr(), SHIPPED.len()) };
    assert_eq!(status, mlmap_status_t::MLMAP_OK);
    let dets = detections();
    let bits = |s: &[f32]| s.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    type One = unsafe extern "C" fn(
        *const mlmap_table_t,
        *const f32,
        usize,
        f32,
        *mut f32,
        usize,
    ) -> mlmap_status_t;
    for (x, os) in &dets {
        let want = [
            rust.ml(x, *os).unwrap().0,
            rust.map(x, *os).unwrap().0,
            rust.bayes(x, *os).unwrap().0,
            rust.open(x, *os).unwrap().0,
        ];
        for (h, f) in [mlmap_ml as One, mlmap_map, mlmap_bayes, mlmap_open]
            .iter()
            .enumerate()
        {
            let mut out = [0.0f32; 3];
            // SAFETY: 3 logits, 3 outputs, a decoded table.
            let s = unsafe { f(t, x.as_ptr(), 3, *os, out.as_mut_ptr(), 3) };
            assert_eq!(s, mlmap_status_t::MLMAP_OK);
            assert_eq!(bits(&out), bits(&want[h]), "head {h}, {x:?}, {os}");
        }
    }
    // Batches.
    let xs: Vec<f32> = dets.iter().flat_map(|(x, _)| *x).collect();
    let os: Vec<f32> = dets.iter().map(|(_, o)| *o).collect();
    let mut out = vec![0.0f32; xs.len()];
    let mut done = 0usize;
    // SAFETY: rows * 3 floats in and out, rows objectness values.
    let s = unsafe {
        mlmap_bayes_batch(
            t,
            xs.as_ptr(),
            dets.len(),
            3,
            os.as_ptr(),
            out.as_mut_ptr(),
            out.len(),
            &mut done,
        )
    };
    assert_eq!((s, done), (mlmap_status_t::MLMAP_OK, dets.len()));
    let rows: Vec<[f32; 3]> = dets.iter().map(|(x, _)| *x).collect();
    let mut want = vec![[0.0f32; 3]; rows.len()];
    rust.bayes_batch(&rows, Some(&os), &mut want).unwrap();
    assert_eq!(bits(&out), bits(want.as_flattened()));
    // SAFETY: as above.
    let s = unsafe {
        mlmap_open_batch(
            t,
            xs.as_ptr(),
            dets.len(),
            3,
            os.as_ptr(),
            out.as_mut_ptr(),
            out.len(),
            &mut done,
        )
    };
    assert_eq!((s, done), (mlmap_status_t::MLMAP_OK, dets.len()));
    rust.open_batch(&rows, Some(&os), &mut want).unwrap();
    assert_eq!(bits(&out), bits(want.as_flattened()));
}

/// Decodes `bytes` into fresh storage.
fn decoded(bytes: &[u8]) -> (Box<Storage>, mlmap_status_t) {
    let mut storage = Box::new(Storage([0; 128 * 1024]));
    let t = storage.0.as_mut_ptr().cast::<mlmap_table_t>();
    // SAFETY: 128 KiB of 8-aligned storage, and the table's bytes.
    let s = unsafe { mlmap_table_decode(t, storage.0.len(), bytes.as_ptr(), bytes.len()) };
    (storage, s)
}

#[test]
fn the_open_head_of_a_small_table_equals_the_rust_layer() {
    // T = 1.75, epsilon = 0.05, a background category.
    const OPEN: &[u8] = include_bytes!("../../tests/golden/layer/small_open.mlmap");
    let rust = Table::<3, 4, 2, 4, 4>::from_bytes(OPEN).unwrap();
    let p = rust.open_params().unwrap();
    let (storage, s) = decoded(OPEN);
    assert_eq!(s, mlmap_status_t::MLMAP_OK);
    let t = storage.0.as_ptr().cast::<mlmap_table_t>();
    let mut settings = mlmap_settings_t::default();
    // SAFETY: a decoded table and a settings struct.
    assert_eq!(
        unsafe { mlmap_settings(t, &mut settings) },
        mlmap_status_t::MLMAP_OK
    );
    assert_eq!(settings.temperature.to_bits(), p.temperature().to_bits());
    assert_eq!(settings.epsilon.to_bits(), p.epsilon().to_bits());
    for (x, os) in detections() {
        let want = rust.open(&x, os).unwrap().0;
        let mut out = [0.0f32; 3];
        // SAFETY: 3 logits, 3 outputs, a decoded table.
        let s = unsafe { mlmap_open(t, x.as_ptr(), 3, os, out.as_mut_ptr(), 3) };
        assert_eq!(s, mlmap_status_t::MLMAP_OK);
        assert_eq!(out.map(f32::to_bits), want.map(f32::to_bits), "{x:?}, {os}");
    }
}

#[test]
fn tables_without_the_open_head_answer_no_open_head() {
    for bytes in [
        &include_bytes!("../../tests/golden/layer/small_bayes.mlmap")[..],
        &include_bytes!("../../tests/golden/layer/small.mlmap")[..],
    ] {
        let (storage, s) = decoded(bytes);
        assert_eq!(s, mlmap_status_t::MLMAP_OK);
        let t = storage.0.as_ptr().cast::<mlmap_table_t>();
        let (x, mut out, mut done) = ([0.5f32, 1.0, -1.0], [-7.0f32; 3], 99usize);
        // SAFETY: 3 logits, 3 outputs, a decoded table.
        let s = unsafe { mlmap_open(t, x.as_ptr(), 3, 1.0, out.as_mut_ptr(), 3) };
        assert_eq!(s, mlmap_status_t::MLMAP_ERR_NO_OPEN_HEAD);
        // SAFETY: as above; 0 rows.
        let s = unsafe {
            mlmap_open_batch(
                t,
                x.as_ptr(),
                0,
                3,
                std::ptr::null(),
                out.as_mut_ptr(),
                0,
                &mut done,
            )
        };
        assert_eq!(s, mlmap_status_t::MLMAP_ERR_NO_OPEN_HEAD);
        assert_eq!((out, done), ([-7.0; 3], 99));
        let mut settings = mlmap_settings_t::default();
        // SAFETY: a decoded table and a settings struct.
        assert_eq!(
            unsafe { mlmap_settings(t, &mut settings) },
            mlmap_status_t::MLMAP_OK
        );
        assert_eq!((settings.temperature, settings.epsilon), (0.0, 0.0));
    }
}

#[test]
fn every_status_has_a_distinct_description() {
    let unknown = unsafe { std::ffi::CStr::from_ptr(mlmap_status_str(-1)) };
    let mut seen = std::collections::HashSet::new();
    for (i, s) in ALL_STATUSES.iter().enumerate() {
        assert_eq!(*s as i32, i as i32);
        // SAFETY: a static NUL-terminated string.
        let d = unsafe { std::ffi::CStr::from_ptr(mlmap_status_str(*s as i32)) };
        assert!(
            !d.is_empty() && d != unknown && seen.insert(d.to_owned()),
            "{s:?}"
        );
    }
    let next = unsafe { std::ffi::CStr::from_ptr(mlmap_status_str(ALL_STATUSES.len() as i32)) };
    assert_eq!(next, unknown);
}

/// The status of an error of the layer is described by that error's one message
/// (`message()` of mlmap's error types), for every status that stands for exactly one
/// kind of error of the layer.
#[test]
fn status_strings_are_the_layers_messages() {
    use mlmap::{DecodeError, InferError, TableError};
    let cases: [(DecodeErrorOrInfer, &str); 13] = [
        (
            DecodeError::Truncated.into(),
            DecodeError::Truncated.message(),
        ),
        (
            DecodeError::NotATable.into(),
            DecodeError::NotATable.message(),
        ),
        (
            DecodeError::Corrupted.into(),
            DecodeError::Corrupted.message(),
        ),
        (
            DecodeError::UnsupportedVersion { found: 9 }.into(),
            DecodeError::UnsupportedVersion { found: 9 }.message(),
        ),
        (
            DecodeError::Malformed.into(),
            DecodeError::Malformed.message(),
        ),
        (
            DecodeError::Invalid(TableError::ClassCount).into(),
            DecodeError::Invalid(TableError::ClassCount).message(),
        ),
        (
            DecodeError::Invalid(TableError::Temperature).into(),
            TableError::Temperature.message(),
        ),
        (
            DecodeError::Invalid(TableError::Epsilon).into(),
            TableError::Epsilon.message(),
        ),
        (
            InferError::NanLogit { class: 1 }.into(),
            InferError::NanLogit { class: 1 }.message(),
        ),
        (
            InferError::Objectness.into(),
            InferError::Objectness.message(),
        ),
        (
            InferError::NoBayesHead.into(),
            InferError::NoBayesHead.message(),
        ),
        (
            InferError::NoOpenHead.into(),
            InferError::NoOpenHead.message(),
        ),
        (
            InferError::CodeWidth {
                expected: 8,
                found: 16,
            }
            .into(),
            InferError::CodeWidth {
                expected: 8,
                found: 16,
            }
            .message(),
        ),
    ];
    let mut statuses = std::collections::HashSet::new();
    for (status, message) in cases {
        let s: mlmap_status_t = status.0;
        // SAFETY: a static NUL-terminated string.
        let d = unsafe { std::ffi::CStr::from_ptr(mlmap_status_str(s as i32)) };
        assert_eq!(d.to_str().unwrap(), message, "{s:?}");
        assert!(statuses.insert(s as i32), "{s:?} twice");
    }
}

/// The status an error of the layer maps to.
struct DecodeErrorOrInfer(mlmap_status_t);

impl From<mlmap::DecodeError> for DecodeErrorOrInfer {
    fn from(e: mlmap::DecodeError) -> Self {
        Self(e.into())
    }
}

impl From<mlmap::InferError> for DecodeErrorOrInfer {
    fn from(e: mlmap::InferError) -> Self {
        Self(e.into())
    }
}

/// The quantized calls give `QTable`'s scores bit for bit, every head, for every int8
/// code of each class against a spread of the others, one detection and in a batch.
#[test]
fn quantized_calls_equal_the_rust_qtable_bit_for_bit() {
    const Q8: &[u8] = include_bytes!("../../tables/default_q8.mlmap");
    let rust = mlmap::QTable::<3, i8>::from_bytes(Q8).unwrap();
    let mut arena = Box::new(Storage([0; 128 * 1024]));
    let mut size = 0usize;
    // SAFETY: the bytes, and a `size_t`.
    let s =
        unsafe { mlmap_qtable_arena_size(Q8.as_ptr(), Q8.len(), &mut size, std::ptr::null_mut()) };
    assert_eq!(s, mlmap_status_t::MLMAP_OK);
    assert_eq!(size, 96 + 24 * 8 + 3 * (16 + 11 * 8));
    let mut q: *mut mlmap_qtable_t = std::ptr::null_mut();
    // SAFETY: 8-aligned storage of `size` bytes, the bytes, outputs.
    let s = unsafe {
        mlmap_qtable_init(
            arena.0.as_mut_ptr().cast(),
            size,
            Q8.as_ptr(),
            Q8.len(),
            &mut q,
            std::ptr::null_mut(),
        )
    };
    assert_eq!(s, mlmap_status_t::MLMAP_OK);
    let mut rows = Vec::new();
    for c in 0..3 {
        for v in i8::MIN..=i8::MAX {
            let mut codes = [(v as i32 * 7 % 128) as i8, v.wrapping_mul(3), -v / 2];
            codes[c] = v;
            rows.push((codes, (v as u8 % 11) as f32 / 10.0));
        }
    }
    let flat: Vec<i8> = rows.iter().flat_map(|(c, _)| *c).collect();
    let os: Vec<f32> = rows.iter().map(|(_, o)| *o).collect();
    for head in 0..4i32 {
        let mut batch = vec![0.0f32; flat.len()];
        let mut done = 0usize;
        // SAFETY: `rows` rows of 3 codes, objectness and outputs.
        let s = unsafe {
            mlmap_qscore_i8_batch(
                q,
                head,
                flat.as_ptr(),
                rows.len(),
                3,
                os.as_ptr(),
                batch.as_mut_ptr(),
                batch.len(),
                &mut done,
            )
        };
        assert_eq!((s, done), (mlmap_status_t::MLMAP_OK, rows.len()));
        for (r, (codes, o)) in rows.iter().enumerate() {
            let want = match head {
                0 => rust.ml(codes, *o),
                1 => rust.map(codes, *o),
                2 => rust.bayes(codes, *o),
                _ => rust.open(codes, *o),
            }
            .unwrap()
            .0;
            let mut out = [0.0f32; 3];
            // SAFETY: 3 codes, 3 floats.
            let s = unsafe { mlmap_qscore_i8(q, head, codes.as_ptr(), 3, *o, out.as_mut_ptr(), 3) };
            assert_eq!(s, mlmap_status_t::MLMAP_OK);
            let bits = |a: &[f32]| a.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&out), bits(&want), "head {head}, codes {codes:?}");
            assert_eq!(bits(&batch[3 * r..3 * r + 3]), bits(&want), "batch row {r}");
        }
    }
}
