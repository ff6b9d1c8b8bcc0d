//! Recalibration maps (DESIGN §1.9): arbitrary knots (`ArbMaps`) on every head, and the
//! mapped scores checked against the head's own (same error, order and decision).

use super::*;

/// One arbitrary map: mostly knots built to the rule (x from positive steps normalised
/// to end at 1, y from non-negative steps), sometimes knots of any bits.
#[derive(Arbitrary, Debug, Clone)]
pub enum ArbKnots {
    /// Steps in x and y: knot `i` is at the running sums, x scaled to end at 1.
    Steps(Vec<(u8, u8)>, u8),
    /// Any `(x, y)` bit patterns.
    Bits(Vec<(u32, u32)>),
}

impl ArbKnots {
    /// The knots.
    pub fn knots(&self) -> Vec<mlmap::Knot> {
        match self {
            Self::Steps(steps, y0) => {
                let total: f32 = steps.iter().map(|&(dx, _)| f32::from(dx)).sum();
                let (mut x, mut y) = (0.0f32, f32::from(*y0) / 255.0);
                let mut out = vec![mlmap::Knot { x: 0.0, y }];
                for (i, &(dx, dy)) in steps.iter().enumerate() {
                    x += f32::from(dx);
                    y = (y + f32::from(dy) / 1024.0).min(1.0);
                    let at = if i + 1 == steps.len() { 1.0 } else { x / total };
                    out.push(mlmap::Knot { x: at, y });
                }
                out
            }
            Self::Bits(b) => b
                .iter()
                .map(|&(x, y)| mlmap::Knot {
                    x: f32::from_bits(x),
                    y: f32::from_bits(y),
                })
                .collect(),
        }
    }
}

/// An arbitrary map for each head (or none).
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbMaps(pub [Option<ArbKnots>; 4]);

/// The heads in the order of [`ArbMaps`].
pub const MAP_HEADS: [Head; 4] = [Head::Ml, Head::Map, Head::Bayes, Head::Open];

impl ArbMaps {
    /// `table` with the maps `DynTable::with_map` accepts; each is accepted exactly
    /// when `RecalMap::new` accepts its knots and the table has the head. The table
    /// round-trips through its bytes (version 4 when it holds a map) and its maps are
    /// stored bit for bit.
    pub fn attach(&self, table: &DynTable) -> DynTable {
        let mut t = table.clone();
        for (head, knots) in MAP_HEADS.iter().zip(&self.0) {
            let Some(k) = knots else { continue };
            let knots = k.knots();
            let has = match head {
                Head::Ml | Head::Map => true,
                Head::Bayes => t.bayes_head().is_some(),
                Head::Open => t.open_params().is_some(),
            };
            let valid = mlmap::RecalMap::new(&knots).is_ok() && has;
            match t.clone().with_map(*head, knots.clone()) {
                Ok(with) => {
                    assert!(valid, "with_map({head}) accepted {knots:?}");
                    let g = with.recal_map(*head).expect("the map is held");
                    let same = g.knots().iter().zip(&knots).all(|(a, b)| {
                        a.x.to_bits() == b.x.to_bits() && a.y.to_bits() == b.y.to_bits()
                    });
                    assert!(
                        same && g.knots().len() == knots.len(),
                        "{head}: map not stored"
                    );
                    t = with;
                }
                Err(e) => assert!(!valid, "with_map({head}) refused {knots:?}: {e}"),
            }
        }
        let bytes = t.to_vec().expect("a table with maps encodes");
        let back = DynTable::from_bytes(&bytes).expect("its encoding decodes");
        assert_eq!(back, t, "maps changed through the bytes");
        let any = MAP_HEADS.iter().any(|&h| t.recal_map(h).is_some());
        assert_eq!(
            bytes.get(4) == Some(&4),
            any,
            "format version 4 iff a map is held"
        );
        let plain = t.clone().without_maps().to_vec().expect("encodes");
        assert_eq!(
            plain,
            table.clone().without_maps().to_vec().expect("encodes")
        );
        t
    }
}

/// One detection on a table with maps, every head it has: the same error as without
/// the maps, or the mapped top is `g(top)` of the head's own top, every other score
/// is strictly below it, the scores keep the head's order and its decision; a
/// fixed-size `Table` with room for the maps gives the same bits.
pub fn check_mapped_detection<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    mapped: &DynTable,
    fixed: &Table<K, B_ML, B_MAP, BB, C, { mlmap::MAX_KNOTS }>,
    x: &[f32; K],
    os: f32,
) {
    let raw = mapped.clone().without_maps();
    for head in MAP_HEADS {
        let (mut m, mut r, mut scratch) = ([0.0f32; K], [0.0f32; K], vec![0.0f32; K + 1]);
        let got = mapped.view().score_into(head, x, os, &mut m, &mut scratch);
        let own = raw.view().score_into(head, x, os, &mut r, &mut scratch);
        assert_eq!(got, own, "{head}: mapped and own results differ");
        let mut fm = [0.0f32; K];
        let f = fixed.view().score_into(head, x, os, &mut fm, &mut scratch);
        assert_eq!(f, got, "{head}: Table and DynTable results differ");
        if got.is_err() {
            continue;
        }
        assert_eq!(
            fm.map(f32::to_bits),
            m.map(f32::to_bits),
            "{head}: Table differs"
        );
        let Some(g) = mapped.recal_map(head) else {
            assert_eq!(m.map(f32::to_bits), r.map(f32::to_bits), "{head}: no map");
            continue;
        };
        let top = r.iter().fold(0.0f32, |a, &v| a.max(v));
        if top == 0.0 {
            assert!(
                m.iter().all(|&v| v == 0.0),
                "{head}: zero scores mapped to {m:?}"
            );
            continue;
        }
        let gt = g.eval(top);
        for i in 0..K {
            if r[i] == top {
                assert_eq!(
                    m[i].to_bits(),
                    gt.to_bits(),
                    "{head}: top {top} -> {} != g = {gt}",
                    m[i]
                );
            } else {
                assert!(
                    m[i] < gt && m[i] >= 0.0,
                    "{head}: score {i} {} not below g(top) {gt}",
                    m[i]
                );
            }
            for j in 0..K {
                if r[i] >= r[j] {
                    assert!(m[i] >= m[j], "{head}: order of {i}, {j}: {r:?} -> {m:?}");
                }
            }
        }
        assert_eq!(
            mlmap::decide(&m, x),
            mlmap::decide(&r, x),
            "{head}: decision changed"
        );
    }
}

/// Detections read from `u` on `table` given the arbitrary maps `maps`.
pub fn check_detections_with_maps<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    table: &Table<K, B_ML, B_MAP, BB, C>,
    maps: &ArbMaps,
    u: &mut Unstructured<'_>,
) {
    let mapped = maps.attach(&DynTable::from_table(table));
    let bytes = mapped.to_vec().expect("encodes");
    let fixed = Table::<K, B_ML, B_MAP, BB, C, { mlmap::MAX_KNOTS }>::from_bytes(&bytes)
        .expect("a table type with room for the maps decodes them");
    for_detections(table, u, |x, os| {
        check_mapped_detection(&mapped, &fixed, x, os)
    });
}
