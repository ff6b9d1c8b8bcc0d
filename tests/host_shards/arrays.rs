//! Rows given as arrays (the Python package's path): shards in any order, and signed
//! zeros, give the same statistics.

use super::*;

/// Rows as arrays: K in 2..5, f32 logits of mixed scales (zeros and subnormals
/// included), integer labels (-1 background), every class with a row.
fn arrays_strategy() -> impl Strategy<Value = (usize, Vec<f32>, Vec<i64>)> {
    (2usize..5).prop_flat_map(|k| {
        let logit = prop_oneof![
            8 => -8.0f32..8.0,
            1 => (-1.0f32..1.0).prop_map(|x| 3e5 + x),
            1 => (-1.0f32..1.0).prop_map(|x| x * 1e-9),
            1 => Just(0.0f32),
            1 => (1u32..0x80_0000).prop_map(f32::from_bits),
        ];
        let one = (-1i64..k as i64, proptest::collection::vec(logit, k));
        (Just(k), proptest::collection::vec(one, 0..300)).prop_map(|(k, mut rows)| {
            for c in 0..k {
                rows.push((
                    c as i64,
                    (0..k).map(|j| (c * k + j) as f32 * 0.37).collect(),
                ));
            }
            let labels = rows.iter().map(|r| r.0).collect();
            (k, rows.into_iter().flat_map(|r| r.1).collect(), labels)
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// `push_rows` of blocks cut anywhere, f32 or f64, any label type, gives the bytes
    /// of `push` of every row (statistics, counts and the table).
    #[test]
    fn blocks_of_arrays_give_the_bytes_of_row_by_row_pushes(
        (k, logits, labels) in arrays_strategy(),
        params in params_strategy(),
        cuts in proptest::collection::vec(any::<prop::sample::Index>(), 0..6),
        wide in proptest::collection::vec(prop::bool::ANY, 7),
    ) {
        let classes: Vec<String> = (0..k).map(|c| format!("c{c}")).collect();
        let rows: Vec<(Label, Vec<f64>)> = logits
            .chunks(k)
            .zip(&labels)
            .map(|(x, &l)| {
                let label = if l < 0 { Label::Background } else { Label::Class(l as usize) };
                (label, x.iter().map(|&v| f64::from(v)).collect())
            })
            .collect();
        let mut one = FitStats::new(&classes);
        rows.iter().enumerate().for_each(|(i, r)| one.push(&row(i, r)));

        let n = labels.len();
        let mut bounds: Vec<usize> = cuts.iter().map(|i| i.index(n + 1)).collect();
        bounds.extend([0, n]);
        bounds.sort_unstable();
        let blocks: Vec<(usize, usize)> = bounds.windows(2).map(|w| (w[0], w[1])).collect();
        let widened: Vec<f64> = logits.iter().map(|&v| f64::from(v)).collect();
        let small: Vec<i8> = labels.iter().map(|&l| l as i8).collect();
        let mut stats = FitStats::new(&classes);
        for (b, &(lo, hi)) in blocks.iter().enumerate() {
            let r = if wide[b % 7] {
                stats.push_rows(&widened[lo * k..hi * k], &labels[lo..hi])
            } else {
                stats.push_rows(&logits[lo * k..hi * k], &small[lo..hi])
            };
            prop_assert!(r.is_ok());
        }
        prop_assert_eq!(stats.to_bytes(), one.to_bytes());

        let Ok(edges) = one.edges(&params) else { return Ok(()); };
        let mut want = FitCounts::new(&edges);
        for (i, r) in rows.iter().enumerate() {
            prop_assert!(want.push(&row(i, r)));
        }
        let mut counts = FitCounts::new(&edges);
        for (b, &(lo, hi)) in blocks.iter().enumerate() {
            let r = if wide[(b + 3) % 7] {
                counts.push_rows(&widened[lo * k..hi * k], &small[lo..hi])
            } else {
                counts.push_rows(&logits[lo * k..hi * k], &labels[lo..hi])
            };
            prop_assert_eq!(r, Ok(None));
        }
        prop_assert_eq!(counts.to_bytes(), want.to_bytes());
        let table = finish(&stats, &counts).map(|t| t.to_vec().unwrap());
        let whole = finish(&one, &want).map(|t| t.to_vec().unwrap());
        prop_assert_eq!(table, whole);
    }
}

/// `+0.0` and `-0.0` compare equal, so `f64::min` may keep either: the extremes follow
/// IEEE 754's total order instead (`-0.0 < +0.0`), and the statistics of rows holding
/// both zeros are the same bytes in every order of rows and of shards.
#[test]
fn signed_zeros_give_the_same_statistics_in_every_order() {
    let rows = [
        (Label::Class(0), vec![0.0, -0.0]),
        (Label::Class(0), vec![-0.0, 0.0]),
        (Label::Class(1), vec![0.0, 0.0]),
        (Label::Class(1), vec![-0.0, -0.0]),
    ];
    let stats = |order: &[usize]| {
        let mut s = FitStats::new(&["a", "b"]);
        for &i in order {
            s.push(&row(i, &rows[i]));
        }
        s
    };
    let forward = stats(&[0, 1, 2, 3]).to_bytes();
    assert_eq!(stats(&[3, 2, 1, 0]).to_bytes(), forward);
    assert_eq!(stats(&[1, 0, 3, 2]).to_bytes(), forward);
    let (mut a, b) = (stats(&[1, 3]), stats(&[0, 2]));
    a.merge(&b).unwrap();
    assert_eq!(a.to_bytes(), forward);
    // The recorded extremes are -0.0 and +0.0 (by their bits).
    let s = stats(&[2, 0, 3, 1]);
    for m in s.moments() {
        assert_eq!(m.min().to_bits(), (-0.0f64).to_bits());
        assert_eq!(m.max().to_bits(), 0.0f64.to_bits());
    }
}
