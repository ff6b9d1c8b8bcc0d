//! Shared test support: the tolerances (all in one place), the golden files written by
//! the numpy reference, and a raw `.mlmap` writer (versions 1 and 2) that can also write
//! *invalid* tables.
//!
//! Golden data comes from `tools/mlmap_ref.py` (numpy 2.4.6), an implementation of
//! DESIGN §1.2 and of the format that shares no code with the crate. Regenerate with
//!
//! ```text
//! python3 tools/mlmap_ref.py goldens tests/golden/layer
//! ```

use mlmap::{ClassSpec, EdgeMode, InferError, Settings, Table, UpperTail};

/// Largest absolute difference allowed between a score computed by the layer in `f32`
/// and the float64 reference, with `Libm` or with `FastMath` (whose `exp` is within
/// `FAST_MATH_MAX_REL_ERROR`, 2.3e-7, of `exp`: the Bayes and open heads' default).
pub const GOLDEN_ABS_TOL: f64 = 1e-6;

/// Shape of the hand-checkable table: 3 classes, 4 ML bins, 2 MAP bins.
pub type Small = Table<3, 4, 2>;
/// Shape of the shipped table `tables/default.mlmap`.
pub type Shipped = Table<3, 22, 17, 22, 4>;
/// The small table with a Bayes head of 4 bins and a background category.
pub type SmallBayes = Table<3, 4, 2, 4, 4>;
/// The small table with a Bayes head of 4 bins and no background category.
pub type SmallBayesNoBg = Table<3, 4, 2, 4, 3>;

/// `tests/golden/layer/small.mlmap`, written by the reference encoder.
pub const SMALL_MLMAP: &[u8] = include_bytes!("golden/layer/small.mlmap");
/// The same table with the `upper tail = clamp` policy.
pub const SMALL_CLAMP_MLMAP: &[u8] = include_bytes!("golden/layer/small_clamp.mlmap");
/// The small table plus a Bayes head with background (`SMALL_BAYES` in the script).
pub const SMALL_BAYES_MLMAP: &[u8] = include_bytes!("golden/layer/small_bayes.mlmap");
/// The small table plus a Bayes head without background (`SMALL_BAYES_NOBG`).
pub const SMALL_BAYES_NOBG_MLMAP: &[u8] = include_bytes!("golden/layer/small_bayes_nobg.mlmap");
/// The table shipped with the crate.
pub const SHIPPED_MLMAP: &[u8] = include_bytes!("../tables/default.mlmap");
/// Golden scores of the four small tables.
pub const SMALL_CSV: &str = include_str!("golden/layer/small.csv");
/// Golden scores of the shipped table for random logit vectors.
pub const SHIPPED_CSV: &str = include_str!("golden/layer/default.csv");
/// Golden scores of the shipped table for every 20th row of `examples/data/test.csv`
/// (the case column holds the row's id).
#[cfg(feature = "std")]
pub const TEST_SPLIT_CSV: &str = include_str!("golden/layer/test_split.csv");

pub fn small() -> Small {
    Small::from_bytes(SMALL_MLMAP).expect("small.mlmap is valid")
}

pub fn small_clamp() -> Small {
    Small::from_bytes(SMALL_CLAMP_MLMAP).expect("small_clamp.mlmap is valid")
}

pub fn small_bayes() -> SmallBayes {
    SmallBayes::from_bytes(SMALL_BAYES_MLMAP).expect("small_bayes.mlmap is valid")
}

pub fn small_bayes_nobg() -> SmallBayesNoBg {
    SmallBayesNoBg::from_bytes(SMALL_BAYES_NOBG_MLMAP).expect("small_bayes_nobg.mlmap is valid")
}

pub fn shipped() -> Shipped {
    Shipped::from_bytes(SHIPPED_MLMAP).expect("tables/default.mlmap is valid")
}

/// The settings of the small table (mirrors `SMALL_LAMBDA_*` in `tools/mlmap_ref.py`).
pub fn small_settings(upper_tail: UpperTail) -> Settings {
    Settings {
        lambda_ml: 0.01,
        lambda_map: 0.001,
        edge_mode: EdgeMode::Linspace,
        upper_tail,
    }
}

/// The classes of the small table (mirrors `SMALL` in `tools/mlmap_ref.py`).
pub fn small_specs() -> [ClassSpec<'static, [f32; 4], [f32; 2]>; 3] {
    [
        ClassSpec {
            name: "car",
            rows: 1000,
            mean: 2.0,
            variance: 1.0,
            ml_range: (0.0, 4.0),
            ml_freqs: [0.1, 0.2, 0.3, 0.4],
            map_range: (0.0, 4.0),
            map_freqs: [0.25, 0.75],
        },
        ClassSpec {
            name: "cyclist",
            rows: 250,
            mean: 0.0,
            variance: 0.25,
            ml_range: (-2.0, 2.0),
            ml_freqs: [0.4, 0.3, 0.2, 0.1],
            map_range: (-2.0, 2.0),
            map_freqs: [0.5, 0.5],
        },
        ClassSpec {
            name: "pedestrian",
            rows: 40,
            mean: -2.0,
            variance: 4.0,
            ml_range: (-4.0, 0.0),
            ml_freqs: [0.25; 4],
            map_range: (-4.0, 0.0),
            map_freqs: [0.6, 0.4],
        },
    ]
}

/// One row of a golden CSV file.
#[derive(Debug, Clone)]
pub struct Golden {
    pub table: String,
    pub case: String,
    pub objectness: f32,
    pub logits: [f32; 3],
    /// Expected scores (float64), `None` when an error is expected.
    pub ml: Option<[f64; 3]>,
    pub map: Option<[f64; 3]>,
    /// Expected Bayes scores, `None` for an error or a table without a Bayes head.
    pub bayes: Option<[f64; 3]>,
    /// The expected error, `None` when scores are expected.
    pub error: Option<InferError>,
}

fn parse_f32(s: &str) -> f32 {
    s.parse().unwrap_or_else(|_| panic!("not an f32: {s:?}"))
}

fn parse_f64(s: &str) -> f64 {
    s.parse().unwrap_or_else(|_| panic!("not an f64: {s:?}"))
}

fn three<T: Copy + Default>(fields: &[&str], parse: fn(&str) -> T) -> [T; 3] {
    let mut out = [T::default(); 3];
    for (o, f) in out.iter_mut().zip(fields) {
        *o = parse(f);
    }
    out
}

/// Parses a golden CSV file of a K = 3 table (see the header of the file).
pub fn goldens(csv: &str) -> Vec<Golden> {
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().expect("header");
    assert_eq!(
        header,
        "table,case,objectness,x0,x1,x2,ml0,ml1,ml2,map0,map1,map2,bayes0,bayes1,bayes2,error"
    );
    let rows: Vec<Golden> = lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), 16, "golden line {line:?}");
            let error = match f[15] {
                "" => None,
                "objectness" => Some(InferError::Objectness),
                e => {
                    let class = e
                        .strip_prefix("nan_logit:")
                        .and_then(|c| c.parse().ok())
                        .unwrap_or_else(|| panic!("unknown error {e:?}"));
                    Some(InferError::NanLogit { class })
                }
            };
            let scores = |r: &[&str]| error.is_none().then(|| three(r, parse_f64));
            Golden {
                table: f[0].to_owned(),
                case: f[1].to_owned(),
                objectness: parse_f32(f[2]),
                logits: three(&f[3..6], parse_f32),
                ml: scores(&f[6..9]),
                map: scores(&f[9..12]),
                bayes: (error.is_none() && !f[12].is_empty()).then(|| three(&f[12..15], parse_f64)),
                error,
            }
        })
        .collect();
    assert!(!rows.is_empty());
    rows
}

/// CRC-32/ISO-HDLC (zlib's `crc32`), the checksum of the format and its sections,
/// computed bit by bit: independent of the table-driven one the library uses.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A section (or table) with `bytes` written at `at` and its last four bytes, the
/// CRC-32 of everything before them, made right again.
pub fn resealed(section: &[u8], at: usize, bytes: &[u8]) -> Vec<u8> {
    let mut s = section.to_vec();
    s[at..at + bytes.len()].copy_from_slice(bytes);
    fix_crc(&s)
}

/// `payload` followed by its CRC-32, little-endian: a file whose checksum is right.
pub fn with_crc(payload: &[u8]) -> Vec<u8> {
    let mut out = payload.to_vec();
    out.extend_from_slice(&crc32(payload).to_le_bytes());
    out
}

/// `bytes` with its last four bytes replaced by the CRC-32 of the rest (bytes shorter
/// than four get a CRC appended).
pub fn fix_crc(bytes: &[u8]) -> Vec<u8> {
    with_crc(&bytes[..bytes.len().saturating_sub(4)])
}

/// One class as it is laid out on the wire, any values allowed.
#[derive(Debug, Clone, PartialEq)]
pub struct RawClass {
    pub name: Vec<u8>,
    pub rows: u64,
    pub mean: f32,
    pub variance: f32,
    pub ml_lo: f32,
    pub ml_hi: f32,
    pub ml_freqs: Vec<f32>,
    pub map_lo: f32,
    pub map_hi: f32,
    pub map_freqs: Vec<f32>,
}

/// The Bayes section of a version-2 table as laid out on the wire, any values allowed.
#[derive(Debug, Clone, PartialEq)]
pub struct RawBayes {
    pub lambda: f32,
    /// Rows per category (the sequence length is written from it).
    pub rows: Vec<u64>,
    /// `(lo, hi)` per logit.
    pub ranges: Vec<(f32, f32)>,
    /// Log-terms, category-major.
    pub terms: Vec<f32>,
}

/// The frequencies of the small Bayes heads, per category (car, cyclist, pedestrian,
/// background) and logit (mirrors `SMALL_BAYES_FREQS` in `tools/mlmap_ref.py`).
pub const SMALL_BAYES_FREQS: [[[f64; 4]; 3]; 4] = [
    [
        [0.0, 0.1, 0.3, 0.6],
        [0.4, 0.4, 0.2, 0.0],
        [0.2, 0.2, 0.3, 0.3],
    ],
    [
        [0.2, 0.5, 0.2, 0.1],
        [0.0, 0.1, 0.3, 0.6],
        [0.3, 0.3, 0.2, 0.2],
    ],
    [
        [0.3, 0.4, 0.2, 0.1],
        [0.25, 0.25, 0.25, 0.25],
        [0.0, 0.1, 0.3, 0.6],
    ],
    [
        [0.1, 0.2, 0.5, 0.2],
        [0.2, 0.3, 0.3, 0.2],
        [0.1, 0.4, 0.4, 0.1],
    ],
];

/// The axes of the small Bayes heads: `(lo, hi)` of logits 0, 1 and 2 (4 bins each).
pub const SMALL_BAYES_RANGES: [(f32, f32); 3] = [(-4.0, 4.0), (-2.0, 2.0), (-4.0, 0.0)];

/// `f32(ln(h + lambda))` computed in `f64`, the rule of the format for a log-term.
pub fn log_term(h: f64, lambda: f32) -> f32 {
    (h + f64::from(lambda)).ln() as f32
}

impl RawBayes {
    /// A head over [`SMALL_BAYES_RANGES`] whose category `c` has `rows[c]` rows and the
    /// frequencies `SMALL_BAYES_FREQS[c]`.
    pub fn small(rows: &[u64], lambda: f32) -> Self {
        let terms = SMALL_BAYES_FREQS[..rows.len()]
            .iter()
            .flatten()
            .flatten()
            .map(|&h| log_term(h, lambda))
            .collect();
        Self {
            lambda,
            rows: rows.to_vec(),
            ranges: SMALL_BAYES_RANGES.to_vec(),
            terms,
        }
    }

    /// The terms in the order the format stores them, logit-major (logit, bin,
    /// category); held category-major here. A sequence whose length does not fit the
    /// shape (a deliberately broken one) is returned as held.
    pub fn stored_terms(&self) -> Vec<f32> {
        let (cats, k) = (self.rows.len(), self.ranges.len());
        let bins = self.terms.len() / (cats * k).max(1);
        if cats * k * bins != self.terms.len() {
            return self.terms.clone();
        }
        let mut stored = Vec::with_capacity(self.terms.len());
        for j in 0..k {
            for bin in 0..bins {
                for c in 0..cats {
                    stored.extend(self.terms.get((c * k + j) * bins + bin));
                }
            }
        }
        stored
    }

    /// Sets the 4 log-terms of category `c` and logit `j` (K = 3) from frequencies.
    pub fn set_freqs(&mut self, c: usize, j: usize, freqs: [f64; 4]) {
        let start = (c * 3 + j) * 4;
        for (t, h) in self.terms[start..start + 4].iter_mut().zip(freqs) {
            *t = log_term(h, self.lambda);
        }
    }
}

/// A table as it is laid out on the wire (docs/FORMAT.md, versions 1 and 2), any values
/// allowed, so that a test can break exactly one thing and keep the CRC right.
#[derive(Debug, Clone, PartialEq)]
pub struct RawTable {
    pub magic: [u8; 4],
    pub version: u64,
    pub k: u64,
    pub bins_ml: u64,
    pub bins_map: u64,
    /// Version 2's `(Bayes bins, categories)`, written after `bins_map` when present.
    pub bayes_shape: Option<(u64, u64)>,
    pub edge_mode: u8,
    pub upper_tail: u8,
    pub lambda_ml: f32,
    pub lambda_map: f32,
    /// The class count written before the classes (normally `classes.len()`).
    pub class_count: u64,
    pub classes: Vec<RawClass>,
    /// The Bayes section, written after the classes when present.
    pub bayes: Option<RawBayes>,
    /// Bytes written after the classes (and the Bayes section), before the CRC.
    pub trailing: Vec<u8>,
}

fn varint(out: &mut Vec<u8>, mut n: u64) {
    loop {
        let b = (n & 0x7f) as u8;
        n >>= 7;
        if n == 0 {
            out.push(b);
            return;
        }
        out.push(b | 0x80);
    }
}

fn floats(out: &mut Vec<u8>, v: &[f32]) {
    varint(out, v.len() as u64);
    for x in v {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

impl RawTable {
    /// The hand-checkable table of `tools/mlmap_ref.py` (`SMALL`).
    pub fn small() -> Self {
        let classes = small_specs()
            .iter()
            .map(|c| RawClass {
                name: c.name.as_bytes().to_vec(),
                rows: c.rows,
                mean: c.mean,
                variance: c.variance,
                ml_lo: c.ml_range.0,
                ml_hi: c.ml_range.1,
                ml_freqs: c.ml_freqs.to_vec(),
                map_lo: c.map_range.0,
                map_hi: c.map_range.1,
                map_freqs: c.map_freqs.to_vec(),
            })
            .collect();
        let s = small_settings(UpperTail::Zero);
        Self {
            magic: *b"MLMP",
            version: 1,
            k: 3,
            bins_ml: 4,
            bins_map: 2,
            bayes_shape: None,
            edge_mode: 0,
            upper_tail: 0,
            lambda_ml: s.lambda_ml,
            lambda_map: s.lambda_map,
            class_count: 3,
            classes,
            bayes: None,
            trailing: Vec::new(),
        }
    }

    /// The small table with the Bayes head of `tests/golden/layer/small_bayes.mlmap`
    /// (background: 4 categories, lambda 0.01).
    pub fn small_bayes() -> Self {
        Self::small_with(RawBayes::small(&[40, 20, 20, 20], 0.01))
    }

    /// The small table with the Bayes head of `small_bayes_nobg.mlmap` (3 categories,
    /// lambda 0.001).
    pub fn small_bayes_nobg() -> Self {
        Self::small_with(RawBayes::small(&[40, 20, 20], 0.001))
    }

    /// The small table with `bayes` as its Bayes head (version 2, 4 bins per logit).
    pub fn small_with(bayes: RawBayes) -> Self {
        Self {
            version: 2,
            bayes_shape: Some((4, bayes.rows.len() as u64)),
            bayes: Some(bayes),
            ..Self::small()
        }
    }

    /// The bytes before the CRC.
    pub fn payload(&self) -> Vec<u8> {
        let mut b = self.magic.to_vec();
        for v in [self.version, self.k, self.bins_ml, self.bins_map] {
            varint(&mut b, v);
        }
        if let Some((bins, categories)) = self.bayes_shape {
            varint(&mut b, bins);
            varint(&mut b, categories);
        }
        b.push(self.edge_mode);
        b.push(self.upper_tail);
        b.extend_from_slice(&self.lambda_ml.to_le_bytes());
        b.extend_from_slice(&self.lambda_map.to_le_bytes());
        varint(&mut b, self.class_count);
        for c in &self.classes {
            varint(&mut b, c.name.len() as u64);
            b.extend_from_slice(&c.name);
            varint(&mut b, c.rows);
            for v in [c.mean, c.variance, c.ml_lo, c.ml_hi] {
                b.extend_from_slice(&v.to_le_bytes());
            }
            floats(&mut b, &c.ml_freqs);
            b.extend_from_slice(&c.map_lo.to_le_bytes());
            b.extend_from_slice(&c.map_hi.to_le_bytes());
            floats(&mut b, &c.map_freqs);
        }
        if let Some(bayes) = &self.bayes {
            b.extend_from_slice(&bayes.lambda.to_le_bytes());
            varint(&mut b, bayes.rows.len() as u64);
            for &n in &bayes.rows {
                varint(&mut b, n);
            }
            varint(&mut b, bayes.ranges.len() as u64);
            for &(lo, hi) in &bayes.ranges {
                b.extend_from_slice(&lo.to_le_bytes());
                b.extend_from_slice(&hi.to_le_bytes());
            }
            floats(&mut b, &bayes.stored_terms());
        }
        b.extend_from_slice(&self.trailing);
        b
    }

    /// The complete file, with a correct CRC.
    pub fn encode(&self) -> Vec<u8> {
        with_crc(&self.payload())
    }
}
