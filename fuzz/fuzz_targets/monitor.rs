//! The drift monitor (DESIGN §7): any bytes appended to the shipped table either fail to
//! read as a monitor section or give a monitor whose windows keep the invariants of
//! DESIGN §7 for any detections: each logit's counts sum to the window's rows, every
//! metric finite and non-negative (`oos_rate` and `q_mean` at most 1), no alarm on a
//! partial window; the fixed-size `Monitor` and the slice functions agree bit for bit.
//!
//! The same bytes are tried as a conformal section (DESIGN §8): when they read, every
//! detection's set holds exactly the classes whose score reaches its threshold, its
//! size is the mask's popcount, and the section's stored -inf thresholds are exactly
//! those of rank 0.
//!
//! Input: a `u16` section length `n`, `n` section bytes (tried as given and with a valid
//! trailer), then detections of three `f32` logits and one objectness byte.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mlmap::host::monitor::DynMonitor;
use mlmap::{threshold_rank, ConformalSpec, Monitor, MonitorSpec, Table};
use mlmap_fuzz::with_valid_trailer;

type Shipped = Table<3, 22, 17, 22, 4>;
const SHIPPED: &[u8] = include_bytes!("../../tables/default.mlmap");

fuzz_target!(|data: &[u8]| {
    let Some((len, rest)) = data.split_first_chunk::<2>() else {
        return;
    };
    let n = usize::from(u16::from_le_bytes(*len)).min(rest.len());
    let (section, detections) = rest.split_at(n);
    let Ok(table) = Shipped::from_bytes(SHIPPED) else {
        panic!("the shipped table decodes");
    };
    for s in [section.to_vec(), with_valid_trailer(section)] {
        let mut file = SHIPPED.to_vec();
        file.extend_from_slice(&s);
        if let Ok(spec) = MonitorSpec::from_bytes(&file, &table.view()) {
            // A file with a monitor section still reads as its table.
            assert!(Shipped::from_bytes(&file).is_ok());
            run(&spec, detections);
        }
        if let Ok(spec) = ConformalSpec::from_bytes(&file, &table.view()) {
            assert!(Shipped::from_bytes(&file).is_ok());
            sets(&spec, &table, detections);
        }
    }
});

fn sets(spec: &ConformalSpec<'_>, table: &Shipped, detections: &[u8]) {
    for c in 0..3 {
        let (Some(n), Some(t)) = (spec.calibration_rows(c), spec.threshold(c)) else {
            panic!("class {c} has a threshold");
        };
        assert_eq!(threshold_rank(n, spec.alpha()) == 0, t == f32::NEG_INFINITY);
    }
    let view = table.view();
    for d in detections.chunks_exact(13) {
        let x = [0, 1, 2].map(|i| {
            let b: [u8; 4] = d[4 * i..4 * i + 4].try_into().unwrap_or_default();
            f32::from_le_bytes(b)
        });
        let os = f32::from(d[12]) / 255.0;
        let (mut s, mut scratch, mut mask) = ([0.0f32; 3], [0.0f32; 4], [0u32; 1]);
        match spec.score_set(&view, &x, os, &mut s, &mut scratch, &mut mask) {
            Ok(size) => {
                assert_eq!(size, mask[0].count_ones());
                for (c, &score) in s.iter().enumerate() {
                    let t = spec.threshold(c).unwrap_or(f32::INFINITY);
                    assert_eq!(mask[0] >> c & 1 == 1, score >= t);
                }
                assert_eq!(mask[0] >> 3, 0);
            }
            Err(_) => assert!(x.iter().any(|v| v.is_nan())),
        }
    }
}

fn run(spec: &MonitorSpec<'_>, detections: &[u8]) {
    let Ok(mut fixed) = Monitor::<'_, 3, 22, 4>::new(spec) else {
        panic!("the section's shape is the table's");
    };
    let mut dynamic = DynMonitor::new(spec);
    for d in detections.chunks_exact(13) {
        let x = [0, 1, 2].map(|i| {
            let b: [u8; 4] = d[4 * i..4 * i + 4].try_into().unwrap_or_default();
            f32::from_le_bytes(b)
        });
        let os = f32::from(d[12]) / 255.0;
        let a = fixed.push(&x, os);
        let b = dynamic.push(spec, &x, os);
        assert_eq!(
            a.as_ref()
                .map(|r| r.map(|w| (w.summary, w.psi.to_vec())))
                .map_err(|e| *e),
            b
        );
        if let Ok(Some(w)) = a {
            check(&w.summary, &w.psi, spec.params().window);
        }
        let rows = fixed.accumulators().rows;
        for j in 0..3 {
            let Some((below, bins, above)) = fixed.counts(j) else {
                panic!("logit {j} has counts");
            };
            assert_eq!(below + bins.iter().sum::<u32>() + above, rows);
        }
    }
    if let Some(w) = fixed.flush() {
        assert!(!w.summary.alarms.any() || w.summary.rows == spec.params().window);
        check(&w.summary, &w.psi, spec.params().window);
    }
}

fn check(s: &mlmap::WindowSummary, psi: &[f32], window: u32) {
    assert!(s.rows >= 1 && s.rows <= window);
    assert!(psi.iter().all(|p| p.is_finite() && *p >= 0.0));
    assert!(s.psi_max.is_finite() && s.psi_max >= 0.0);
    assert!((0.0..=1.0).contains(&s.oos_rate));
    if let Some(q) = s.q_mean {
        assert!((0.0..=1.0 + 1e-6).contains(&q), "q_mean {q}");
    }
    if s.rows < window {
        assert!(!s.alarms.any());
    }
}
