//! The recalibration maps of DESIGN §1.9 on the small table with a map on every head.

use super::*;

/// The heads of the table with maps (DESIGN §1.9) against the numpy reference's mapped
/// scores. The same table without maps is `small` (the maps were added to it): its
/// scores decide what is compared. Where a head's own top score is below 1e-30 its
/// `f32` scores have lost their ratios to underflow, so only the mapped top is
/// compared; all-zero scores stay zero. The map keeps the decision and the order of the
/// scores; the batch calls give the single calls' bits. Returns the largest deviation.
pub(crate) fn check_maps(r: &mut Report, small: &SmallTable) -> f64 {
    let name = "small table with maps";
    let bytes: &'static [u8] = black_box(MAPS_FILE);
    let crc = bytes
        .get(bytes.len().saturating_sub(4)..)
        .and_then(|b| b.try_into().ok())
        .map(u32::from_le_bytes);
    r.check(
        crc == Some(MAPS_TABLE_CRC),
        "maps table CRC",
        format_args!("{crc:x?}, but expected.rs was computed for {MAPS_TABLE_CRC:08x}"),
    );
    // A table type without room for maps refuses it.
    let refused = SmallTable::from_bytes(bytes).err();
    r.check(
        matches!(refused, Some(DecodeError::MapCapacity { .. })),
        name,
        format_args!("a table type without maps gave {refused:?}, want MapCapacity"),
    );
    let t = match MapsTable::from_bytes(bytes) {
        Ok(t) => t,
        Err(e) => {
            r.check(false, name, format_args!("decode: {e:?}"));
            return 0.0;
        }
    };
    let heads = ["ML", "MAP", "Bayes", "open"];
    let score = |head: usize, x: &[f32; K], os: f32| match head {
        0 => (t.ml(x, os), small.ml(x, os)),
        1 => (t.map(x, os), small.map(x, os)),
        2 => (t.bayes(x, os), small.bayes(x, os)),
        _ => (t.open(x, os), small.open(x, os)),
    };
    let mut max_err = 0.0f64;
    for case in MAP_CASES {
        let x = black_box(case.logits);
        let os = black_box(case.objectness);
        for (h, head) in heads.iter().enumerate() {
            let (got, own) = score(h, &x, os);
            let want = match case.error {
                Some(e) => {
                    r.check(
                        got == Err(e),
                        case.label,
                        format_args!("{name} {head}: got {got:?}, want {e:?}"),
                    );
                    continue;
                }
                None => case.scores.get(h).copied().unwrap_or([f64::NAN; K]),
            };
            #[allow(unused_mut)]
            let mut want = want;
            #[cfg(feature = "canary")]
            if case.label == MAP_CASES[0].label && h == 3 {
                want[0] += 1e-3;
            }
            let (got, own) = match (got, own) {
                (Ok(g), Ok(o)) => (g, o),
                (g, o) => {
                    r.check(
                        false,
                        case.label,
                        format_args!("{name} {head}: got {g:?}, without maps {o:?}"),
                    );
                    continue;
                }
            };
            let top = own.0.iter().fold(0.0f32, |m, &v| m.max(v));
            let want_top = want.iter().fold(0.0f64, |m, &v| m.max(v));
            let mut ok = true;
            for (&g, (&o, &w)) in got.0.iter().zip(own.0.iter().zip(want.iter())) {
                if top == 0.0 {
                    ok &= g == 0.0;
                    continue;
                }
                if top < 1e-30 && o != top {
                    continue;
                }
                let w = if top < 1e-30 { want_top } else { w };
                let err = (f64::from(g) - w).abs();
                max_err = max_err.max(err);
                ok &= err <= TOLERANCE;
                // The order of the classes is the head's own.
                for (&oj, &gj) in own.0.iter().zip(got.0.iter()) {
                    ok &= o.partial_cmp(&oj).is_none_or(|c| c.is_lt()) || g >= gj;
                }
            }
            ok &= got.decide(&x) == own.decide(&x);
            r.check(
                ok,
                case.label,
                format_args!("{name} {head}: got {:?}, want {want:?}", got.0),
            );
        }
    }
    // The batch calls give the single calls' bits.
    let mut logits = [[0.0f32; K]; ROWS];
    let mut os = [0.0f32; ROWS];
    let mut n = 0;
    for case in MAP_CASES.iter().filter(|c| c.error.is_none()) {
        if let (Some(l), Some(o)) = (logits.get_mut(n), os.get_mut(n)) {
            *l = case.logits;
            *o = case.objectness;
            n += 1;
        }
    }
    let (logits, os) = (&logits[..n], &os[..n]);
    let mut out = [[0.0f32; K]; ROWS];
    let out = &mut out[..n];
    for (h, head) in heads.iter().enumerate() {
        let result = match h {
            0 => t.ml_batch(logits, Some(os), out),
            1 => t.map_batch(logits, Some(os), out),
            2 => t.bayes_batch(logits, Some(os), out),
            _ => t.open_batch(logits, Some(os), out),
        };
        let same = result.is_ok()
            && logits
                .iter()
                .zip(os.iter())
                .zip(out.iter())
                .all(|((x, &o), row)| score(h, x, o).0.is_ok_and(|s| s.0 == *row));
        r.check(
            same && n >= 20,
            "batch",
            format_args!("{name} {head}: batch rows differ from single detections ({n} rows)"),
        );
    }
    max_err
}
