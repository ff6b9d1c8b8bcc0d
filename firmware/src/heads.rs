//! The float heads of a decoded or embedded table against the host's float64 values:
//! ML, MAP, Bayes and open, one detection at a time and in batches, the invalid inputs'
//! errors, and the temperature layer of the table without background.

use super::*;

/// `got`'s scores against the host's `want` (within `TOLERANCE`) and the head's own
/// rule on them, as one check; the scores and the largest deviation, or `None` after
/// reporting the error.
fn scores_within(
    r: &mut Report,
    table: &str,
    head: &str,
    case: &Case<K>,
    got: Result<Scores<K>, InferError>,
    want: &[f64; K],
    rule: impl Fn(&Scores<K>) -> bool,
) -> Option<(Scores<K>, f64)> {
    let got = match got {
        Ok(s) => s,
        Err(e) => {
            r.check(
                false,
                case.label,
                format_args!("{table} {head}: error {e:?}"),
            );
            return None;
        }
    };
    let (mut max_err, mut within) = (0.0f64, true);
    for (&g, &w) in got.0.iter().zip(want) {
        let err = (f64::from(g) - w).abs();
        max_err = max_err.max(err);
        // A NaN score fails here (`max` would skip it).
        within &= err <= TOLERANCE;
    }
    r.check(
        within && rule(&got),
        case.label,
        format_args!("{table} {head}: got {:?}, want {:?}", got.0, want),
    );
    Some((got, max_err))
}

/// One head's scores against the host's values; returns the largest deviation.
pub(crate) fn check_head(
    r: &mut Report,
    table: &str,
    head: &str,
    case: &Case<K>,
    got: Result<Scores<K>, InferError>,
    want: &Expect<K>,
) -> f64 {
    #[allow(unused_mut)]
    let mut want_scores = want.scores;
    #[cfg(feature = "canary")]
    if case.label == CASES[0].label && head == "ML" {
        want_scores[0] += 1e-3;
    }
    // "I don't know": exactly OS / K each.
    let share = case.objectness / K as f32;
    let rule = |s: &Scores<K>| !want.uniform || s.0.iter().all(|g| g.to_bits() == share.to_bits());
    let Some((got, max_err)) = scores_within(r, table, head, case, got, &want_scores, rule) else {
        return 0.0;
    };
    if let Some(class) = want.argmax {
        r.check(
            got.argmax() == class,
            case.label,
            format_args!(
                "{table} {head}: predicted {}, want {}",
                got.argmax(),
                CLASS_NAMES[class]
            ),
        );
    }
    max_err
}

/// The open head's scores against the host's values and its decision against the
/// largest logit; returns the largest deviation.
pub(crate) fn check_open(
    r: &mut Report,
    table: &str,
    head: &str,
    case: &Case<K>,
    got: Result<Scores<K>, InferError>,
    want: &OpenExpect<K>,
) -> f64 {
    #[allow(unused_mut)]
    let mut want_scores = want.scores;
    #[cfg(feature = "canary")]
    if case.label == SMALL_CASES[0].label && head == "open" {
        want_scores[1] += 1e-3;
    }
    // Every score in [0, OS], summing to at most OS (DESIGN §1.8).
    let os = case.objectness;
    let rule = |s: &Scores<K>| {
        let sum: f64 = s.0.iter().map(|&g| f64::from(g)).sum();
        s.0.iter().all(|g| (0.0..=os).contains(g)) && sum <= f64::from(os) * (1.0 + 1e-5)
    };
    let Some((got, max_err)) = scores_within(r, table, head, case, got, &want_scores, rule) else {
        return 0.0;
    };
    let decided = got.decide(&case.logits);
    r.check(
        decided == want.decision,
        case.label,
        format_args!(
            "{table} {head}: decided {decided}, want the largest logit {}",
            want.decision
        ),
    );
    max_err
}

/// Every case with every head of `t`, and its open head's parameters.
pub(crate) fn check_table<
    const B_ML: usize,
    const B_MAP: usize,
    const BB: usize,
    const C: usize,
>(
    r: &mut Report,
    name: &str,
    t: &Table<K, B_ML, B_MAP, BB, C>,
    cases: &[Case<K>],
    open_params: (f32, f32),
) {
    let params = t.open_params().map(|p| (p.temperature(), p.epsilon()));
    r.check(
        params.map(|(a, b)| (a.to_bits(), b.to_bits()))
            == Some((open_params.0.to_bits(), open_params.1.to_bits())),
        "open head parameters",
        format_args!("{name}: {params:?}, want {open_params:?}"),
    );
    for (i, class) in CLASS_NAMES.iter().enumerate() {
        r.check(
            t.class_name(i) == Some(*class),
            "class names",
            format_args!("{name}: class {i} is {:?}, want {class}", t.class_name(i)),
        );
    }
    for case in cases {
        let logits = black_box(case.logits);
        let os = black_box(case.objectness);
        let e = check_head(r, name, "ML", case, t.ml(&logits, os), &case.ml);
        r.max_err_ml = r.max_err_ml.max(e);
        let e = check_head(r, name, "MAP", case, t.map(&logits, os), &case.map);
        r.max_err_map = r.max_err_map.max(e);
        let e = check_head(r, name, "Bayes", case, t.bayes(&logits, os), &case.bayes);
        r.max_err_bayes = r.max_err_bayes.max(e);
        let e = check_open(r, name, "open", case, t.open(&logits, os), &case.open);
        r.max_err_open = r.max_err_open.max(e);
        let got = t.open_with::<Libm>(&logits, os);
        let e = check_open(r, name, "open (libm)", case, got, &case.open);
        r.max_err_open = r.max_err_open.max(e);
        // The fast-math backend stays within its documented bound of libm.
        match (t.map(&logits, os), t.map_with::<FastMath>(&logits, os)) {
            (Ok(exact), Ok(fast)) => {
                let ok = exact
                    .0
                    .iter()
                    .zip(fast.0.iter())
                    .all(|(a, b)| (a - b).abs() <= FAST_MATH_MAX_SCORE_ERROR);
                r.check(
                    ok,
                    case.label,
                    format_args!("{name} MAP FastMath {:?} vs libm {:?}", fast.0, exact.0),
                );
            }
            _ => r.check(
                false,
                case.label,
                format_args!("{name} MAP FastMath: error"),
            ),
        }
    }
    for case in ERROR_CASES {
        let logits = black_box(case.logits);
        let os = black_box(case.objectness);
        for (head, got) in [
            ("ML", t.ml(&logits, os)),
            ("MAP", t.map(&logits, os)),
            ("MAP FastMath", t.map_with::<FastMath>(&logits, os)),
            ("Bayes", t.bayes(&logits, os)),
            ("open", t.open(&logits, os)),
            ("open (libm)", t.open_with::<Libm>(&logits, os)),
        ] {
            r.check(
                got == Err(case.error),
                case.label,
                format_args!("{name} {head}: got {got:?}, want {:?}", case.error),
            );
        }
    }
    // The batch API gives, row by row, the per-detection answers.
    let n = cases.len().min(ROWS);
    let mut logits = [[0.0f32; K]; ROWS];
    let mut os = [0.0f32; ROWS];
    for (i, case) in cases.iter().take(n).enumerate() {
        logits[i] = case.logits;
        os[i] = case.objectness;
    }
    let (logits, os) = (&logits[..n], &os[..n]);
    let mut out = [[0.0f32; K]; ROWS];
    let out = &mut out[..n];
    for head in ["ML", "MAP", "Bayes", "open"] {
        let result = match head {
            "ML" => t.ml_batch(logits, Some(os), out),
            "MAP" => t.map_batch(logits, Some(os), out),
            "Bayes" => t.bayes_batch(logits, Some(os), out),
            _ => t.open_batch(logits, Some(os), out),
        };
        let same = match result {
            Ok(()) => cases.iter().zip(out.iter()).all(|(c, row)| {
                let single = match head {
                    "ML" => t.ml(&c.logits, c.objectness),
                    "MAP" => t.map(&c.logits, c.objectness),
                    "Bayes" => t.bayes(&c.logits, c.objectness),
                    _ => t.open(&c.logits, c.objectness),
                };
                single.is_ok_and(|s| s.0 == *row)
            }),
            Err(_) => false,
        };
        r.check(
            same,
            "batch",
            format_args!("{name} {head}: batch rows differ from single detections"),
        );
    }
}

/// The open head with epsilon 0 and no background category is the temperature layer
/// (DESIGN §1.8), bit for bit, on every case of the small table.
pub(crate) fn check_temperature_identity(r: &mut Report) {
    let t = match SmallNoBg::from_bytes(black_box(SMALL_NOBG_FILE)) {
        Ok(t) => t,
        Err(e) => {
            r.check(
                false,
                "small table without background",
                format_args!("{e:?}"),
            );
            return;
        }
    };
    let Some(params) = t.open_params() else {
        r.check(
            false,
            "small table without background",
            format_args!("no open head"),
        );
        return;
    };
    r.check(
        params.epsilon() == 0.0,
        "small table without background",
        format_args!("epsilon {}, want 0", params.epsilon()),
    );
    for case in SMALL_CASES {
        let logits = black_box(case.logits);
        let os = black_box(case.objectness);
        let open = t.open(&logits, os);
        let temp = mlmap::baseline::temperature::<FastMath, K>(&logits, params.temperature(), os);
        let same = match (open, temp) {
            (Ok(a), Ok(b)) => a.0.map(f32::to_bits) == b.0.map(f32::to_bits),
            _ => false,
        };
        r.check(
            same,
            case.label,
            format_args!(
                "epsilon 0, no background: open {open:?} is not the temperature layer {temp:?}"
            ),
        );
    }
}
