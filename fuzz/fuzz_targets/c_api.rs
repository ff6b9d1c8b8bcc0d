//! The C API (`ffi/`) with arbitrary bytes and lengths: decoding any bytes into storage
//! of any size returns a status (OK exactly when the host decoder accepts the table and
//! its shape fits the library's maximum); every entry point, given a decoded table or
//! not, NULL or real buffers of any length, logits and objectness of any value, returns
//! a known status; on OK the scores are in `[0, OS]` and equal the batch entry point's.
//! The open head answers `MLMAP_ERR_NO_OPEN_HEAD` exactly when the host table has none,
//! its scores sum to at most OS, and `mlmap_settings` reports the host table's `T` and
//! `epsilon`. The same bytes into an arena of any size (`mlmap_table_init`): OK exactly
//! when the host decoder accepts them, K fits and the arena holds
//! `mlmap_table_arena_size` bytes (`MLMAP_ERR_STORAGE_TOO_SMALL`, with that size in the
//! detail, when it does not); the detail's status is the returned one; the arena's
//! table scores bit for bit as the `mlmap_table_t`'s.
#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use libfuzzer_sys::fuzz_target;
use mlmap::host::DynTable;
use mlmap_ffi::mlmap_status_t::*;
use mlmap_ffi::*;
use mlmap_fuzz::with_valid_crc;

#[repr(C, align(8))]
struct Storage([u8; 96 * 1024]);

#[derive(Arbitrary, Debug)]
struct Call {
    head: u8,
    null_table: bool,
    null_logits: bool,
    null_out: bool,
    null_objectness: bool,
    n_logits: u8,
    out_len: u8,
    rows: u8,
    objectness: f32,
    logits: Vec<f32>,
}

fn known(s: mlmap_status_t) -> bool {
    ALL_STATUSES.contains(&s)
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let split: u16 = u.arbitrary().unwrap_or(0);
    let size_cut: u32 = u.arbitrary().unwrap_or(0);
    let fix_crc: bool = u.arbitrary().unwrap_or(false);
    let rest = u.take_rest();
    let n = (usize::from(split)).min(rest.len());
    let (table_bytes, calls) = rest.split_at(n);
    let fixed;
    let table_bytes = if fix_crc {
        fixed = with_valid_crc(table_bytes).unwrap_or_default();
        &fixed[..]
    } else {
        table_bytes
    };

    let mut storage = Box::new(Storage([0xa5; 96 * 1024]));
    let t = storage.0.as_mut_ptr().cast::<mlmap_table_t>();
    let mut limits = mlmap_limits_t::default();
    // SAFETY: a valid pointer.
    assert_eq!(unsafe { mlmap_limits(&mut limits) }, MLMAP_OK);
    // Any storage size up to the real one.
    let size = (size_cut as usize) % (storage.0.len() + 1);
    // SAFETY: `size <= storage.0.len()` bytes of 8-aligned storage; the table's bytes.
    let s = unsafe { mlmap_table_decode(t, size, table_bytes.as_ptr(), table_bytes.len()) };
    assert!(known(s), "{s:?}");
    if size < limits.table_size {
        assert_eq!(s, MLMAP_ERR_STORAGE_TOO_SMALL);
    } else {
        let host = DynTable::from_bytes(table_bytes);
        let fits = host.as_ref().is_ok_and(|d| {
            d.k() <= limits.max_classes
                && d.bins_ml() <= limits.max_bins
                && d.bins_map() <= limits.max_bins
                && d.bayes_head()
                    .is_none_or(|b| b.bins() <= limits.max_bins_bayes)
        });
        assert_eq!(s == MLMAP_OK, fits, "{s:?} vs {:?}", host.as_ref().err());
    }
    let mut k = 0usize;
    // SAFETY: valid pointers; the storage holds a table or not (tag).
    let ks = unsafe { mlmap_class_count(t, &mut k) };
    assert_eq!(ks == MLMAP_OK, s == MLMAP_OK);
    let mut has_open = false;
    if s == MLMAP_OK {
        let host = DynTable::from_bytes(table_bytes).expect("decoded by the C API");
        let mut settings = mlmap_settings_t::default();
        // SAFETY: a decoded table and a settings struct.
        assert_eq!(unsafe { mlmap_settings(t, &mut settings) }, MLMAP_OK);
        let open = host.open_params();
        has_open = open.is_some();
        let (temperature, epsilon) = open.map_or((0.0, 0.0), |o| (o.temperature(), o.epsilon()));
        assert_eq!(settings.temperature.to_bits(), temperature.to_bits());
        assert_eq!(settings.epsilon.to_bits(), epsilon.to_bits());
    }

    let mut arena = vec![0u64; 96 * 1024 / 8];
    let mut need = 0usize;
    let mut detail = core::mem::MaybeUninit::<mlmap_error_t>::uninit();
    // SAFETY: the bytes, a `size_t` and an `mlmap_error_t`.
    let sized = unsafe {
        mlmap_table_arena_size(
            table_bytes.as_ptr(),
            table_bytes.len(),
            &mut need,
            detail.as_mut_ptr(),
        )
    };
    assert!(known(sized), "{sized:?}");
    // SAFETY: written by the call.
    assert_eq!(unsafe { detail.assume_init() }.status, sized);
    let arena_size = (size_cut as usize) % (arena.len() * 8 + 1);
    let mut handle = core::ptr::null_mut::<mlmap_table_t>();
    // SAFETY: `arena_size` bytes of 8-aligned storage; the table's bytes; two outputs.
    let a = unsafe {
        mlmap_table_init(
            arena.as_mut_ptr().cast(),
            arena_size,
            table_bytes.as_ptr(),
            table_bytes.len(),
            &mut handle,
            detail.as_mut_ptr(),
        )
    };
    assert!(known(a), "{a:?}");
    // SAFETY: written by the call.
    let d = unsafe { detail.assume_init() };
    assert_eq!(d.status, a);
    assert_eq!(a == MLMAP_OK, !handle.is_null());
    if arena_size >= 8 && sized != MLMAP_OK {
        assert_eq!(a, sized);
    }
    if sized == MLMAP_OK && arena_size >= 8 {
        let host = DynTable::from_bytes(table_bytes);
        if arena_size < need {
            assert_eq!(a, MLMAP_ERR_STORAGE_TOO_SMALL);
            assert_eq!(d.needed, need);
        } else {
            assert_eq!(
                a == MLMAP_OK,
                host.is_ok(),
                "{a:?} vs {:?}",
                host.as_ref().err()
            );
        }
    }
    if a == MLMAP_OK && s == MLMAP_OK {
        let mut shape = mlmap_shape_t::default();
        // SAFETY: a decoded table and a shape.
        assert_eq!(unsafe { mlmap_shape(handle, &mut shape) }, MLMAP_OK);
        let k = shape.classes;
        let x: Vec<f32> = (0..k).map(|i| i as f32 * 0.75 - 1.0).collect();
        let (mut o1, mut o2) = (vec![0.0f32; k], vec![0.0f32; k]);
        type One = unsafe extern "C" fn(
            *const mlmap_table_t,
            *const f32,
            usize,
            f32,
            *mut f32,
            usize,
        ) -> mlmap_status_t;
        let heads: [One; 4] = [mlmap_ml, mlmap_map, mlmap_bayes, mlmap_open];
        for f in heads {
            // SAFETY: two decoded tables, K logits and K scores each.
            let (r1, r2) = unsafe {
                (
                    f(handle, x.as_ptr(), k, 0.5, o1.as_mut_ptr(), k),
                    f(t, x.as_ptr(), k, 0.5, o2.as_mut_ptr(), k),
                )
            };
            assert_eq!(r1, r2);
            if r1 == MLMAP_OK {
                let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&o1), bits(&o2));
            }
        }
    }

    let mut u = Unstructured::new(calls);
    for _ in 0..8 {
        let Ok(c) = Call::arbitrary(&mut u) else {
            break;
        };
        let n_logits = usize::from(c.n_logits) % 20;
        let rows = usize::from(c.rows) % 8;
        let mut logits = c.logits.clone();
        logits.resize(n_logits * rows.max(1), 0.5);
        let out_len = usize::from(c.out_len) % 64;
        let mut out = vec![-7.0f32; out_len.max(1)];
        let os = vec![c.objectness; rows.max(1)];
        let table = if c.null_table {
            core::ptr::null()
        } else {
            t.cast_const()
        };
        let lp = if c.null_logits {
            core::ptr::null()
        } else {
            logits.as_ptr()
        };
        let op = if c.null_out {
            core::ptr::null_mut()
        } else {
            out.as_mut_ptr()
        };
        let osp = if c.null_objectness {
            core::ptr::null()
        } else {
            os.as_ptr()
        };
        let mut done = usize::MAX;
        // SAFETY: every non-NULL pointer has the length passed with it.
        let (one, batch) = unsafe {
            match c.head % 4 {
                0 => (
                    mlmap_ml(table, lp, n_logits, c.objectness, op, out_len),
                    mlmap_ml_batch(table, lp, rows, n_logits, osp, op, out_len, &mut done),
                ),
                1 => (
                    mlmap_map(table, lp, n_logits, c.objectness, op, out_len),
                    mlmap_map_batch(table, lp, rows, n_logits, osp, op, out_len, &mut done),
                ),
                2 => (
                    mlmap_bayes(table, lp, n_logits, c.objectness, op, out_len),
                    mlmap_bayes_batch(table, lp, rows, n_logits, osp, op, out_len, &mut done),
                ),
                _ => (
                    mlmap_open(table, lp, n_logits, c.objectness, op, out_len),
                    mlmap_open_batch(table, lp, rows, n_logits, osp, op, out_len, &mut done),
                ),
            }
        };
        assert!(known(one) && known(batch), "{one:?} {batch:?}");
        if c.head % 4 == 3 {
            // Only a table without the open head says so, and such a table always does
            // once the arguments are right.
            for r in [one, batch] {
                assert!(r != MLMAP_ERR_NO_OPEN_HEAD || (s == MLMAP_OK && !has_open));
            }
            if s == MLMAP_OK && !has_open {
                assert!(one != MLMAP_OK && batch != MLMAP_OK, "{one:?} {batch:?}");
            }
        }
        if one == MLMAP_OK {
            assert_eq!(n_logits, k);
            // The batch wrote its rows over `out`: score row 0 again to check it.
            let mut again = vec![0.0f32; k];
            // SAFETY: k logits, k outputs.
            let r = unsafe {
                match c.head % 4 {
                    0 => mlmap_ml(table, lp, k, c.objectness, again.as_mut_ptr(), k),
                    1 => mlmap_map(table, lp, k, c.objectness, again.as_mut_ptr(), k),
                    2 => mlmap_bayes(table, lp, k, c.objectness, again.as_mut_ptr(), k),
                    _ => mlmap_open(table, lp, k, c.objectness, again.as_mut_ptr(), k),
                }
            };
            assert_eq!(r, MLMAP_OK);
            let os = c.objectness;
            for v in &again {
                assert!(*v >= 0.0 && *v <= os, "score {v} outside [0, {os}]");
            }
            if c.head % 4 >= 2 {
                // The Bayes and open heads: at most OS in all (DESIGN §1.6, §1.8).
                let sum: f32 = again.iter().sum();
                assert!(sum <= os * (1.0 + 1e-5), "scores sum to {sum} > {os}");
            }
            if batch == MLMAP_OK && rows > 0 && !c.null_objectness {
                for (a, b) in again.iter().zip(&out) {
                    assert_eq!(a.to_bits(), b.to_bits(), "batch row 0 differs");
                }
            }
        }
        if batch == MLMAP_OK {
            assert_eq!(done, rows);
        }
        let mut name = [0 as core::ffi::c_char; 40];
        let len = usize::from(c.out_len) % 40;
        // SAFETY: `len <= 40` writable bytes.
        let s = unsafe { mlmap_class_name(table, usize::from(c.rows), name.as_mut_ptr(), len) };
        assert!(known(s));
        let mut idx = 0usize;
        let bytes: Vec<u8> = c.logits.iter().map(|f| f.to_bits() as u8).collect();
        // SAFETY: `bytes.len()` readable bytes.
        let s = unsafe { mlmap_class_index(table, bytes.as_ptr().cast(), bytes.len(), &mut idx) };
        assert!(known(s));
        if n_logits > 0 && logits.len() >= n_logits {
            // SAFETY: n_logits floats each.
            let s = unsafe { mlmap_decide(logits.as_ptr(), logits.as_ptr(), n_logits, &mut idx) };
            // A NaN score is refused (here the scores are the logits).
            if logits[..n_logits].iter().any(|v| v.is_nan()) {
                assert_eq!(s, MLMAP_ERR_NAN_SCORE);
            } else {
                assert_eq!(s, MLMAP_OK);
                assert!(idx < n_logits);
            }
        }
    }
});
