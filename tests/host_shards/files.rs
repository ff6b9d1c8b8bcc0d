//! The training data fitted in shards, in one fit and in memory; statistics of other
//! classes, settings or edges refused; the versioned bytes; bad rows in memory.

use super::*;

#[test]
fn sharded_fit_of_the_training_data_equals_fit_and_in_memory_fits() {
    let src = train();
    let want = fit(&src, &FitParams::default()).unwrap().to_vec().unwrap();
    // The same rows in memory: fit, TrainingSet and the sharded path agree.
    let mem = Loaded::read(&repo("examples/data/train.csv")).unwrap();
    assert_eq!(
        fit(&mem, &FitParams::default()).unwrap().to_vec().unwrap(),
        want
    );
    let set = TrainingSet::read(&mem).unwrap();
    assert_eq!(
        set.fit(&FitParams::default()).unwrap().to_vec().unwrap(),
        want
    );
    assert_eq!(set.path(), Path::new("rows"));
    // Three shards by row index modulo 3.
    let params = FitParams::default();
    let mut shards = vec![FitStats::new(src.classes()).with_params(params).unwrap(); 3];
    src.for_each_row(|r| {
        shards[r.index as usize % 3].push(&r);
        Ok::<(), FitError>(())
    })
    .unwrap();
    let mut stats = shards[2].clone();
    stats.merge(&shards[0]).unwrap();
    stats.merge(&shards[1]).unwrap();
    let edges = stats.edges(&params).unwrap();
    let mut counts = vec![FitCounts::new(&edges); 3];
    src.for_each_row(|r| {
        assert!(counts[r.index as usize % 3].push(&r));
        Ok::<(), FitError>(())
    })
    .unwrap();
    let mut c = counts[1].clone();
    c.merge(&counts[2]).unwrap();
    c.merge(&counts[0]).unwrap();
    assert_eq!(finish(&stats, &c).unwrap().to_vec().unwrap(), want);
    // Counts of two shards only cover other rows.
    let mut partial = counts[0].clone();
    partial.merge(&counts[1]).unwrap();
    assert!(matches!(
        finish(&stats, &partial),
        Err(FitError::RowsDiffer { .. })
    ));
    let msg = finish(&stats, &partial).unwrap_err().to_string();
    assert!(
        msg.contains("the shards of pass (b) are not those of pass (a)"),
        "{msg}"
    );
}

/// Statistics of three rows of classes `a`, `b`.
fn small_stats() -> FitStats {
    let rows = [
        (Label::Class(0), vec![1.0, -2.0]),
        (Label::Class(1), vec![0.5, 3.25]),
        (Label::Background, vec![-1.0, 0.0]),
    ];
    let mut s = FitStats::new(&["a", "b"]);
    rows.iter()
        .enumerate()
        .for_each(|(i, r)| s.push(&row(i, r)));
    s
}

#[test]
fn merging_statistics_of_other_classes_or_settings_is_refused() {
    let mut s = small_stats();
    let other = FitStats::new(&["a", "c"]);
    let e = s.merge(&other).unwrap_err();
    assert!(matches!(e, FitError::ClassesDiffer { .. }));
    assert!(e.to_string().contains("[a, b]") && e.to_string().contains("[a, c]"));
    assert_eq!(s, small_stats(), "nothing changed");

    let p = FitParams::default();
    let q = FitParams { bins_ml: 5, ..p };
    let mut a = small_stats().with_params(p).unwrap();
    let b = small_stats().with_params(q).unwrap();
    assert_eq!(a.merge(&b), Err(FitError::ParamsDiffer));
    assert_eq!(a.merge(&small_stats()), Err(FitError::ParamsDiffer));
    assert_eq!(a.edges(&q), Err(FitError::ParamsDiffer));
    assert!(a.edges(&p).is_ok());
    assert!(matches!(
        small_stats().with_params(FitParams { bins_ml: 0, ..p }),
        Err(FitError::Param {
            name: "bins_ml",
            ..
        })
    ));
}

#[test]
fn counts_over_other_edges_are_refused() {
    let s = small_stats();
    let e22 = s.edges(&FitParams::default()).unwrap();
    let e5 = s
        .edges(&FitParams {
            bins_map: 5,
            ..FitParams::default()
        })
        .unwrap();
    let mut c = FitCounts::new(&e22);
    assert_eq!(c.merge(&FitCounts::new(&e5)), Err(FitError::EdgesDiffer));
    // Edges of other statistics: the counts do not belong to these statistics.
    let mut wider = small_stats();
    wider.push(&row(9, &(Label::Class(0), vec![7.0, 7.0])));
    let foreign = FitCounts::new(&wider.edges(&FitParams::default()).unwrap());
    assert_eq!(finish(&s, &foreign).unwrap_err(), FitError::EdgesDiffer);
    // A value outside the edges is reported, so is a background row the stats lacked.
    assert!(!c.push(&row(0, &(Label::Class(0), vec![9.0, 0.0]))));
    let no_bg = {
        let mut t = FitStats::new(&["a", "b"]);
        t.push(&row(0, &(Label::Class(0), vec![1.0, 1.0])));
        t.push(&row(1, &(Label::Class(1), vec![2.0, 2.0])));
        t
    };
    let mut c = FitCounts::new(&no_bg.edges(&FitParams::default()).unwrap());
    assert!(c.push(&row(0, &(Label::Class(1), vec![1.5, 1.5]))));
    assert!(!c.push(&row(0, &(Label::Background, vec![1.5, 1.5]))));
    // Statistics with a class without rows have no edges.
    let e = FitStats::new(&["a", "b"]).edges(&FitParams::default());
    assert!(matches!(e, Err(FitError::EmptyClasses { .. })));
}

/// Replaces the format version of serialized bytes and fixes their checksum.
fn with_version(bytes: &[u8], version: u16) -> Vec<u8> {
    let mut b = bytes[..bytes.len() - 4].to_vec();
    b[8..10].copy_from_slice(&version.to_le_bytes());
    let crc = crate::support::crc32(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

#[test]
fn serialized_statistics_round_trip_and_bad_bytes_are_refused() {
    let s = small_stats().with_params(FitParams::default()).unwrap();
    let bytes = s.to_bytes();
    assert_eq!(&bytes[..8], b"MLMAPFST");
    assert_eq!(
        u16::from_le_bytes([bytes[8], bytes[9]]),
        STATS_FORMAT_VERSION
    );
    let back = FitStats::from_bytes(&bytes).unwrap();
    assert_eq!(back, s);
    assert_eq!(back.to_bytes(), bytes);
    for (m, n) in back.moments().iter().zip(s.moments()) {
        assert_eq!(m.min().to_bits(), n.min().to_bits());
        assert_eq!(m.mean().to_bits(), n.mean().to_bits());
    }
    let edges = s.edges(&FitParams::default()).unwrap();
    let mut counts = FitCounts::new(&edges);
    counts.push(&row(0, &(Label::Class(0), vec![1.0, -2.0])));
    let cbytes = counts.to_bytes();
    assert_eq!(FitCounts::from_bytes(&cbytes).unwrap(), counts);
    assert_eq!(FitEdges::from_bytes(&edges.to_bytes()).unwrap(), edges);

    let msg = |r: Result<FitStats, FitError>| r.unwrap_err().to_string();
    // A newer format version names itself.
    let m = msg(FitStats::from_bytes(&with_version(&bytes, 2)));
    assert!(m.contains("format version 2 is newer"), "{m}");
    // Another kind of file.
    let m = msg(FitStats::from_bytes(&cbytes));
    assert!(
        m.contains("these are pass-(b) counts, not pass-(a) statistics"),
        "{m}"
    );
    let m = FitCounts::from_bytes(&bytes).unwrap_err().to_string();
    assert!(m.contains("these are pass-(a) statistics"), "{m}");
    let m = msg(FitStats::from_bytes(b"label,a,b\n"));
    assert!(m.contains("unknown magic"), "{m}");
    // Every truncation and every flipped byte is an error, never a panic.
    for n in 0..bytes.len() {
        assert!(FitStats::from_bytes(&bytes[..n]).is_err(), "{n}");
    }
    for i in 0..bytes.len() {
        let mut b = bytes.clone();
        b[i] ^= 0x41;
        assert!(FitStats::from_bytes(&b).is_err(), "{i}");
    }
    for i in 0..cbytes.len() {
        let mut b = cbytes.clone();
        b[i] ^= 0x10;
        assert!(FitCounts::from_bytes(&b).is_err(), "{i}");
        assert!(FitCounts::from_bytes(&cbytes[..i]).is_err(), "{i}");
    }
    // Trailing bytes (with a valid checksum) are refused too.
    let mut long = bytes[..bytes.len() - 4].to_vec();
    long.push(0);
    let crc = crate::support::crc32(&long);
    long.extend_from_slice(&crc.to_le_bytes());
    let m = msg(FitStats::from_bytes(&long));
    assert!(m.contains("unexpected bytes"), "{m}");
    assert!(FitError::Format {
        reason: String::new()
    }
    .is_bad_input());
}

#[test]
fn bad_rows_in_memory_are_errors_naming_the_rows() {
    let good = (Label::Class(0), vec![1.0, 2.0]);
    let mut l = loaded(2, &[good.clone(), (Label::Class(1), vec![0.0, 1.0])]);
    fit(&l, &FitParams::default()).unwrap();
    l.logits.pop();
    let e = fit(&l, &FitParams::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "rows: logits (rows x classes) holds 3 values; 4 are needed"
    );
    let l = loaded(2, &[good.clone(), (Label::Class(2), vec![0.0, 1.0])]);
    let e = fit(&l, &FitParams::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "rows: row index 1: column \"label\": label 2 is not a class index (0 to 1) or -1 (background)"
    );
    let l = loaded(2, &[good.clone(), (Label::Class(1), vec![0.0, f64::NAN])]);
    match fit(&l, &FitParams::default()).unwrap_err() {
        FitError::Data(d) => {
            assert!(matches!(d.kind(), DataErrorKind::NotFinite { .. }));
            assert_eq!(d.column(), Some("c1"));
        }
        other => panic!("{other:?}"),
    }
    let mut l = loaded(2, &[good.clone(), (Label::Class(1), vec![0.0, 1.0])]);
    l.objectness[1] = 1.5;
    assert!(fit(&l, &FitParams::default())
        .unwrap_err()
        .to_string()
        .contains(
            "row index 1: column \"objectness\": objectness \"1.5\" is not a number in [0, 1]"
        ));
    let l = loaded(2, &[good]);
    assert_eq!(
        fit(&l, &FitParams::default()).unwrap_err().to_string(),
        "rows: class \"c1\" has no training rows (rows labelled with the class); every class \
         needs at least one"
    );
}
