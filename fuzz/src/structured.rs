//! Structured tables: reals, frequencies, names, classes and settings from fuzz input,
//! and whole tables (`ArbTable`) of a given shape built from them.

use super::*;

/// A real number from fuzz input: mostly ordinary magnitudes, sometimes any `f32` bit
/// pattern (NaN, ±inf, subnormals, extremes).
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Real {
    /// `v / 64`: values of order 1 to 500, the range logits live in.
    Small(i16),
    /// `m * 2^e`: any magnitude, exactly representable.
    Scaled(i16, i8),
    /// Any bit pattern.
    Bits(u32),
}

impl Real {
    /// The value.
    pub fn get(self) -> f32 {
        match self {
            Real::Small(v) => f32::from(v) / 64.0,
            Real::Scaled(m, e) => f32::from(m) * 2f32.powi(i32::from(e)),
            Real::Bits(b) => f32::from_bits(b),
        }
    }

    /// The value made non-negative, except for raw bit patterns (which may be anything,
    /// so that validation sees negative and non-finite values too).
    pub fn positive(self) -> f32 {
        match self {
            Real::Bits(b) => f32::from_bits(b),
            other => other.get().abs(),
        }
    }
}

/// Frequencies of a `B`-bin histogram.
#[derive(Arbitrary, Debug, Clone)]
pub enum Freqs<const B: usize> {
    /// Proportional to integer weights (uniform when they are all 0).
    Weights([u16; B]),
    /// All mass in one bin.
    OneHot(u16),
    /// Any bit patterns (almost always invalid).
    Bits([u32; B]),
}

impl<const B: usize> Freqs<B> {
    /// The `B` frequencies.
    pub fn get(&self) -> [f32; B] {
        match self {
            Freqs::Weights(w) => {
                let total: u64 = w.iter().map(|&v| u64::from(v)).sum();
                if total == 0 {
                    [1.0 / B as f32; B]
                } else {
                    w.map(|v| (f64::from(v) / total as f64) as f32)
                }
            }
            Freqs::OneHot(i) => {
                let mut f = [0.0; B];
                f[usize::from(*i) % B] = 1.0;
                f
            }
            Freqs::Bits(b) => b.map(f32::from_bits),
        }
    }
}

/// One histogram: first edge, width of the support, frequencies.
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbHistogram<const B: usize> {
    lo: Real,
    span: Real,
    freqs: Freqs<B>,
}

impl<const B: usize> ArbHistogram<B> {
    fn range(&self) -> (f32, f32) {
        let lo = self.lo.get();
        (lo, lo + self.span.positive())
    }
}

/// A class name: a usual one, or any string.
#[derive(Arbitrary, Debug, Clone)]
pub enum ArbName {
    /// One of a few usual names (so that duplicates occur).
    Known(u8),
    /// Any UTF-8 string.
    Text(String),
}

impl ArbName {
    fn get(&self) -> &str {
        const KNOWN: [&str; 8] = [
            "car",
            "cyclist",
            "pedestrian",
            "truck",
            "bus",
            "background",
            "x",
            "a-class-name-of-exactly-31-bytes",
        ];
        match self {
            ArbName::Known(i) => KNOWN[usize::from(*i) % KNOWN.len()],
            ArbName::Text(s) => s,
        }
    }
}

/// One class's statistics.
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbClass<const B_ML: usize, const B_MAP: usize> {
    name: ArbName,
    rows: u64,
    mean: Real,
    variance: Real,
    ml: ArbHistogram<B_ML>,
    map: ArbHistogram<B_MAP>,
}

impl<const B_ML: usize, const B_MAP: usize> ArbClass<B_ML, B_MAP> {
    fn spec(&self) -> ClassSpec<'_, [f32; B_ML], [f32; B_MAP]> {
        ClassSpec {
            name: self.name.get(),
            rows: self.rows,
            mean: self.mean.get(),
            variance: self.variance.positive(),
            ml_range: self.ml.range(),
            ml_freqs: self.ml.freqs.get(),
            map_range: self.map.range(),
            map_freqs: self.map.freqs.get(),
        }
    }
}

/// Settings of a table.
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbSettings {
    lambda_ml: Real,
    lambda_map: Real,
    matlab: bool,
    clamp: bool,
}

impl ArbSettings {
    fn get(&self) -> Settings {
        Settings {
            lambda_ml: self.lambda_ml.positive(),
            lambda_map: self.lambda_map.positive(),
            edge_mode: if self.matlab {
                EdgeMode::Matlab
            } else {
                EdgeMode::Linspace
            },
            upper_tail: if self.clamp {
                UpperTail::Clamp
            } else {
                UpperTail::Zero
            },
        }
    }
}

/// A whole table, valid or not; [`ArbTable::build`] validates it.
#[derive(Arbitrary, Debug, Clone)]
pub struct ArbTable<const K: usize, const B_ML: usize, const B_MAP: usize> {
    settings: ArbSettings,
    classes: [ArbClass<B_ML, B_MAP>; K],
}

impl<const K: usize, const B_ML: usize, const B_MAP: usize> ArbTable<K, B_ML, B_MAP> {
    /// `Table::from_parts` of these statistics. When it succeeds, asserts that the table
    /// stores the statistics exactly as given.
    pub fn build(&self) -> Result<Table<K, B_ML, B_MAP>, TableError> {
        let settings = self.settings.get();
        let specs: [ClassSpec<'_, [f32; B_ML], [f32; B_MAP]>; K] =
            core::array::from_fn(|i| self.classes[i].spec());
        let t = Table::from_parts(settings, specs.clone())?;
        assert_eq!(bits_of_settings(t.settings()), bits_of_settings(&settings));
        for (i, want) in specs.iter().enumerate() {
            let got = t.spec(i).expect("spec of an existing class");
            assert_eq!(got.name, want.name, "class {i}: name");
            assert_eq!(got.rows, want.rows, "class {i}: rows");
            let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
            assert_eq!(scalars(&got), scalars(want), "class {i}: statistics");
            assert_eq!(
                bits(got.ml_freqs),
                bits(&want.ml_freqs),
                "class {i}: ML freqs"
            );
            assert_eq!(
                bits(got.map_freqs),
                bits(&want.map_freqs),
                "class {i}: MAP freqs"
            );
        }
        Ok(t)
    }
}

/// The scalar statistics of a class, as bits.
fn scalars<F, G>(c: &ClassSpec<'_, F, G>) -> [u32; 6] {
    [
        c.mean,
        c.variance,
        c.ml_range.0,
        c.ml_range.1,
        c.map_range.0,
        c.map_range.1,
    ]
    .map(f32::to_bits)
}

fn bits_of_settings(s: &Settings) -> (u32, u32, EdgeMode, UpperTail) {
    (
        s.lambda_ml.to_bits(),
        s.lambda_map.to_bits(),
        s.edge_mode,
        s.upper_tail,
    )
}
