//! The table checkers: valid tables pass; each settings, names, prior and histogram
//! violation is reported.

use super::*;

#[test]
fn valid_tables_pass() {
    let t = Table::<2, 2, 1>::from_parts(settings(1e-3, 1e-6), [spec("car"), spec("bus")]).unwrap();
    assert_eq!(check_table(&t), Ok(()));
    let shipped =
        Table::<3, 22, 17, 22, 4>::from_bytes(include_bytes!("../../../tables/default.mlmap"))
            .unwrap();
    assert_eq!(check_table(&shipped), Ok(()));
    #[cfg(feature = "std")]
    assert_eq!(
        check_dyn_table(&crate::host::DynTable::from_table(&shipped)),
        Ok(())
    );
    let h = Histogram::new(-1.0, 1.0, [0.5f32, 0.0, 0.5]).unwrap();
    assert_eq!(check_histogram(Head::Ml, 0, &h, 3), Ok(()));
}

#[test]
fn each_settings_names_and_prior_violation_is_reported() {
    fails(
        check_settings(&settings(0.0, 1.0)),
        Violation::Lambda {
            head: Head::Ml,
            lambda: 0.0,
        },
        5,
        "ML lambda = 0e0 is not in (0, 1e6]",
    );
    fails(
        check_settings(&settings(1.0, 2e6)),
        Violation::Lambda {
            head: Head::Map,
            lambda: 2e6,
        },
        5,
        "MAP lambda = 2e6",
    );
    let nan = check_settings(&settings(1.0, f32::NAN));
    assert!(
        matches!(nan, Err(Violation::Lambda { head: Head::Map, lambda }) if lambda.is_nan()),
        "{nan:?}"
    );
    assert_eq!(check_settings(&settings(MAX_LAMBDA, 1e-30)), Ok(()));

    assert_eq!(check_names(["car", "bus"]), Ok(()));
    fails(
        check_names(["car", "", "bus"]),
        Violation::Name { class: 1, len: 0 },
        5,
        "name of class 1 (0 bytes)",
    );
    fails(
        check_names(["car", "background"]),
        Violation::Name { class: 1, len: 10 },
        5,
        "or `background`",
    );
    let long = "x".repeat(NAME_MAX + 1);
    fails(
        check_names(["car", long.as_str()]),
        Violation::Name { class: 1, len: 32 },
        5,
        "longer than 31 bytes",
    );
    assert_eq!(check_names(["car", &long[1..]]), Ok(()));
    fails(
        check_names(["car", "bus", "car"]),
        Violation::DuplicateName { class: 2, first: 0 },
        5,
        "name of class 2 repeats the name of class 0",
    );
    fails(
        check_names(["car"]),
        Violation::ClassCount {
            expected: 2,
            found: 1,
        },
        5,
        "1 classes, the table needs 2",
    );

    assert_eq!(check_prior(3, -1e30, f32::MIN_POSITIVE), Ok(()));
    fails(
        check_prior(3, f32::INFINITY, 1.0),
        Violation::Mean {
            class: 3,
            mean: f32::INFINITY,
        },
        5,
        "prior mean of class 3 = inf is not finite",
    );
    for variance in [0.0, -1.0, f32::INFINITY] {
        fails(
            check_prior(3, 0.0, variance),
            Violation::Variance { class: 3, variance },
            5,
            "prior variance of class 3",
        );
    }
    assert!(check_prior(0, f32::NAN, 1.0).is_err());
    assert!(check_prior(0, 0.0, f32::NAN).is_err());
}

#[test]
fn each_histogram_violation_is_reported() {
    let ok = check_bins(Head::Ml, 1, [0.0, 0.5, 1.0], &[0.25, 0.75], 2);
    assert_eq!(ok, Ok(()));
    fails(
        check_bins(Head::Map, 4, [0.0, 0.5, 1.0], &[0.25, 0.75], 3),
        Violation::BinCount {
            head: Head::Map,
            class: 4,
            expected: 3,
            found: 2,
        },
        5,
        "MAP histogram of class 4 has 2 bins, the shape 3",
    );
    fails(
        check_bins(Head::Ml, 1, [0.0, 1.0], &[0.25, 0.75], 2),
        Violation::BinCount {
            head: Head::Ml,
            class: 1,
            expected: 2,
            found: 1,
        },
        5,
        "has 1 bins",
    );
    fails(
        check_bins(Head::Ml, 1, [0.0, f32::INFINITY, 1.0], &[0.25, 0.75], 2),
        Violation::EdgeNotFinite {
            head: Head::Ml,
            class: 1,
            edge: 1,
            value: f32::INFINITY,
        },
        5,
        "ML histogram of class 1: edge 1 = inf is not finite",
    );
    fails(
        check_bins(Head::Map, 0, [0.0, 1.0, 1.0], &[0.25, 0.75], 2),
        Violation::EdgesNotIncreasing {
            head: Head::Map,
            class: 0,
            edge: 2,
            previous: 1.0,
            value: 1.0,
        },
        5,
        "MAP histogram of class 0: edge 2 = 1e0 is not above edge 1 = 1e0",
    );
    fails(
        check_bins(Head::Ml, 2, [0.0, 0.5, 1.0], &[1.5, -0.5], 2),
        Violation::Frequency {
            head: Head::Ml,
            class: 2,
            bin: 1,
            value: -0.5,
        },
        5,
        "frequency 1 = -5e-1 is not finite and >= 0",
    );
    assert!(check_bins(Head::Ml, 2, [0.0, 0.5, 1.0], &[f32::NAN, 1.0], 2).is_err());
    // 1e-4 is the tolerance: 0.25 + 0.7502 is out, 0.25 + 0.75009 in.
    fails(
        check_bins(Head::Ml, 2, [0.0, 0.5, 1.0], &[0.25, 0.7502], 2),
        Violation::FrequencySum {
            head: Head::Ml,
            class: 2,
            sum: f64::from(0.25f32 + 0.7502f32),
        },
        5,
        "ML histogram of class 2: frequencies sum to 1.0002",
    );
    let edges = [0.0, 0.5, 1.0];
    assert_eq!(check_bins(Head::Ml, 2, edges, &[0.25, 0.750_09], 2), Ok(()));
}
