use std::path::Path;

use mlmap::dequantize;

use super::*;

/// `val.csv` with its logits replaced by codes `clamp(round(x / scale_c) + zp_c)` (the
/// `codes` file) and by the dequantized logits of those codes, written exactly (the
/// `logits` file): `apply` of the second is what `apply --quantized` of the first must
/// write, byte for byte.
fn code_files(dir: &Path, scales: [f32; 3], zps: [i32; 3], bits: u8) -> (String, String) {
    let (lo, hi) = mlmap::code_range(bits);
    let mut r = csv::Reader::from_path(data("val")).unwrap();
    let header = r.headers().unwrap().clone();
    let (mut codes, mut logits) = (
        csv::Writer::from_path(dir.join("codes.csv")).unwrap(),
        csv::Writer::from_path(dir.join("logits.csv")).unwrap(),
    );
    codes.write_record(&header).unwrap();
    logits.write_record(&header).unwrap();
    for rec in r.records() {
        let rec = rec.unwrap();
        let (mut c_rec, mut x_rec) = (Vec::new(), Vec::new());
        for (field, value) in header.iter().zip(rec.iter()) {
            let class = ["car", "cyclist", "pedestrian"]
                .iter()
                .position(|c| *c == field);
            match class {
                Some(c) => {
                    let x: f64 = value.parse().unwrap();
                    let q = ((x / f64::from(scales[c])).round() as i32 + zps[c]).clamp(lo, hi);
                    c_rec.push(q.to_string());
                    // The f32 logit as its exact f64 decimal: read back to the same f32.
                    x_rec.push(f64::from(dequantize(q, scales[c], zps[c])).to_string());
                }
                None => {
                    c_rec.push(value.to_string());
                    x_rec.push(value.to_string());
                }
            }
        }
        codes.write_record(&c_rec).unwrap();
        logits.write_record(&x_rec).unwrap();
    }
    codes.flush().unwrap();
    logits.flush().unwrap();
    ("codes.csv".into(), "logits.csv".into())
}

fn quantize(
    dir: &Path,
    table: &str,
    scale: &str,
    zp: &str,
    bits: &str,
    more: &[&str],
    out: &str,
) -> Run {
    let mut args = vec![
        "quantize",
        "--table",
        table,
        "--scale",
        scale,
        "--zero-point",
        zp,
        "--bits",
        bits,
        "-o",
        out,
    ];
    args.extend_from_slice(more);
    ok(dir, &args)
}

#[test]
fn apply_quantized_equals_apply_on_the_dequantized_logits() {
    let dir = tempdir();
    let d = dir.path();
    for (scales, zps, bits, scale, zp) in [
        ([0.08f32; 3], [0i32; 3], 8u8, "0.08", "0"),
        (
            [0.05, 0.04, 0.06],
            [3, -7, 0],
            8,
            "0.05,0.04,0.06",
            "3,-7,0",
        ),
        ([0.001; 3], [100; 3], 16, "0.001", "100"),
    ] {
        for (table, more) in [
            (bayes_table(), &[][..]),
            (bayes_table(), &["--no-bayes"][..]),
            (golden_table(), &[][..]),
        ] {
            let run = quantize(d, &table, scale, zp, &bits.to_string(), more, "q.mlmap");
            assert!(run.stdout.contains("quantized section"), "{run:?}");
            let (codes, logits) = code_files(d, scales, zps, bits);
            ok(
                d,
                &[
                    "apply",
                    "--quantized",
                    "--table",
                    "q.mlmap",
                    "--input",
                    &codes,
                    "-o",
                    "a.csv",
                ],
            );
            ok(d, &apply_args(&table, &logits, "b.csv"));
            let (a, b) = (
                std::fs::read_to_string(d.join("a.csv")).unwrap(),
                std::fs::read_to_string(d.join("b.csv")).unwrap(),
            );
            if more.is_empty() {
                assert_eq!(a, b, "{scale} / {zp} / int{bits} / {table}");
            } else {
                // Without the Bayes head in the section: the same ML and MAP columns.
                let drop = |t: &str| -> Vec<String> {
                    t.lines()
                        .map(|l| {
                            l.split(',')
                                .enumerate()
                                // id, label, ML 2..5, MAP 5..8, Bayes 8..11, open
                                // 11..14, then the ML, MAP, Bayes and open decisions.
                                .filter(|(i, _)| !(8..14).contains(i) && *i < 16)
                                .map(|(_, f)| f)
                                .collect::<Vec<_>>()
                                .join(",")
                        })
                        .collect()
                };
                assert!(!a.lines().next().unwrap().contains("bayes"));
                assert_eq!(a.lines().map(str::to_string).collect::<Vec<_>>(), drop(&b));
            }
        }
    }
}

#[test]
fn apply_quantized_reads_int8_and_int16_npy() {
    let dir = tempdir();
    let d = dir.path();
    let table = bayes_table();
    for (bits, codes) in [
        (8u8, vec![50i64, -20, 10, 127, -128, 0, 0, 0, 0]),
        (16, vec![5000, -2000, 1000, 32767, -32768, 0, 9, -9, 3]),
    ] {
        let scale = if bits == 8 { 0.08f32 } else { 0.0008 };
        quantize(
            d,
            &table,
            &scale.to_string(),
            "0",
            &bits.to_string(),
            &[],
            "q.mlmap",
        );
        for (name, float) in [("q", false), ("x", true)] {
            let sub = d.join(format!("{name}{bits}"));
            std::fs::create_dir_all(&sub).unwrap();
            if float {
                let x: Vec<f64> = codes
                    .iter()
                    .map(|&q| f64::from(dequantize(q as i32, scale, 0)))
                    .collect();
                write_npy(&sub.join("logits.npy"), &[3, 3], &x);
            } else if bits == 8 {
                write_npy(
                    &sub.join("logits.npy"),
                    &[3, 3],
                    &codes.iter().map(|&q| q as i8).collect::<Vec<_>>(),
                );
            } else {
                write_npy(
                    &sub.join("logits.npy"),
                    &[3, 3],
                    &codes.iter().map(|&q| q as i16).collect::<Vec<_>>(),
                );
            }
            write(&sub, "classes.txt", "car\ncyclist\npedestrian\n");
        }
        let (q, x) = (format!("q{bits}"), format!("x{bits}"));
        ok(
            d,
            &[
                "apply",
                "--quantized",
                "--table",
                "q.mlmap",
                "--input",
                &q,
                "-o",
                "a.csv",
            ],
        );
        ok(d, &apply_args(&table, &x, "b.csv"));
        assert_eq!(
            std::fs::read(d.join("a.csv")).unwrap(),
            std::fs::read(d.join("b.csv")).unwrap()
        );
        // Float logits are not codes.
        refused(
            d,
            &[
                "apply",
                "--quantized",
                "--table",
                "q.mlmap",
                "--input",
                &x,
                "-o",
                "c.csv",
            ],
            &["logits.npy", "int8 or int16"],
        );
    }
}

#[test]
fn quantized_inputs_and_tables_that_do_not_fit_are_refused() {
    let dir = tempdir();
    let d = dir.path();
    let table = bayes_table();
    quantize(d, &table, "0.08", "0", "8", &[], "q.mlmap");
    let head = "id,label,objectness,car,cyclist,pedestrian\n";
    write(
        d,
        "half.csv",
        &format!("{head}1,car,0.9,3,4,5\n2,car,0.9,3,4.5,5\n"),
    );
    refused(
        d,
        &[
            "apply",
            "--quantized",
            "--table",
            "q.mlmap",
            "--input",
            "half.csv",
            "-o",
            "o.csv",
        ],
        &[
            "half.csv:3",
            "cyclist",
            "4.5",
            "not an integer code in [-128, 127]",
        ],
    );
    write(d, "big.csv", &format!("{head}1,car,0.9,3,4,128\n"));
    refused(
        d,
        &[
            "apply",
            "--quantized",
            "--table",
            "q.mlmap",
            "--input",
            "big.csv",
            "-o",
            "o.csv",
        ],
        &["big.csv:2", "pedestrian", "128"],
    );
    // A table without a section.
    write(d, "ok.csv", &format!("{head}1,car,0.9,3,4,5\n"));
    refused(
        d,
        &[
            "apply",
            "--quantized",
            "--table",
            &table,
            "--input",
            "ok.csv",
            "-o",
            "o.csv",
        ],
        &["default.mlmap", "no quantized section", "mlmap quantize"],
    );
    // A section whose checksum is broken.
    let mut bytes = std::fs::read(d.join("q.mlmap")).unwrap();
    let n = bytes.len();
    bytes[n - 100] ^= 1;
    std::fs::write(d.join("bad.mlmap"), &bytes).unwrap();
    refused(
        d,
        &[
            "apply",
            "--quantized",
            "--table",
            "bad.mlmap",
            "--input",
            "ok.csv",
            "-o",
            "o.csv",
        ],
        &["bad.mlmap", "checksum"],
    );
    // Parameters.
    for (scale, zp, bits, needle) in [
        ("0.1,0.2", "0", "8", "--scale has 2 values"),
        ("0.1", "0,1", "8", "--zero-point has 2 values"),
        ("0", "0", "8", "scale of class 0"),
        ("0.1", "-129", "8", "zero point of class 0"),
        ("0.1", "0", "12", "8 or 16 bits"),
    ] {
        refused(
            d,
            &[
                "quantize",
                "--table",
                &table,
                "--scale",
                scale,
                "--zero-point",
                zp,
                "--bits",
                bits,
                "-o",
                "x.mlmap",
            ],
            &[needle],
        );
    }
}

#[test]
fn a_quantized_table_is_still_a_table_and_inspect_shows_its_section() {
    let dir = tempdir();
    let d = dir.path();
    let table = bayes_table();
    quantize(d, &table, "0.05,0.04,0.06", "3,-7,0", "8", &[], "q.mlmap");
    // Every command that reads a table reads the table part.
    ok(d, &apply_args("q.mlmap", &data("val"), "a.csv"));
    ok(d, &apply_args(&table, &data("val"), "b.csv"));
    assert_eq!(
        std::fs::read(d.join("a.csv")).unwrap(),
        std::fs::read(d.join("b.csv")).unwrap()
    );
    // Quantizing a quantized table replaces its section.
    quantize(d, "q.mlmap", "0.08", "0", "16", &[], "q16.mlmap");
    let plain = std::fs::read(&table).unwrap();
    let q16 = std::fs::read(d.join("q16.mlmap")).unwrap();
    assert_eq!(&q16[..plain.len()], &plain[..]);
    let text = ok(d, &["inspect", "q.mlmap"]).stdout;
    for needle in [
        "quantized  ",
        "int8",
        "car",
        "scale 0.05",
        "zero point -7",
        "Bayes",
        // `fit` writes the open head with T = 1 and epsilon = 0; the section carries it.
        "heads ML, MAP, Bayes, open",
        "open head: temperature 1, epsilon 0, ln unknown -inf",
    ] {
        assert!(text.contains(needle), "{needle:?} not in:\n{text}");
    }
    let json = ok_json(d, &["inspect", "--format", "json", "q.mlmap"]);
    let q = &json["quantized"];
    assert_eq!(q["bits"], 8);
    assert_eq!(q["classes"][1]["zero_point"], -7);
    assert_eq!(q["open"]["temperature"], 1.0);
    assert_eq!(q["open"]["epsilon"], 0.0);
    assert!(q["open"]["log_unknown"].is_null(), "-inf for epsilon 0");
    assert_eq!(
        q["bytes"].as_u64().unwrap() as usize + plain.len(),
        std::fs::read(d.join("q.mlmap")).unwrap().len()
    );
    assert_eq!(json["bytes"].as_u64().unwrap() as usize, plain.len());
    let json = ok_json(d, &["inspect", "--format", "json", &table]);
    assert!(json["quantized"].is_null());
}
