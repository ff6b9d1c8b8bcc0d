//! Table invariants (DESIGN §1.3, invariant 5): every histogram, prior and table a target
//! meets, and the encoding of a valid table.

use super::*;

/// Checks one histogram against every table invariant and the bin rule of numpy.
pub fn check_histogram<F: AsRef<[f32]>>(h: &Histogram<F>, head: Head, class: usize, bins: usize) {
    must(
        invariants::check_histogram(head, class, h, bins),
        "table invariants",
    );
    let what = format!("{head} histogram {class}");
    let (lo, hi) = (h.lo(), h.hi());
    assert_eq!(h.edge(0).to_bits(), lo.to_bits(), "{what}: e_0 != lo");
    assert_eq!(h.edge(bins).to_bits(), hi.to_bits(), "{what}: e_B != hi");
    // The bin rule: an edge opens the bin to its right, the last edge is closed, and
    // nothing outside [e_0, e_B] is in a bin.
    for k in 0..bins {
        let e = h.edge(k);
        assert_eq!(h.bin(e), Some(k), "{what}: edge {k} = {e} not in bin {k}");
        let below_next = h.edge(k + 1).next_down();
        assert_eq!(
            h.bin(below_next),
            Some(k),
            "{what}: {below_next} (just below edge {}) not in bin {k}",
            k + 1
        );
    }
    assert_eq!(
        h.bin(hi),
        Some(bins - 1),
        "{what}: last edge not in the last bin"
    );
    assert_eq!(h.bin(lo.next_down()), None, "{what}: below e_0 is in a bin");
    assert_eq!(h.bin(hi.next_up()), None, "{what}: above e_B is in a bin");
    assert_eq!(h.bin(f32::NAN), None, "{what}: NaN is in a bin");
    for (k, &f) in h.frequencies().iter().enumerate() {
        let l = h.likelihood(h.edge(k), UpperTail::Zero);
        assert_eq!(l.to_bits(), f.to_bits(), "{what}: likelihood at edge {k}");
    }
}

/// Checks one prior: finite mean, finite positive variance, a finite positive density.
pub fn check_prior(g: &Gaussian, class: usize) {
    must(
        invariants::check_prior(class, g.mean(), g.variance()),
        "table invariants",
    );
    let what = format!("prior {class}");
    let peak = g.pdf::<Libm>(g.mean());
    assert!(
        peak.is_finite() && peak > 0.0,
        "{what}: pdf at the mean {peak}"
    );
    assert_eq!(g.pdf::<Libm>(f32::INFINITY), 0.0, "{what}: pdf(+inf)");
    assert_eq!(g.pdf::<Libm>(f32::NEG_INFINITY), 0.0, "{what}: pdf(-inf)");
}

/// Checks every table invariant of a fixed-size table through its accessors.
pub fn check_table<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
) {
    must(invariants::check_table(t), "table invariants");
    for i in 0..K {
        let ml = t
            .ml_histograms()
            .get(i)
            .expect("ML histogram of an existing class");
        let map = t
            .map_histograms()
            .get(i)
            .expect("MAP histogram of an existing class");
        check_histogram(ml, Head::Ml, i, B_ML);
        check_histogram(map, Head::Map, i, B_MAP);
        check_prior(t.priors().get(i).expect("prior of an existing class"), i);
        assert_eq!(t.class_index(t.class_name(i).unwrap_or_default()), Some(i));
    }
    assert!(t.class_name(K).is_none() && t.ml_histograms().get(K).is_none() && t.spec(K).is_none());
}

/// Checks every table invariant of a run-time shaped table.
pub fn check_dyn_table(t: &DynTable) {
    let k = t.k();
    assert!((2..=usize::from(u16::MAX)).contains(&k), "K = {k}");
    must(invariants::check_dyn_table(t), "table invariants");
    assert_eq!(t.rows().len(), k);
    for (i, h) in t.ml_histograms().iter().enumerate() {
        check_histogram(h, Head::Ml, i, t.bins_ml());
    }
    for (i, h) in t.map_histograms().iter().enumerate() {
        check_histogram(h, Head::Map, i, t.bins_map());
    }
    for (i, g) in t.priors().iter().enumerate() {
        check_prior(g, i);
    }
}

/// Encodes `t` and asserts the result is `expected` byte for byte, twice (encoding is
/// deterministic), and that decoding it gives `t` back.
pub fn check_encoding<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    t: &Table<K, B_ML, B_MAP, BB, C>,
    expected: Option<&[u8]>,
) -> Vec<u8> {
    let mut buf = vec![0u8; Table::<K, B_ML, B_MAP, BB, C>::MAX_ENCODED_LEN];
    let first = t
        .to_slice(&mut buf)
        .expect("MAX_ENCODED_LEN suffices")
        .to_vec();
    let mut buf2 = vec![0xA5u8; Table::<K, B_ML, B_MAP, BB, C>::MAX_ENCODED_LEN];
    let second = t.to_slice(&mut buf2).expect("MAX_ENCODED_LEN suffices");
    assert_eq!(first.as_slice(), &*second, "encoding is not deterministic");
    if let Some(expected) = expected {
        assert_eq!(first.as_slice(), expected, "re-encoding changed the bytes");
    }
    let back = Table::<K, B_ML, B_MAP, BB, C>::from_bytes(&first).expect("own encoding decodes");
    assert_eq!(&back, t, "encode -> decode changed the table");
    // Host and device share the format: the run-time shaped table reads the same bytes
    // into the same statistics and writes them back identically.
    let dynt = DynTable::from_bytes(&first).expect("own encoding decodes as DynTable");
    assert_eq!(dynt, DynTable::from_table(t), "DynTable differs from Table");
    assert_eq!(
        dynt.to_vec().expect("encodes"),
        first,
        "DynTable re-encodes differently"
    );
    let again = Table::<K, B_ML, B_MAP, BB, C>::try_from(&dynt).expect("DynTable converts back");
    assert_eq!(&again, t, "Table -> DynTable -> Table changed the table");
    first
}
