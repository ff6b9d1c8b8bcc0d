use super::*;

/// The small golden frame copied into `dir` as `scan.bin` and `calib.txt`.
fn frame(dir: &Path) {
    std::fs::copy(repo("tests/golden/lidar/small.bin"), dir.join("scan.bin")).unwrap();
    std::fs::copy(
        repo("tests/golden/lidar/small_calib.txt"),
        dir.join("calib.txt"),
    )
    .unwrap();
}

fn npy(path: &Path) -> (Vec<u64>, Vec<f32>) {
    let bytes = std::fs::read(path).unwrap();
    let f = npyz::NpyFile::new(&bytes[..]).unwrap();
    (f.shape().to_vec(), f.into_vec::<f32>().unwrap())
}

fn golden_npy(name: &str) -> Vec<f32> {
    npy(&repo(&format!("tests/golden/lidar/{name}"))).1
}

fn close(got: &[f32], want: &[f32]) {
    assert_eq!(got.len(), want.len());
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= 1e-5 * w.abs().max(1e-30),
            "pixel {i}: {g} vs {w}"
        );
    }
}

/// The four maps, the PNGs' 16-bit scaling, the sparse maps, the r0 option and the crops.
#[test]
fn lidar_maps_writes_the_reference_maps() {
    let dir = tempdir();
    let d = dir.path();
    frame(d);
    let base = [
        "lidar-maps",
        "--velodyne",
        "scan.bin",
        "--calib",
        "calib.txt",
        "--width",
        "96",
        "--height",
        "32",
    ];
    let run = ok(d, &[&base[..], &["--sparse", "-o", "out"]].concat());
    assert!(
        run.stdout
            .contains("508 points, 461 in the 96 x 32 image, 427 pixels"),
        "{}",
        run.stdout
    );
    let (shape, rav) = npy(&d.join("out/rav.npy"));
    assert_eq!(shape, [32, 96]);
    close(&rav, &golden_npy("m13_rav.npy"));
    close(&npy(&d.join("out/rev.npy")).1, &golden_npy("m13_rev.npy"));
    assert_eq!(
        npy(&d.join("out/rav_sparse.npy")).1,
        golden_npy("small_rav_sparse.npy")
    );
    assert_eq!(
        npy(&d.join("out/rev_sparse.npy")).1,
        golden_npy("small_rev_sparse.npy")
    );
    // The PNG: 16-bit grayscale, range x 256 rounded.
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(d.join("out/rav.png")).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0u8; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(
        (info.width, info.height, info.bit_depth),
        (96, 32, png::BitDepth::Sixteen)
    );
    assert_eq!(info.color_type, png::ColorType::Grayscale);
    for (i, px) in buf.chunks_exact(2).enumerate() {
        let v = u16::from_be_bytes([px[0], px[1]]);
        let want = (f64::from(rav[i]) * 256.0 + 0.5).floor().min(65535.0) as u16;
        assert_eq!(v, want, "pixel {i}");
    }

    ok(d, &[&base[..], &["--mask", "5", "-o", "m5"]].concat());
    close(&npy(&d.join("m5/rav.npy")).1, &golden_npy("m5_rav.npy"));
    ok(d, &[&base[..], &["--r0", "nearest", "-o", "near"]].concat());
    close(
        &npy(&d.join("near/rev.npy")).1,
        &golden_npy("m13_nearest_rev.npy"),
    );
    assert!(!d.join("near/rav_sparse.npy").exists());

    write(d, "label.txt", "Car 0 0 0 10.5 3.2 20.9 7.5 1 1 1 0 0 0 0\nDontCare -1 -1 -10 1 1 2 2 -1 -1 -1 -1 -1 -1 -10\nPedestrian 0 0 0 90 20 100 40 1 1 1 0 0 0 0 0.5\n");
    ok(
        d,
        &[&base[..], &["--boxes", "label.txt", "-o", "crops"]].concat(),
    );
    let (csv_head, rows) = read_csv(&d.join("crops/crops/crops.csv"));
    assert_eq!(csv_head, ["index", "type", "col0", "row0", "col1", "row1"]);
    assert_eq!(
        rows,
        [
            ["0", "Car", "10", "3", "21", "8"],
            ["1", "Pedestrian", "90", "20", "96", "32"]
        ]
    );
    let (shape, car) = npy(&d.join("crops/crops/000_Car.npy"));
    assert_eq!(shape, [2, 5, 11]);
    let rev = golden_npy("m13_rev.npy");
    assert_eq!(car[0], rav[3 * 96 + 10]);
    assert_eq!(
        car[55 + 4 * 11 + 10],
        npy(&d.join("crops/rev.npy")).1[7 * 96 + 20]
    );
    close(&[car[55]], &[rev[3 * 96 + 10]]);
    assert!(d.join("crops/crops/001_Pedestrian.npy").exists());
}

/// Bad scans, calibrations, labels and flags: exit code 2, the file named, nothing written.
#[test]
fn lidar_maps_refuses_bad_input() {
    let dir = tempdir();
    let d = dir.path();
    frame(d);
    // The default flags with `extra`'s (flag, value) pairs in place of theirs.
    let run = |extra: &[&str], needles: &[&str]| {
        let mut flags = vec![
            ("--velodyne", "scan.bin"),
            ("--calib", "calib.txt"),
            ("--width", "96"),
            ("--height", "32"),
            ("-o", "out"),
        ];
        for pair in extra.chunks_exact(2) {
            match flags.iter_mut().find(|(f, _)| *f == pair[0]) {
                Some(slot) => slot.1 = pair[1],
                None => flags.push((pair[0], pair[1])),
            }
        }
        let mut args = vec!["lidar-maps"];
        for (f, v) in flags {
            args.extend([f, v]);
        }
        refused(d, &args, needles);
    };
    let scan = std::fs::read(d.join("scan.bin")).unwrap();
    std::fs::write(d.join("short.bin"), &scan[..scan.len() - 5]).unwrap();
    let mut nan = scan.clone();
    nan[16 * 3 + 4..16 * 3 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(d.join("nan.bin"), &nan).unwrap();
    let calib = std::fs::read_to_string(d.join("calib.txt")).unwrap();
    write(d, "no_r0.txt", &calib.replace("R0_rect", "R_rect"));
    write(d, "short.txt", &calib.replace(" 0.003\n", "\n"));
    let cases: [(&[&str], &[&str]); 9] = [
        (
            &["--velodyne", "short.bin"],
            &["short.bin: 8123 bytes", "truncated"],
        ),
        (
            &["--velodyne", "nan.bin"],
            &["nan.bin: point 3 (bytes 48..64): y is NaN"],
        ),
        (&["--velodyne", "missing.bin"], &["missing.bin"]),
        (&["--calib", "no_r0.txt"], &["no_r0.txt: no R0_rect line"]),
        (
            &["--calib", "short.txt"],
            &["short.txt:2: P2 has 11 numbers; expected 12"],
        ),
        (&["--mask", "4"], &["--mask 4 is out of range"]),
        (&["--mask", "65"], &["--mask 65 is out of range"]),
        (&["--width", "0"], &["--width 0 is out of range"]),
        (&["--boxes", "calib.txt"], &["calib.txt:1: 13 fields"]),
    ];
    for (extra, needles) in cases {
        run(extra, needles);
    }
    write(d, "out", "a file");
    refused(
        d,
        &[
            "lidar-maps",
            "--velodyne",
            "scan.bin",
            "--calib",
            "calib.txt",
            "-o",
            "out",
        ],
        &["out: is not a directory"],
    );
}
