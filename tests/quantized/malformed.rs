//! Malformed sections refused with their error, the open record's ranges, and mutated
//! sections that never panic.

use super::*;

#[test]
fn malformed_sections_are_refused_with_their_error() {
    let sec = shipped_section(8);
    let read = |b: &[u8]| QTable::<3, i8>::from_bytes(b).map(|_| ());
    assert_eq!(read(&sec), Ok(()));
    let invalid = |field, class| Err(QTableError::Invalid { field, class });
    // Class 0's record starts after the 32-byte header: scale, zero point, ML window.
    let cases: Vec<(Vec<u8>, Result<(), QTableError>)> = vec![
        (resealed(&sec, 0, b"MLMX"), Err(QTableError::NotQuantized)),
        (
            {
                let mut b = sec.clone();
                b[40] ^= 1;
                b
            },
            Err(QTableError::Corrupted),
        ),
        (
            resealed(&sec, 4, &[4]),
            Err(QTableError::UnsupportedVersion { found: 4 }),
        ),
        // Version 3 announces maps after the last record: there are none here.
        (resealed(&sec, 4, &[3]), Err(QTableError::Malformed)),
        (
            resealed(&sec, 4, &[0]),
            Err(QTableError::UnsupportedVersion { found: 0 }),
        ),
        // Version 1 has no open record: its 12 bytes are left over.
        (resealed(&sec, 4, &[1]), Err(QTableError::Malformed)),
        (
            resealed(&sec, 5, &[16]),
            Err(QTableError::ShapeMismatch {
                expected: (3, 8),
                found: (3, 16),
            }),
        ),
        (
            resealed(&sec, 8, &4u16.to_le_bytes()),
            Err(QTableError::ShapeMismatch {
                expected: (3, 8),
                found: (4, 8),
            }),
        ),
        (resealed(&sec, 6, &[2]), Err(QTableError::Malformed)),
        (resealed(&sec, 7, &[1]), Err(QTableError::Malformed)),
        (
            resealed(&sec, 14, &9u16.to_le_bytes()),
            invalid(QField::Shape, 0),
        ),
        (
            resealed(&sec, 20, &0f32.to_le_bytes()),
            invalid(QField::Lambda, 0),
        ),
        (
            resealed(&sec, 24, &f32::INFINITY.to_le_bytes()),
            invalid(QField::Lambda, 0),
        ),
        (
            resealed(&sec, 28, &f32::NAN.to_le_bytes()),
            invalid(QField::LogTerm, 0),
        ),
        (
            resealed(&sec, 32, &(-0.5f32).to_le_bytes()),
            invalid(QField::Scale, 0),
        ),
        (
            resealed(&sec, 36, &128i32.to_le_bytes()),
            invalid(QField::ZeroPoint, 0),
        ),
        (
            resealed(&sec, 40, &100i32.to_le_bytes()),
            invalid(QField::Window, 0),
        ),
        (
            resealed(&sec, 40, &(-129i32).to_le_bytes()),
            invalid(QField::Window, 0),
        ),
        (resealed(&sec, 48, &[22]), invalid(QField::Index, 0)),
    ];
    for (i, (bytes, want)) in cases.into_iter().enumerate() {
        assert_eq!(read(&bytes), want, "case {i}");
    }
    // A mass of 0 and a log-term of infinity, found by value.
    let ml_masses_at = {
        let n = u32::from_le_bytes(sec[44..48].try_into().unwrap()) as usize;
        48 + n
    };
    assert_eq!(
        read(&resealed(&sec, ml_masses_at, &0f32.to_le_bytes())),
        invalid(QField::Mass, 0)
    );
    let open_at = sec.len() - 8 - 12;
    let prior_at = open_at - 16;
    assert_eq!(
        read(&resealed(&sec, prior_at + 12, &f32::INFINITY.to_le_bytes())),
        invalid(QField::LogTerm, 3)
    );
    // The open record: temperature, epsilon, the unknown log-score (the shipped table:
    // epsilon 0, so -inf).
    let record =
        |at: usize| f32::from_le_bytes(sec[open_at + at..open_at + at + 4].try_into().unwrap());
    assert_eq!(
        (record(0), record(4), record(8)),
        (1.0, 0.0, f32::NEG_INFINITY)
    );
    let open_cases: Vec<(usize, f32, QField)> = vec![
        (0, 0.0, QField::Temperature),
        (0, -1.0, QField::Temperature),
        (0, f32::NAN, QField::Temperature),
        (0, 2e6, QField::Temperature),
        (0, 5e-7, QField::Temperature),
        (4, -0.0, QField::Epsilon),
        (4, -1e-3, QField::Epsilon),
        (4, f32::from_bits(1), QField::Epsilon),
        (4, 2e30, QField::Epsilon),
        (4, f32::INFINITY, QField::Epsilon),
        (4, f32::NAN, QField::Epsilon),
        // An unknown category with epsilon 0, or none with epsilon > 0.
        (8, 0.0, QField::LogUnknown),
        (8, -1e30, QField::LogUnknown),
        (8, f32::NAN, QField::LogUnknown),
        (8, f32::INFINITY, QField::LogUnknown),
        (4, 0.01, QField::LogUnknown),
    ];
    for (at, v, field) in open_cases {
        assert_eq!(
            read(&resealed(&sec, open_at + at, &v.to_le_bytes())),
            invalid(field, 0),
            "offset {at}: {v:e}"
        );
    }
    // Values in range are read as they are: the smallest and largest temperature and
    // epsilon, each epsilon > 0 with a finite log-score (the values `quantize` writes
    // are compared with the table's in `int8_open_head_equals_f32_layer_for_every_code`).
    let read_open = |t: f32, e: f32, l: f32| {
        let mut rec = Vec::new();
        for v in [t, e, l] {
            rec.extend_from_slice(&v.to_le_bytes());
        }
        QTable::<3, i8>::from_bytes(&resealed(&sec, open_at, &rec))
            .map(|q| open_bits(q.open_params()))
    };
    for (t, e, l) in [
        (1e-6f32, 0.0, f32::NEG_INFINITY),
        (1e6, 0.0, f32::NEG_INFINITY),
        (1.0, f32::MIN_POSITIVE, -100.0),
        (1.0, 1e30, 60.0),
        (2.5, 0.3, -1e30),
    ] {
        assert_eq!(
            read_open(t, e, l),
            Ok(Some([t.to_bits(), e.to_bits(), l.to_bits()]))
        );
    }
    // Version 2 needs the Bayes head: a section without it, marked version 2.
    let no_bayes = section(
        &shipped(),
        &QParams {
            bits: 8,
            scales: &[0.08; 3],
            zero_points: &[0; 3],
            bayes: false,
        },
    );
    assert_eq!(no_bayes[4], 1);
    assert_eq!(
        read(&resealed(&no_bayes, 4, &[2])),
        Err(QTableError::Malformed)
    );
    // Every truncation, and a byte added before the trailer.
    for n in 0..sec.len() {
        assert!(read(&sec[..n]).is_err(), "prefix of {n} bytes");
        assert!(
            read(&fix_crc(&sec[..n])).is_err(),
            "prefix of {n} bytes, CRC fixed"
        );
    }
    let mut longer = sec[..sec.len() - 8].to_vec();
    longer.push(0);
    let len = (longer.len() + 8) as u32;
    longer.extend_from_slice(&len.to_le_bytes());
    longer.extend_from_slice(&[0; 4]);
    assert_eq!(read(&fix_crc(&longer)), Err(QTableError::Malformed));
}

/// The open record's temperature and epsilon are accepted exactly where the table
/// accepts them (`DynTable::with_open`, the table decoder's rule): at, just inside and
/// just outside every bound, and NaN, infinities and -0.
#[cfg(feature = "std")]
#[test]
fn open_record_ranges_are_the_tables() {
    let sec = shipped_section(8);
    let open_at = sec.len() - 8 - 12;
    let table = mlmap::host::DynTable::from_table(&shipped());
    let up = |v: f32| f32::from_bits(v.to_bits() + 1);
    let down = |v: f32| f32::from_bits(v.to_bits() - 1);
    let (tmin, tmax, emax) = (
        mlmap::MIN_TEMPERATURE,
        mlmap::MAX_TEMPERATURE,
        mlmap::MAX_EPSILON,
    );
    let odd = [
        0.0f32,
        -0.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -1.0,
        f32::from_bits(1),
    ];
    let temperatures = [tmin, up(tmin), down(tmin), 1.0, tmax, up(tmax), down(tmax)];
    let epsilons = [
        f32::MIN_POSITIVE,
        down(f32::MIN_POSITIVE),
        0.5,
        emax,
        up(emax),
        down(emax),
    ];
    let record = |t: f32, e: f32| {
        // -inf with epsilon 0 (of either sign), a finite log-score otherwise.
        let l = if e == 0.0 { f32::NEG_INFINITY } else { -1.0 };
        let mut rec = Vec::new();
        for v in [t, e, l] {
            rec.extend_from_slice(&v.to_le_bytes());
        }
        QTable::<3, i8>::from_bytes(&resealed(&sec, open_at, &rec)).is_ok()
    };
    for t in temperatures.iter().chain(&odd) {
        let want = table.clone().with_open(*t, 0.0).is_ok();
        assert_eq!(record(*t, 0.0), want, "temperature {t:e}");
    }
    for e in epsilons.iter().chain(&odd) {
        let want = table.clone().with_open(1.0, *e).is_ok();
        assert_eq!(record(1.0, *e), want, "epsilon {e:e} ({:#x})", e.to_bits());
    }
}

/// Every byte of the section set to a few values, the CRC fixed: no panic, and any
/// section that is accepted scores within the invariants.
#[test]
fn mutated_sections_never_panic() {
    for (bits, open) in [(8u8, false), (16, false), (8, true), (16, true)] {
        let p = QParams {
            bits,
            scales: &[0.1; 3],
            zero_points: &[0; 3],
            bayes: true,
        };
        let sec = if open {
            section(&small_open(), &p)
        } else {
            section(&small_bayes(), &p)
        };
        let mut accepted = 0;
        for i in 0..sec.len() - 4 {
            for v in [0x00u8, 0x01, 0x7f, 0x80, 0xff, sec[i] ^ 0x10] {
                let b = resealed(&sec, i, &[v]);
                let (a, b) = (
                    QTable::<3, i8>::from_bytes(&b),
                    QTable::<3, i16>::from_bytes(&b),
                );
                if let Ok(q) = a {
                    accepted += 1;
                    for codes in [[0i8; 3], [127, -128, 5], [-3, 40, -90]] {
                        check_scores(&q.ml(&codes, 1.0).unwrap().0, 1.0, Sum::Equal).unwrap();
                        check_scores(&q.map(&codes, 1.0).unwrap().0, 1.0, Sum::Equal).unwrap();
                        check_scores(&q.bayes(&codes, 1.0).unwrap().0, 1.0, Sum::AtMost).unwrap();
                        check_open(&q.open(&codes, 1.0), open, &q.logits(&codes));
                    }
                }
                if let Ok(q) = b {
                    accepted += 1;
                    for codes in [[0i16; 3], [32767, -32768, 5]] {
                        check_scores(&q.ml(&codes, 1.0).unwrap().0, 1.0, Sum::Equal).unwrap();
                        check_scores(&q.map(&codes, 1.0).unwrap().0, 1.0, Sum::Equal).unwrap();
                        check_scores(&q.bayes(&codes, 1.0).unwrap().0, 1.0, Sum::AtMost).unwrap();
                        check_open(&q.open(&codes, 1.0), open, &q.logits(&codes));
                    }
                }
            }
        }
        assert!(accepted > 0);
    }
}

/// An accepted mutated section scores the open head within DESIGN §1.8's invariants, or
/// says it has none (a mutation cannot add the open head to a section without it: the
/// version byte of a version-1 section set to 2 leaves the record missing).
fn check_open(s: &Result<Scores<3>, InferError>, open: bool, x: &[f32; 3]) {
    match s {
        Ok(s) => {
            assert!(open, "an open head in a section built without one");
            check_scores(&s.0, 1.0, Sum::AtMost).unwrap();
            check_open_decision(&s.0, x).unwrap();
        }
        Err(e) => assert_eq!((*e, open), (InferError::NoOpenHead, false)),
    }
}
