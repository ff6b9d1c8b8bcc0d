//! Properties of the sets on exchangeable rows: coverage, monotone in alpha, empty
//! exactly when every score is below its threshold.

use super::*;

/// The default table's scores of the pooled validation and test rows (exchangeable:
/// one generator), per head, computed once.
type Pooled = (Vec<f32>, Vec<Option<usize>>);

fn pooled(head: Head) -> &'static Pooled {
    static P: OnceLock<Vec<(Head, Pooled)>> = OnceLock::new();
    let all = P.get_or_init(|| {
        let (table, _) = default_table();
        [Head::Map, Head::Open]
            .into_iter()
            .map(|h| {
                let mut s = head_scores(&table, h, data("val"));
                s.extend(head_scores(&table, h, data("test")));
                let mut l = data("val").labels.clone();
                l.extend(&data("test").labels);
                (h, (s, l))
            })
            .collect()
    });
    &all.iter().find(|(h, _)| *h == head).unwrap().1
}

/// Splits the pooled rows at random into calibration and test rows (a permutation from
/// `seed`): scores and labels of each part.
fn split(head: Head, seed: u64, cal_share: f64) -> [(Vec<f32>, Vec<Option<usize>>); 2] {
    let (s, l) = pooled(head);
    let n = l.len();
    let mut idx: Vec<usize> = (0..n).collect();
    let mut state = seed;
    for i in (1..n).rev() {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let j = ((state >> 33) as usize) % (i + 1);
        idx.swap(i, j);
    }
    let cut = (n as f64 * cal_share) as usize;
    let part = |ix: &[usize]| {
        let mut ss = Vec::with_capacity(ix.len() * 3);
        let mut ll = Vec::with_capacity(ix.len());
        for &i in ix {
            ss.extend_from_slice(&s[3 * i..3 * i + 3]);
            ll.push(l[i]);
        }
        (ss, ll)
    };
    [part(&idx[..cut]), part(&idx[cut..])]
}

fn spec_bytes(f: &Fitted) -> Vec<u8> {
    let (_, bytes) = default_table();
    with_conformal(&bytes, f).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// On exchangeable rows, every class's coverage on the held-out rows is at least
    /// 1 - alpha, less four standard deviations of the sampling error: that of the
    /// threshold (the class's calibration rows) and that of the held-out rows.
    #[test]
    fn coverage_on_exchangeable_rows(seed in any::<u64>(), open in any::<bool>(), alpha in 0.05f64..0.3) {
        let head = if open { Head::Open } else { Head::Map };
        let [(cs, cl), (ts, tl)] = split(head, seed, 0.5);
        let f = fit(head, alpha, 3, &cs, &cl);
        let file = spec_bytes(&f);
        let (table, _) = default_table();
        let spec = ConformalSpec::from_bytes(&file, &table.view()).unwrap();
        let got = coverage(3, &sets(&spec, &ts).unwrap(), &tl, &[]);
        for (c, &(n, cov)) in got.per_class.iter().enumerate() {
            let n_cal = f64::from(f.rows[c]);
            let sd = (alpha * (1.0 - alpha) * (1.0 / n as f64 + 1.0 / n_cal)).sqrt();
            prop_assert!(cov >= 1.0 - alpha - 4.0 * sd, "class {c}: {cov} at alpha {alpha}, n {n}");
        }
    }

    /// A smaller alpha gives a superset, row by row; a set is empty exactly when every
    /// score is below its threshold, and holds exactly the classes at or above theirs.
    #[test]
    fn monotone_in_alpha_and_empty_iff_below(seed in any::<u64>(), a in 0.01f64..0.5, b in 0.01f64..0.5) {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        let [(cs, cl), (ts, _)] = split(Head::Open, seed, 0.3);
        let (table, _) = default_table();
        let fl = spec_bytes(&fit(Head::Open, lo, 3, &cs, &cl));
        let fh = spec_bytes(&fit(Head::Open, hi, 3, &cs, &cl));
        let sl = ConformalSpec::from_bytes(&fl, &table.view()).unwrap();
        let sh = ConformalSpec::from_bytes(&fh, &table.view()).unwrap();
        let (big, small) = (sets(&sl, &ts).unwrap(), sets(&sh, &ts).unwrap());
        for (x, y) in big.iter().zip(&small) {
            prop_assert!(*x || !*y);
        }
        let t: Vec<f32> = (0..3).map(|c| sh.threshold(c).unwrap()).collect();
        for (row, set) in ts.chunks_exact(3).zip(small.chunks_exact(3)) {
            for c in 0..3 {
                prop_assert_eq!(set[c], row[c] >= t[c]);
            }
            prop_assert_eq!(set.iter().all(|&s| !s), row.iter().zip(&t).all(|(s, t)| s < t));
        }
    }

    /// Any thresholds and scores: the bitmask of a K above 32 spreads over words, bit c
    /// of word c / 32, and its size is its popcount.
    #[test]
    fn wide_masks(k in 2usize..80, seed in any::<u64>()) {
        let mut state = seed;
        let mut next = move || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let thresholds: Vec<f32> = (0..k).map(|_| next()).collect();
        let rows = vec![1000u32; k];
        let mut sec = vec![0u8; conformal_section_len(k)];
        write_conformal_section(&mut sec, 0, Head::Ml, 0.1, &rows, &thresholds).unwrap();
        let names: Vec<String> = (0..k).map(|i| format!("c{i}")).collect();
        let table = wide_table(&names);
        let spec = ConformalSpec::from_bytes(&sec, &table.view()).unwrap();
        let s: Vec<f32> = (0..k).map(|_| next()).collect();
        let mut mask = vec![0u32; mlmap::set_words(k)];
        let size = spec.set_of(&s, &mut mask).unwrap();
        prop_assert_eq!(size, mask.iter().map(|w| w.count_ones()).sum::<u32>());
        for c in 0..k {
            prop_assert_eq!(mask[c / 32] >> (c % 32) & 1 == 1, s[c] >= thresholds[c]);
        }
    }
}
