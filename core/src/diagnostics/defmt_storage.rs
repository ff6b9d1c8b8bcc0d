//! `defmt::Format` for the public modules' types (feature `defmt`): lent table storage
//! ([`crate::storage::lent`]) and the LiDAR maps ([`crate::lidar`]). Errors print their variant's
//! `message()` and then its values, as `Display` does.

use defmt::{write, Format, Formatter};

use crate::lidar::{Calibration, LidarError, Pixel, Projected, Projection, R0};
use crate::storage::inner::{Storage, TableInner};
use crate::storage::lent::{
    ArenaLayout, LentBayes, LentParts, LentStorage, QClass, QLogit, StorageShape,
};

impl Format for StorageShape {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "StorageShape {{ K: {}, bins: {}/{}, Bayes: {} bins x {} categories, knots: {=[?]}, objectness: {} }}",
            self.classes,
            self.bins_ml,
            self.bins_map,
            self.bins_bayes,
            self.categories,
            &self.knots[..],
            self.objectness
        )
    }
}

impl Format for ArenaLayout {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "ArenaLayout {{ size: {}, floats: {} }}",
            self.size, self.floats
        )
    }
}

/// Every table, whatever its storage: `Table { TableView {...} }`, `BoundedTable`,
/// `DynTable`, `LentTable` (an empty bounded table: no classes).
impl<S: Storage> Format for TableInner<S> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "{=str} {{ {} }}", S::NAME, self.in_use_view())
    }
}

impl<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
        const N: usize,
        const F: usize,
    > Format for crate::ArrayStorage<K, B_ML, B_MAP, B_BAYES, C, N, F>
{
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "ArrayStorage<{}, {}, {}, {}, {}, {}, {}>",
            K, B_ML, B_MAP, B_BAYES, C, N, F
        )
    }
}

impl<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
        const N: usize,
        const F: usize,
    > Format for crate::BoundedStorage<K, B_ML, B_MAP, B_BAYES, C, N, F>
{
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "BoundedStorage<{}, {}, {}, {}, {}, {}, {}>",
            K, B_ML, B_MAP, B_BAYES, C, N, F
        )
    }
}

impl Format for crate::BoundedExtent {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "BoundedExtent {{ K: {}, Bayes: {} bins x {} categories, objectness: {} }}",
            self.classes, self.bins_bayes, self.categories, self.objectness
        )
    }
}

#[cfg(feature = "alloc")]
impl Format for crate::VecStorage {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "VecStorage")
    }
}

impl Format for LentStorage<'_> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "LentStorage")
    }
}

impl Format for LentParts {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "LentParts {{ Bayes: {}, objectness: {} }}",
            self.bayes, self.objectness
        )
    }
}

impl Format for LentBayes<'_> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "LentBayes {{ logits: {}, categories: {}, terms: {} }}",
            self.axes.len(),
            self.rows.len(),
            self.terms.len()
        )
    }
}

impl Format for LidarError {
    fn format(&self, f: Formatter<'_>) {
        let m = self.message();
        match *self {
            Self::ImageSize { width, height } => write!(f, "{=str}: {} x {}", m, width, height),
            Self::ImageLen { expected, got }
            | Self::Scratch {
                needed: expected,
                got,
            } => write!(f, "{=str}: {} instead of {}", m, got, expected),
            Self::Mask { mask } => write!(f, "{=str}: {}", m, mask),
            Self::Point { index } => write!(f, "{=str}: point {}", m, index),
            Self::PixelCapacity { needed, got } => {
                write!(f, "{=str}: {} for {} pixels", m, got, needed)
            }
            Self::Pixel { index } => write!(f, "{=str}: entry {}", m, index),
        }
    }
}

impl Format for Calibration {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Calibration {{ P2: {}, R0_rect: {}, Tr_velo_to_cam: {} }}",
            self.p2, self.r0_rect, self.tr_velo_to_cam
        )
    }
}

impl Format for Projection {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "Projection {{ {} }}", self.matrix())
    }
}

impl Format for Pixel {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Pixel {{ col: {}, row: {}, range: {}, reflectance: {} }}",
            self.col, self.row, self.range, self.reflectance
        )
    }
}

impl Format for Projected {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Projected {{ kept: {}, pixels: {} }}",
            self.kept, self.pixels
        )
    }
}

impl Format for R0 {
    fn format(&self, f: Formatter<'_>) {
        match self {
            Self::GsMean => write!(f, "GsMean"),
            Self::Nearest => write!(f, "Nearest"),
        }
    }
}

impl Format for QClass<'_> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "QClass {{ scale: {}, zero point: {}, first ML code: {}, first MAP code: {} }}",
            self.scale, self.zero_point, self.ml_start, self.map_start
        )
    }
}

impl Format for QLogit<'_> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "QLogit {{ first code: {}, index bytes: {} }}",
            self.start,
            self.index.len()
        )
    }
}
