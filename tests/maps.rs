//! Recalibration maps (DESIGN §1.9): every head after its map against the numpy
//! reference on every kind of table, the version-4 bytes, capacity and rule errors, and
//! the map's properties on random knots and scores.

use mlmap::{
    BoundedTable, DecodeError, Head, InferError, Knot, MapError, RecalMap, Table, TableError,
    MAX_KNOTS,
};
use proptest::prelude::*;

use crate::support::{crc32, GOLDEN_ABS_TOL};

/// The small table with a Bayes head, the open head and a map for every head.
const SMALL_MAPS: &[u8] = include_bytes!("golden/layer/small_maps.mlmap");
/// The small table without a Bayes head, with maps for ML and MAP.
const SMALL_MAPS_NOBAYES: &[u8] = include_bytes!("golden/layer/small_maps_nobayes.mlmap");
/// The small table with a Bayes head, the open head and the objectness feature (DESIGN
/// §1.6), no map.
const SMALL_OSF: &[u8] = include_bytes!("golden/layer/small_osf.mlmap");

type Maps = Table<3, 4, 2, 4, 4, MAX_KNOTS>;
type MapsNoBayes = Table<3, 4, 2, 0, 0, MAX_KNOTS>;
type Osf = Table<3, 4, 2, 4, 4, 0, 1>;
type Bounded = BoundedTable<8, 8, 8, 8, 9, MAX_KNOTS, 1>;

const HEADS: [Head; 4] = [Head::Ml, Head::Map, Head::Bayes, Head::Open];

/// One row of `maps.csv`: a table, a case, every head's expected mapped scores (`None`
/// for a head the table lacks), or the error.
struct Golden {
    table: String,
    case: String,
    objectness: f32,
    logits: [f32; 3],
    scores: [Option<[f64; 3]>; 4],
    error: Option<InferError>,
}

fn goldens() -> Vec<Golden> {
    let csv = include_str!("golden/layer/maps.csv");
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let head = lines.next().unwrap();
    assert!(
        head.starts_with("table,case,objectness,x0,x1,x2,ml0"),
        "{head}"
    );
    lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), 19, "golden line {line:?}");
            let error = match f[18] {
                "" => None,
                "objectness" => Some(InferError::Objectness),
                e => Some(InferError::NanLogit {
                    class: e.strip_prefix("nan_logit:").unwrap().parse().unwrap(),
                }),
            };
            let x = |i: usize| f[i].parse::<f32>().unwrap();
            let head = |h: usize| {
                let at = 6 + 3 * h;
                (!f[at].is_empty())
                    .then(|| [at, at + 1, at + 2].map(|i| f[i].parse::<f64>().unwrap()))
            };
            Golden {
                table: f[0].to_owned(),
                case: f[1].to_owned(),
                objectness: x(2),
                logits: [x(3), x(4), x(5)],
                scores: [head(0), head(1), head(2), head(3)],
                error,
            }
        })
        .collect()
}

/// The scores of `head` for one detection from the three kinds of table holding the
/// same bytes; all three must agree bit for bit.
fn score_all(bytes: &[u8], head: Head, x: &[f32; 3], os: f32) -> Result<[f32; 3], InferError> {
    let dynamic = mlmap::host::DynTable::from_bytes(bytes).unwrap();
    let bounded = Bounded::from_bytes(bytes).unwrap();
    let (mut d, mut b, mut scratch) = ([0.0f32; 3], [0.0f32; 3], [0.0f32; 4]);
    let dr = dynamic.view().score_into(head, x, os, &mut d, &mut scratch);
    let br = bounded
        .view()
        .unwrap()
        .score_into(head, x, os, &mut b, &mut scratch);
    let fixed = if bytes == SMALL_MAPS {
        let t = Maps::from_bytes(bytes).unwrap();
        match head {
            Head::Ml => t.ml(x, os),
            Head::Map => t.map(x, os),
            Head::Bayes => t.bayes(x, os),
            Head::Open => t.open(x, os),
        }
    } else if bytes == SMALL_OSF {
        let t = Osf::from_bytes(bytes).unwrap();
        match head {
            Head::Ml => t.ml(x, os),
            Head::Map => t.map(x, os),
            Head::Bayes => t.bayes(x, os),
            Head::Open => t.open(x, os),
        }
    } else {
        let t = MapsNoBayes::from_bytes(bytes).unwrap();
        match head {
            Head::Ml => t.ml(x, os),
            Head::Map => t.map(x, os),
            Head::Bayes | Head::Open => Err(InferError::NoBayesHead),
        }
    }
    .map(|s| s.0);
    if let Ok(f) = fixed {
        assert_eq!((dr, br), (Ok(()), Ok(())));
        assert_eq!(f.map(f32::to_bits), d.map(f32::to_bits), "{head}: DynTable");
        assert_eq!(
            f.map(f32::to_bits),
            b.map(f32::to_bits),
            "{head}: BoundedTable"
        );
    }
    fixed
}

#[test]
fn mapped_heads_match_the_numpy_reference() {
    let rows = goldens();
    let mut worst = 0.0f64;
    let mut compared = 0;
    for g in &rows {
        let bytes = match g.table.as_str() {
            "small_maps" => SMALL_MAPS,
            "small_maps_nobayes" => SMALL_MAPS_NOBAYES,
            "small_osf" => SMALL_OSF,
            other => panic!("unknown golden table {other}"),
        };
        let raw = mlmap::host::DynTable::from_bytes(bytes)
            .unwrap()
            .without_maps();
        let (x, os) = (&g.logits, g.objectness);
        for (h, &head) in HEADS.iter().enumerate() {
            let what = format!("{} {} {head}: x = {x:?}, OS = {os}", g.table, g.case);
            let got = score_all(bytes, head, x, os);
            let lacks = g.table == "small_maps_nobayes" && matches!(head, Head::Bayes | Head::Open);
            if lacks {
                assert_eq!(got.err(), Some(InferError::NoBayesHead), "{what}");
                continue;
            }
            match (g.scores[h], g.error) {
                (None, None) => panic!("{what}: a row without scores or error"),
                (_, Some(e)) => assert_eq!(got.err(), Some(e), "{what}"),
                (Some(want), None) => {
                    let got = got.unwrap_or_else(|e| panic!("{what}: {e:?}"));
                    let (mut r, mut scratch) = ([0.0f32; 3], [0.0f32; 4]);
                    raw.view()
                        .score_into(head, x, os, &mut r, &mut scratch)
                        .unwrap();
                    // Below 1e-30 the head's f32 scores have lost the ratios between
                    // them to underflow, which the map's division by the top score
                    // then shows: only the mapped top, g(top), is compared; scores
                    // that underflowed to 0 stay 0.
                    let top = r.iter().copied().fold(0.0f32, f32::max);
                    let pairs: Vec<(f32, f64)> = if top == 0.0 {
                        assert_eq!(got, [0.0; 3], "{what}");
                        Vec::new()
                    } else if top < 1e-30 {
                        let best = mlmap::decide(&got, x);
                        let w = want.iter().copied().fold(0.0f64, f64::max);
                        vec![(got[best], w)]
                    } else {
                        got.iter().copied().zip(want).collect()
                    };
                    for (i, &(s, w)) in pairs.iter().enumerate() {
                        let err = (f64::from(s) - w).abs();
                        assert!(err <= GOLDEN_ABS_TOL, "{what}: score {i} {s} vs {w}");
                        worst = worst.max(err);
                    }
                    compared += 1;
                    // The map keeps the head's decision and the order of its scores.
                    assert_eq!(mlmap::decide(&got, x), mlmap::decide(&r, x), "{what}");
                    for i in 0..3 {
                        for j in 0..3 {
                            if r[i] >= r[j] {
                                assert!(got[i] >= got[j], "{what}: order of {i}, {j}");
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(compared >= 200, "{compared}");
    assert!(rows.iter().filter(|g| g.table == "small_osf").count() >= 40);
    assert!(rows.iter().any(|g| g.error.is_some()));
    eprintln!("maps: {compared} head scores compared, worst error {worst:e}");
}

#[test]
fn version_four_bytes_round_trip() {
    for bytes in [SMALL_MAPS, SMALL_MAPS_NOBAYES] {
        // Version 4 (the byte after the magic), and one encoding per table.
        assert_eq!(bytes[4], 4);
        let d = mlmap::host::DynTable::from_bytes(bytes).unwrap();
        assert_eq!(d.to_vec().unwrap(), bytes);
        let b = Bounded::from_bytes(bytes).unwrap();
        let mut buf = vec![0u8; Bounded::MAX_ENCODED_LEN];
        assert_eq!(b.view().unwrap().encode(&mut buf).unwrap(), bytes);
        // Without its maps the table goes back to its older version.
        let older = d.clone().without_maps().to_vec().unwrap();
        assert!(older[4] < 4, "{}", older[4]);
        assert!(older.len() < bytes.len());
    }
    let t = Maps::from_bytes(SMALL_MAPS).unwrap();
    let mut buf = [0u8; Maps::MAX_ENCODED_LEN];
    assert_eq!(t.to_slice(&mut buf).unwrap(), SMALL_MAPS);
    let g = t.recal_map(Head::Open).unwrap();
    assert_eq!(
        g.knots(),
        [
            Knot { x: 0.0, y: 0.03125 },
            Knot { x: 0.5, y: 0.25 },
            Knot { x: 1.0, y: 1.0 }
        ]
    );
    // Per map: a head code, a knot count and 8 bytes per knot; plus one record count,
    // the objectness feature's option byte and the open head's option byte.
    let without = mlmap::host::DynTable::from_bytes(SMALL_MAPS)
        .unwrap()
        .without_maps()
        .to_vec()
        .unwrap();
    let knots: usize = HEADS
        .iter()
        .map(|&h| t.recal_map(h).unwrap().knots().len())
        .sum();
    assert_eq!(SMALL_MAPS.len(), without.len() + 3 + 4 * 2 + 8 * knots);
}

#[test]
fn a_table_type_without_room_refuses_maps() {
    assert_eq!(
        Table::<3, 4, 2, 4, 4>::from_bytes(SMALL_MAPS),
        Err(DecodeError::MapCapacity {
            head: Head::Ml,
            capacity: 0,
            found: 4
        })
    );
    // The Bayes map has 6 knots.
    assert_eq!(
        Table::<3, 4, 2, 4, 4, 5>::from_bytes(SMALL_MAPS),
        Err(DecodeError::MapCapacity {
            head: Head::Bayes,
            capacity: 5,
            found: 6
        })
    );
    assert!(Table::<3, 4, 2, 4, 4, 6>::from_bytes(SMALL_MAPS).is_ok());
    assert!(Table::<3, 4, 2, 0, 0, 4>::from_bytes(SMALL_MAPS_NOBAYES).is_ok());
}

/// `SMALL_MAPS` with the open map's knots (the last 24 bytes before the CRC) replaced,
/// the CRC recomputed.
fn with_open_knots(knots: [(f32, f32); 3]) -> Vec<u8> {
    let n = SMALL_MAPS.len();
    let mut b = SMALL_MAPS[..n - 4].to_vec();
    let at = b.len() - 24;
    for (i, (x, y)) in knots.iter().enumerate() {
        b[at + 8 * i..at + 8 * i + 4].copy_from_slice(&x.to_le_bytes());
        b[at + 8 * i + 4..at + 8 * i + 8].copy_from_slice(&y.to_le_bytes());
    }
    let crc = crc32(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

#[test]
fn every_broken_map_rule_is_refused_by_every_decoder() {
    // The unmodified knots decode.
    let same = with_open_knots([(0.0, 0.03125), (0.5, 0.25), (1.0, 1.0)]);
    assert_eq!(same, SMALL_MAPS);
    let cases = [
        ([(0.0, 0.1), (0.5, 0.25), (0.9, 1.0)], MapError::Ends),
        ([(0.1, 0.1), (0.5, 0.25), (1.0, 1.0)], MapError::Ends),
        ([(-0.0, 0.1), (0.5, 0.25), (1.0, 1.0)], MapError::Ends),
        ([(0.0, 0.1), (1.0, 0.25), (1.0, 1.0)], MapError::Order),
        ([(0.0, 0.1), (f32::NAN, 0.25), (1.0, 1.0)], MapError::Order),
        ([(0.0, 0.5), (0.5, 0.25), (1.0, 1.0)], MapError::Values),
        ([(0.0, 0.1), (0.5, 0.25), (1.0, 1.5)], MapError::Values),
        ([(0.0, 0.0), (0.5, 0.25), (1.0, 1.0)], MapError::Values),
        ([(0.0, -0.0), (0.5, 0.25), (1.0, 1.0)], MapError::Values),
        ([(0.0, f32::NAN), (0.5, 0.25), (1.0, 1.0)], MapError::Values),
    ];
    for (knots, error) in cases {
        let bytes = with_open_knots(knots);
        let want = Err(DecodeError::Invalid(TableError::Map {
            head: Head::Open,
            error,
        }));
        assert_eq!(Maps::from_bytes(&bytes).map(|_| ()), want, "{knots:?}");
        assert_eq!(
            mlmap::host::DynTable::from_bytes(&bytes).map(|_| ()),
            want,
            "{knots:?}"
        );
        assert_eq!(Bounded::from_bytes(&bytes).map(|_| ()), want, "{knots:?}");
    }
}

#[test]
fn building_a_map_checks_the_head_and_the_rule() {
    let d = mlmap::host::DynTable::from_bytes(SMALL_MAPS_NOBAYES).unwrap();
    let knots = vec![Knot { x: 0.0, y: 0.5 }, Knot { x: 1.0, y: 1.0 }];
    for head in [Head::Bayes, Head::Open] {
        assert_eq!(
            d.clone().with_map(head, knots.clone()).err(),
            Some(TableError::Map {
                head,
                error: MapError::NoHead
            })
        );
    }
    assert_eq!(
        d.clone().with_map(Head::Ml, knots[..1].to_vec()).err(),
        Some(TableError::Map {
            head: Head::Ml,
            error: MapError::KnotCount
        })
    );
    assert_eq!(
        d.clone()
            .with_map(Head::Ml, vec![Knot { x: 0.0, y: 0.5 }; MAX_KNOTS + 1])
            .err(),
        Some(TableError::Map {
            head: Head::Ml,
            error: MapError::KnotCount
        })
    );
    // Dropping the open head drops its map; the table stays valid.
    let full = mlmap::host::DynTable::from_bytes(SMALL_MAPS).unwrap();
    let no_open = full.clone().without_open();
    assert!(no_open.recal_map(Head::Open).is_none());
    let bytes = no_open.to_vec().unwrap();
    assert!(mlmap::host::DynTable::from_bytes(&bytes).is_ok());
    let no_bayes = full.without_bayes();
    assert!(no_bayes.recal_map(Head::Bayes).is_none());
    assert!(mlmap::host::DynTable::from_bytes(&no_bayes.to_vec().unwrap()).is_ok());
}

/// Random valid knots: sorted distinct `x` in (0, 1) between the ends, sorted `y` in
/// (0, 1].
fn knots() -> impl Strategy<Value = Vec<Knot>> {
    (0usize..=30).prop_flat_map(|inner| {
        (
            proptest::collection::vec(1u32..(1 << 24), inner),
            proptest::collection::vec(1u32..=(1 << 24), inner + 2),
        )
            .prop_map(|(mut xs, mut ys)| {
                xs.sort_unstable();
                xs.dedup();
                ys.sort_unstable();
                let mut k = vec![Knot { x: 0.0, y: 1.0 }];
                k.extend(xs.iter().map(|&x| Knot {
                    x: x as f32 / (1 << 24) as f32,
                    y: 1.0,
                }));
                k.push(Knot { x: 1.0, y: 1.0 });
                for (knot, &y) in k.iter_mut().zip(&ys) {
                    knot.y = y as f32 / (1 << 24) as f32;
                }
                k
            })
    })
}

proptest! {
    /// g never decreases, stays in [y_0, y_last], and passes through every knot.
    #[test]
    fn g_is_monotone_and_interpolates(k in knots(), a in 0.0f32..=1.0, b in 0.0f32..=1.0) {
        let g = RecalMap::new(&k).unwrap();
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        prop_assert!(g.eval(lo) <= g.eval(hi));
        let (first, last) = (k[0].y, k[k.len() - 1].y);
        prop_assert!(first <= g.eval(lo) && g.eval(hi) <= last);
        for knot in &k {
            prop_assert_eq!(g.eval(knot.x), knot.y);
        }
    }

    /// Applying a map: the top score becomes g(top), no score exceeds it, the order of
    /// the scores is kept (as a weak order) and so is the decision.
    #[test]
    fn apply_keeps_the_order(
        k in knots(),
        scores in proptest::collection::vec(0.0f32..=1.0, 2..8),
        logits in proptest::collection::vec(-10.0f32..10.0, 8),
    ) {
        let g = RecalMap::new(&k).unwrap();
        let mut out = scores.clone();
        g.apply(&mut out);
        let top = scores.iter().copied().fold(0.0f32, f32::max);
        if top == 0.0 {
            prop_assert!(out.iter().all(|&s| s == 0.0));
        } else {
            let gt = g.eval(top);
            let x = &logits[..scores.len()];
            let d = mlmap::decide(&scores, x);
            prop_assert_eq!(out[d], gt);
            prop_assert_eq!(mlmap::decide(&out, x), d);
            for i in 0..scores.len() {
                prop_assert!((0.0..=gt).contains(&out[i]));
                if scores[i] < top {
                    prop_assert!(out[i] < gt);
                }
                for j in 0..scores.len() {
                    if scores[i] >= scores[j] {
                        prop_assert!(out[i] >= out[j]);
                    }
                }
            }
        }
    }
}

/// The objectness feature (DESIGN §1.6): a table type without room refuses it, one that
/// requires it refuses a table without; the bytes round-trip; the open head's unknown
/// category has a flat share on the feature's axis too.
#[test]
fn objectness_feature_types_and_bytes() {
    assert_eq!(
        Table::<3, 4, 2, 4, 4>::from_bytes(SMALL_OSF),
        Err(DecodeError::ObjectnessMismatch { found: true })
    );
    let open = include_bytes!("golden/layer/small_open.mlmap");
    assert_eq!(
        Osf::from_bytes(open),
        Err(DecodeError::ObjectnessMismatch { found: false })
    );
    let t = Osf::from_bytes(SMALL_OSF).unwrap();
    assert_eq!(SMALL_OSF[4], 4);
    let mut buf = [0u8; Osf::MAX_ENCODED_LEN];
    assert_eq!(t.to_slice(&mut buf).unwrap(), SMALL_OSF);
    let d = mlmap::host::DynTable::from_bytes(SMALL_OSF).unwrap();
    assert_eq!(d.to_vec().unwrap(), SMALL_OSF);
    let b = d.bayes_head().unwrap();
    assert_eq!(b.features(), 4);
    let axis = b.objectness_axis().unwrap();
    assert_eq!((axis.lo(), axis.hi(), axis.bins()), (-4.0, 4.0, 4));
    // ln(eps) + (K + 1) ln(1/B + lambda), K = 3, B = 4, lambda = 0.01, eps = 0.05.
    let want = (0.05f64).ln() + 4.0 * (0.25f64 + 0.01).ln();
    let got = f64::from(t.open_params().unwrap().log_unknown());
    assert!((got - want).abs() < 1e-5, "{got} vs {want}");
    // Bounded storage with room for the feature reads tables with and without it.
    assert!(Bounded::from_bytes(SMALL_OSF).is_ok());
    assert!(Bounded::from_bytes(open).is_ok());
}
