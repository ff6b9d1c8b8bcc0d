//! `defmt::Format` for the public modules' types (feature `defmt`): lent table storage
//! ([`crate::storage::lent`]) and the LiDAR maps ([`crate::lidar`]). Errors print their variant's
//! `message()` and then its values, as `Display` does.

use defmt::{write, Format, Formatter};

use crate::lidar::{Calibration, LidarError, Pixel, Projected, Projection, R0};
use crate::storage::lent::{ArenaLayout, LentBayes, LentTable, QClass, QLogit, StorageShape};

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

impl Format for LentTable<'_, '_, '_> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "LentTable {{ K: {}, Bayes: {} }}",
            self.names.len(),
            self.bayes
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
