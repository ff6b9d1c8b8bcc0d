//! Shards of random rows merged in any order and grouping, also through their bytes, give
//! the table of one fit; the exact sums against a big-integer oracle.

use super::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn shards_merged_in_any_order_and_grouping_give_the_bytes_of_one_fit(
        (k, rows) in rows_strategy(),
        params in params_strategy(),
        cuts in proptest::collection::vec(any::<prop::sample::Index>(), 0..6),
        shuffle_a in any::<u64>(),
        shuffle_b in any::<u64>(),
        tree_a in prop::bool::ANY,
        tree_b in prop::bool::ANY,
    ) {
        let all = loaded(k, &rows);
        let whole = fit(&all, &params);
        // Shards: the rows cut at random points (empty shards included).
        let mut bounds: Vec<usize> = cuts.iter().map(|i| i.index(rows.len() + 1)).collect();
        bounds.push(0);
        bounds.push(rows.len());
        bounds.sort_unstable();
        let shards: Vec<&[(Label, Vec<f64>)]> =
            bounds.windows(2).map(|w| &rows[w[0]..w[1]]).collect();
        let order = |seed: u64| {
            let mut o: Vec<usize> = (0..shards.len()).collect();
            let mut s = seed | 1;
            for i in (1..o.len()).rev() {
                s ^= s << 13; s ^= s >> 7; s ^= s << 17;
                o.swap(i, (s % (i as u64 + 1)) as usize);
            }
            o
        };
        let classes = all.classes.clone();
        let stats: Vec<FitStats> = shards
            .iter()
            .map(|sh| {
                let mut s = FitStats::new(&classes);
                sh.iter().enumerate().for_each(|(i, r)| s.push(&row(i, r)));
                s
            })
            .collect();
        let merged = merge_all(
            stats,
            &order(shuffle_a),
            tree_a,
            |a, b| a.merge(b).unwrap(),
            |s| FitStats::from_bytes(&s.to_bytes()).unwrap(),
        );
        // The exact state of the merge is that of one pass.
        let mut one = FitStats::new(&classes);
        rows.iter().enumerate().for_each(|(i, r)| one.push(&row(i, r)));
        prop_assert_eq!(&merged, &one);
        prop_assert_eq!(merged.to_bytes(), one.to_bytes());

        let edges = match (merged.edges(&params), &whole) {
            (Ok(e), Ok(_)) => e,
            (Err(a), Err(b)) => {
                prop_assert_eq!(a.to_string(), b.to_string());
                return Ok(());
            }
            (a, b) => return Err(TestCaseError::fail(format!("{a:?} vs {b:?}"))),
        };
        let edges = FitEdges::from_bytes(&edges.to_bytes()).unwrap();
        let counts: Vec<FitCounts> = shards
            .iter()
            .map(|sh| {
                let mut c = FitCounts::new(&edges);
                for (i, r) in sh.iter().enumerate() {
                    assert!(c.push(&row(i, r)));
                }
                c
            })
            .collect();
        let counts = merge_all(
            counts,
            &order(shuffle_b),
            tree_b,
            |a, b| a.merge(b).unwrap(),
            |c| FitCounts::from_bytes(&c.to_bytes()).unwrap(),
        );
        let table = finish(&merged, &counts).map(|t| t.to_vec().unwrap());
        let whole = whole.map(|t| t.to_vec().unwrap());
        prop_assert_eq!(table, whole);
    }

    #[test]
    fn mean_and_variance_are_the_exact_values_correctly_rounded(
        values in proptest::collection::vec(
            prop_oneof![
                -1e6f64..1e6,
                (-1.0f64..1.0).prop_map(|x| 1e15 + x),
                (-1e-3f64..1e-3).prop_map(|x| x * 1e-200),
                any::<f64>().prop_filter("finite and not too large", |x| x.is_finite() && x.abs() < 1e300),
            ],
            1..60,
        ),
    ) {
        let mut m = ClassMoments::new("x");
        values.iter().for_each(|&x| m.push(x));
        // The oracle: every value as an integer multiple of 2^-1074, by f64 bits.
        let exact = |x: f64| -> BigInt {
            let bits = x.to_bits();
            let e = ((bits >> 52) & 0x7ff) as u32;
            let frac = bits & ((1 << 52) - 1);
            let (m, shift) = if e == 0 { (frac, 0) } else { (frac | 1 << 52, e - 1) };
            let v = BigInt::from(m) << shift;
            if x.is_sign_negative() { -v } else { v }
        };
        let n = values.len() as u64;
        let s1: BigInt = values.iter().map(|&x| exact(x)).sum();
        let s2: BigInt = values.iter().map(|&x| exact(x) * exact(x)).sum();
        // mean = s1 / n (units 2^-1074); check |s1 - n c| <= n ulp(c) / 2 exactly.
        let within_half_ulp = |num: &BigInt, den: &BigInt, units: u32, c: f64| -> bool {
            // c and its ulp as integers in units of 2^-units (c is finite here).
            let c_units = |v: f64| -> BigInt {
                let sc = exact(v); // units 2^-1074
                if units >= 1074 { sc << (units - 1074) } else { sc >> (1074 - units) }
            };
            let ulp = c_units(f64::from_bits(c.abs().to_bits() + 1)) - c_units(c.abs());
            let diff = num - den * c_units(c);
            let diff = if diff < BigInt::from(0) { -diff } else { diff };
            BigInt::from(2) * diff <= den * ulp
        };
        prop_assert!(within_half_ulp(&s1, &BigInt::from(n), 1074, m.mean()), "mean {}", m.mean());
        if n >= 2 {
            // var = (n s2 - s1^2) / (n (n-1)) in units 2^-2148.
            let num = BigInt::from(n) * &s2 - &s1 * &s1;
            let den = BigInt::from(n) * BigInt::from(n - 1);
            let v = m.sample_variance();
            prop_assume!(v > 1e-300 && v < 1e300);
            prop_assert!(within_half_ulp(&num, &den, 2148, v), "variance {v}");
        }
    }
}
