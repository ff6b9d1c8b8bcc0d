//! How much storage a table needs ([`StorageShape`]), read by a parse that stores
//! nothing.

use crate::diagnostics::error::{DecodeError, Head};
use crate::format::wire::{self, BayesSlots, BodySink, ClassFields};
use crate::heads::recal::{Knot, MAX_KNOTS};

/// How much storage a table needs: its shape as its header announces it, and the
/// lengths of the parts the header does not announce (the recalibration maps and the
/// objectness feature of a version-4 table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StorageShape {
    /// Classes K.
    pub classes: usize,
    /// Bins of the ML head.
    pub bins_ml: usize,
    /// Bins of the MAP head.
    pub bins_map: usize,
    /// Bins per logit of the Bayes head; 0 without one.
    pub bins_bayes: usize,
    /// Categories of the Bayes head (K or K + 1); 0 without one.
    pub categories: usize,
    /// Knots of each head's recalibration map (ML, MAP, Bayes, open), at most
    /// [`MAX_KNOTS`] each (a map with more is refused by the decoder, which counts the
    /// surplus without storing it); 0 for no map.
    pub knots: [usize; 4],
    /// Whether the Bayes head has the objectness feature (an axis and
    /// `bins_bayes * categories` terms).
    pub objectness: bool,
}

impl StorageShape {
    /// Reads the storage `bytes` needs, checking what the decoder checks before it
    /// stores anything: the magic, the CRC-32, the version; then `limit` (a caller's
    /// maximum shape, e.g. `|_| Ok(())` for none); then that the body is long enough for
    /// the announced frequencies and terms, and for a version-4 table that it parses
    /// (only counted, not stored). A table appended with sections (DESIGN §3) is read
    /// without them.
    ///
    /// # Errors
    ///
    /// The [`DecodeError`] the decoder gives for the same bytes at the same check, or
    /// `limit`'s.
    pub fn of(
        bytes: &[u8],
        limit: impl FnOnce(&Self) -> Result<(), DecodeError>,
    ) -> Result<Self, DecodeError> {
        let bytes = crate::sections::table_part(bytes);
        let (header, body) = wire::open(bytes)?;
        let mut shape = Self {
            classes: usize::from(header.k),
            bins_ml: usize::from(header.bins_ml),
            bins_map: usize::from(header.bins_map),
            bins_bayes: usize::from(header.bins_bayes),
            categories: usize::from(header.categories),
            knots: [0; 4],
            objectness: false,
        };
        limit(&shape)?;
        // Every frequency and term takes 4 bytes of the body: a header announcing more
        // than the body holds is malformed (as in every decoder, before any storage).
        if shape.floats().saturating_mul(4) > body.len() {
            return Err(DecodeError::Malformed);
        }
        if header.maps {
            let mut sink = Measure { k: shape.classes };
            let parsed = wire::parse_body_into(body, header.parts(), &mut sink)?;
            shape.knots = parsed.maps.map(|n| n.min(MAX_KNOTS));
            shape.objectness = parsed.objectness.is_some() && shape.bins_bayes > 0;
        }
        Ok(shape)
    }

    /// Frequencies and log-terms of the table: `K (ML bins + MAP bins)` plus the Bayes
    /// head's `categories K bins` (saturating).
    pub fn floats(&self) -> usize {
        let terms = self
            .categories
            .saturating_mul(self.classes)
            .saturating_mul(self.bins_bayes);
        self.classes
            .saturating_mul(self.bins_ml.saturating_add(self.bins_map))
            .saturating_add(terms)
    }
}

/// A sink that lends no storage and counts every sequence: the measuring parse of
/// [`StorageShape::of`].
struct Measure {
    k: usize,
}

impl<'a> BodySink<'a> for Measure {
    fn capacity(&self) -> usize {
        self.k
    }

    fn freqs(&mut self, _: usize, _: Head) -> &mut [f32] {
        &mut []
    }

    fn class(&mut self, _: usize, _: ClassFields<'a>) {}

    fn bayes(&mut self) -> BayesSlots<'_> {
        BayesSlots {
            rows: &mut [],
            axes: &mut [],
            terms: &mut [],
            objectness_axis: &mut [],
            objectness_terms: &mut [],
        }
    }

    fn recal(&mut self, _: usize) -> &mut [Knot] {
        &mut []
    }

    fn counts_only(&self) -> bool {
        true
    }
}
