//! Quantized sections: any bytes either fail to read or give a `QTable` whose scores keep
//! invariant 1 of DESIGN §1.3 for any codes, with `QTable` (int8 and int16) and the host's
//! `DynQTable` agreeing bit for bit; and a section built from the shipped table with any
//! quantization scores, for any codes, exactly as the `f32` table on the dequantized
//! logits (DESIGN §6.19).
//!
//! The C API's quantized calls agree with `DynQTable`: the init succeeds exactly when it
//! reads the section and K fits the library's maximum, and every head scores the same bits
//! or fails with the matching status.
//!
//! The first byte picks the mode: even, the rest is a section (tried as given, and with
//! its trailer's length and CRC made valid, so that mutations get past the checksum);
//! odd, the rest gives the quantization (code width, scales, zero points) and codes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mlmap::host::{DynQTable, DynTable};
use mlmap::invariants::{check_scores, Sum};
use mlmap::{dequantize, quantize_into, Head, QParams, QTable, Table};
use mlmap_fuzz::{must, with_valid_trailer};

type Shipped = Table<3, 22, 17, 22, 4>;
const SHIPPED: &[u8] = include_bytes!("../../tables/default.mlmap");

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    if mode % 2 == 0 {
        read_all(rest);
        read_all(&with_valid_trailer(rest));
    } else {
        build(rest);
    }
});

/// Codes worth trying on any section: the range ends, 0, and a spread.
const CODES: [i16; 9] = [i16::MIN, -200, -128, -1, 0, 1, 127, 300, i16::MAX];

fn read_all(bytes: &[u8]) {
    c_api(bytes);
    let dynq = DynQTable::from_bytes(bytes);
    if let Err(e) = &dynq {
        assert!(!e.to_string().is_empty());
    }
    let q8 = QTable::<3, i8>::from_bytes(bytes);
    let q16 = QTable::<3, i16>::from_bytes(bytes);
    let Ok(d) = dynq else {
        assert!(
            q8.is_err() && q16.is_err(),
            "QTable accepts what DynQTable refuses"
        );
        return;
    };
    assert_eq!(q8.is_ok(), d.k() == 3 && d.bits() == 8);
    assert_eq!(q16.is_ok(), d.k() == 3 && d.bits() == 16);
    let k = d.k();
    let (lo, hi) = mlmap::code_range(d.bits());
    for (n, &a) in CODES.iter().enumerate() {
        let codes: Vec<i32> = (0..k)
            .map(|c| i32::from(CODES[(n + c * 4) % CODES.len()]).clamp(lo, hi))
            .collect();
        let codes = {
            let mut c = codes;
            c[0] = i32::from(a).clamp(lo, hi);
            c
        };
        for os in [1.0f32, 0.3] {
            for head in [Head::Ml, Head::Map, Head::Bayes] {
                let mut out = vec![0.0f32; k];
                match d.score_i32_into(head, &codes, os, &mut out, &mut vec![0.0; d.scratch_len()])
                {
                    Ok(()) => {
                        let sum = if head == Head::Bayes {
                            Sum::AtMost
                        } else {
                            Sum::Equal
                        };
                        must(
                            check_scores(&out, os, sum),
                            format_args!("{head:?} {codes:?}"),
                        );
                        let fixed = match (&q8, &q16) {
                            (Ok(q), _) => {
                                let c: [i8; 3] = std::array::from_fn(|i| codes[i] as i8);
                                Some(match head {
                                    Head::Ml => q.ml(&c, os),
                                    Head::Map => q.map(&c, os),
                                    Head::Bayes => q.bayes(&c, os),
                                    Head::Open => unreachable!("not among the heads scored here"),
                                })
                            }
                            (_, Ok(q)) => {
                                let c: [i16; 3] = std::array::from_fn(|i| codes[i] as i16);
                                Some(match head {
                                    Head::Ml => q.ml(&c, os),
                                    Head::Map => q.map(&c, os),
                                    Head::Bayes => q.bayes(&c, os),
                                    Head::Open => unreachable!("not among the heads scored here"),
                                })
                            }
                            _ => None,
                        };
                        if let Some(s) = fixed {
                            let s = s.expect("QTable scores what DynQTable scores");
                            assert_eq!(
                                s.0.map(f32::to_bits).to_vec(),
                                out.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
                            );
                        }
                    }
                    Err(e) => assert_eq!(
                        head == Head::Bayes && !d.has_bayes(),
                        e == mlmap::InferError::NoBayesHead,
                        "{e:?}"
                    ),
                }
            }
        }
    }
}

#[repr(C, align(8))]
struct Arena([u8; 4096]);

/// The C API on `bytes`: init, then every head on the codes of [`CODES`], against
/// `DynQTable`.
fn c_api(bytes: &[u8]) {
    use mlmap_ffi::mlmap_status_t::*;
    use mlmap_ffi::*;
    let dynq = DynQTable::from_bytes(bytes);
    let mut arena = Box::new(Arena([0xa5; 4096]));
    let mut size = 0usize;
    let mut detail = mlmap_error_t {
        status: MLMAP_OK,
        field: mlmap_field_t::MLMAP_FIELD_NONE,
        head: -1,
        class_index: -1,
        needed: 0,
    };
    // SAFETY: the bytes and a `size_t`.
    let s = unsafe { mlmap_qtable_arena_size(bytes.as_ptr(), bytes.len(), &mut size, &mut detail) };
    assert!(ALL_STATUSES.contains(&s) && detail.status == s, "{s:?}");
    let mut q: *mut mlmap_qtable_t = std::ptr::null_mut();
    // SAFETY: 4096 bytes of 8-aligned storage, the bytes, outputs.
    let s = unsafe {
        mlmap_qtable_init(
            arena.0.as_mut_ptr().cast(),
            arena.0.len(),
            bytes.as_ptr(),
            bytes.len(),
            &mut q,
            &mut detail,
        )
    };
    assert!(ALL_STATUSES.contains(&s) && detail.status == s, "{s:?}");
    let fits = dynq.as_ref().is_ok_and(|d| d.k() <= 16);
    assert_eq!(s == MLMAP_OK, fits, "{s:?} vs {:?}", dynq.as_ref().err());
    let Ok(d) = dynq else {
        assert!(q.is_null());
        return;
    };
    if !fits {
        return;
    }
    assert_eq!(size, 96 + 24 * 8 + d.k() * (16 + 11 * 8));
    let k = d.k();
    let (lo, hi) = mlmap::code_range(d.bits());
    for (n, &a) in CODES.iter().enumerate() {
        let mut codes: Vec<i32> = (0..k)
            .map(|c| i32::from(CODES[(n + c * 4) % CODES.len()]).clamp(lo, hi))
            .collect();
        codes[0] = i32::from(a).clamp(lo, hi);
        for (head, h) in [Head::Ml, Head::Map, Head::Bayes, Head::Open]
            .into_iter()
            .zip(0..)
        {
            let mut want = vec![0.0f32; k];
            let r = d.score_i32_into(
                head,
                &codes,
                0.7,
                &mut want,
                &mut vec![0.0; d.scratch_len()],
            );
            let mut out = vec![0.0f32; k];
            // SAFETY: K codes of the section's width, K floats.
            let s = unsafe {
                if d.bits() == 8 {
                    let c: Vec<i8> = codes.iter().map(|&v| v as i8).collect();
                    mlmap_qscore_i8(q, h, c.as_ptr(), k, 0.7, out.as_mut_ptr(), k)
                } else {
                    let c: Vec<i16> = codes.iter().map(|&v| v as i16).collect();
                    mlmap_qscore_i16(q, h, c.as_ptr(), k, 0.7, out.as_mut_ptr(), k)
                }
            };
            match r {
                Ok(()) => {
                    assert_eq!(s, MLMAP_OK);
                    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&out), bits(&want), "{head:?} {codes:?}");
                }
                Err(e) => assert_eq!(s, mlmap_status_t::from(e), "{head:?}"),
            }
        }
    }
}

/// Reads `n` little-endian bytes from the front of `data` (zeros past its end).
fn take<const N: usize>(data: &mut &[u8]) -> [u8; N] {
    let mut out = [0u8; N];
    let n = N.min(data.len());
    out[..n].copy_from_slice(&data[..n]);
    *data = &data[n..];
    out
}

fn build(mut data: &[u8]) {
    let t = Shipped::from_bytes(SHIPPED).expect("the shipped table decodes");
    let d = &mut data;
    let bits = if take::<1>(d)[0].is_multiple_of(2) {
        8
    } else {
        16
    };
    let (lo, hi) = mlmap::code_range(bits);
    let scales: [f32; 3] = std::array::from_fn(|_| f32::from_le_bytes(take::<4>(d)));
    let zps: [i32; 3] = std::array::from_fn(|_| i32::from(i16::from_le_bytes(take::<2>(d))));
    let p = QParams {
        bits,
        scales: &scales,
        zero_points: &zps,
        bayes: true,
    };
    let len = mlmap::quantized_len(&t.view(), &p);
    let mut buf = vec![0u8; *len.as_ref().unwrap_or(&0)];
    let bytes = match len.and_then(|_| quantize_into(&t.view(), &p, &mut buf)) {
        Ok(b) => b,
        Err(e) => {
            // Only bad parameters are refused.
            let bad_scale = scales.iter().any(|s| !(s.is_finite() && *s > 0.0));
            let bad_zp = zps.iter().any(|z| !(lo..=hi).contains(z));
            assert!(bad_scale || bad_zp, "{e:?} for {scales:?} {zps:?}");
            return;
        }
    };
    let q = DynQTable::from_bytes(bytes).expect("a built section reads back");
    let dynt = DynTable::from_table(&t);
    while !d.is_empty() {
        let codes: Vec<i32> = (0..3)
            .map(|_| i32::from(i16::from_le_bytes(take::<2>(d))).clamp(lo, hi))
            .collect();
        let os = f32::from(take::<1>(d)[0]) / 255.0;
        let x: Vec<f32> = (0..3)
            .map(|c| dequantize(codes[c], scales[c], zps[c]))
            .collect();
        for head in [Head::Ml, Head::Map, Head::Bayes] {
            let (mut got, mut want) = ([0.0f32; 3], [0.0f32; 3]);
            q.score_i32_into(head, &codes, os, &mut got, &mut [0.0; 7])
                .expect("valid codes");
            dynt.view()
                .score_into(head, &x, os, &mut want, &mut [0.0; 4])
                .expect("valid logits");
            assert_eq!(
                got.map(f32::to_bits),
                want.map(f32::to_bits),
                "{head:?} {codes:?} {x:?}"
            );
        }
    }
}
