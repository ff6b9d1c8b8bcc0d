//! One table, whatever holds it: [`TableView`] borrows a table's storage and is the
//! single implementation of everything a table does (describe a class, encode, check
//! the canonical encoding, score with each head); [`Slots`] borrows it mutably and is
//! the single decoder and validator. The one table type,
//! [`TableInner`](crate::TableInner), whatever its storage (arrays, bounded arrays,
//! vectors, lent slices), only owns the storage and lends it here.

use crate::diagnostics::error::{DecodeError, EncodeError, Head, InferError, TableError};
use crate::format::name::{check_class_name, ClassName, NAME_RULE_VERSION};
use crate::format::wire::{self, BayesSlots, ClassFields, ClassSpec, Header, Settings};
use crate::heads::bayes::{self, BayesView};
use crate::heads::layer;
use crate::heads::open::{self, OpenParams};
use crate::heads::recal::{self, Knot, Maps, RecalMap, HEADS, MAX_KNOTS};
use crate::math::gaussian::Gaussian;
use crate::math::histogram::{Axis, Histogram};
use crate::math::Backend;

/// A validated table borrowed from its storage: `F` and `G` hold the ML and MAP
/// frequencies of one class (`[f32; B]` or `Vec<f32>`).
#[derive(Debug, Clone, Copy)]
pub struct TableView<'a, F, G> {
    pub(crate) names: &'a [ClassName],
    pub(crate) rows: &'a [u64],
    pub(crate) priors: &'a [Gaussian],
    pub(crate) ml: &'a [Histogram<F>],
    pub(crate) map: &'a [Histogram<G>],
    pub(crate) bayes: Option<BayesView<'a>>,
    pub(crate) settings: &'a Settings,
    /// The heads' recalibration maps (DESIGN §1.9).
    pub(crate) maps: Maps<'a>,
}

impl<'a, F: AsRef<[f32]>, G: AsRef<[f32]>> TableView<'a, F, G> {
    /// Number of classes K.
    #[inline]
    pub fn k(&self) -> usize {
        self.names.len()
    }

    /// Bins of the ML head.
    #[inline]
    pub fn bins_ml(&self) -> usize {
        self.ml.first().map_or(0, Histogram::bins)
    }

    /// Bins of the MAP head.
    #[inline]
    pub fn bins_map(&self) -> usize {
        self.map.first().map_or(0, Histogram::bins)
    }

    /// Hyper-parameters and policies of the ML and MAP heads.
    #[inline]
    pub fn settings(&self) -> &'a Settings {
        self.settings
    }

    /// The Bayes head, if the table has one.
    #[inline]
    pub fn bayes(&self) -> Option<BayesView<'a>> {
        self.bayes
    }

    /// Whether the table has `head` (ML and MAP always; Bayes with a Bayes head; open
    /// with the open head's parameters).
    #[inline]
    pub fn has_head(&self, head: Head) -> bool {
        match head {
            Head::Ml | Head::Map => true,
            Head::Bayes => self.bayes.is_some(),
            Head::Open => self.open().is_some(),
        }
    }

    /// The recalibration map of `head` (DESIGN §1.9), if the table holds one; every
    /// scoring call of this view applies it.
    #[inline]
    pub fn recal_map(&self, head: Head) -> Option<RecalMap<'a>> {
        self.maps.get(head)
    }

    /// The same table without its recalibration maps: the heads' own scores, which
    /// `tune` fits maps to.
    #[inline]
    #[must_use]
    pub fn without_maps(mut self) -> Self {
        self.maps = Maps::NONE;
        self
    }

    /// Applies `head`'s map, if any, to one detection's scores.
    #[inline(always)]
    fn recalibrate(&self, head: Head, out: &mut [f32]) {
        if let Some(g) = self.maps.get(head) {
            g.apply(out);
        }
    }

    /// Name of class `i`.
    #[inline]
    pub fn class_name(&self, i: usize) -> Option<&'a str> {
        self.names.get(i).map(ClassName::as_str)
    }

    /// Index of the class called `name`.
    pub fn class_index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n.as_str() == name)
    }

    /// The statistics of class `i` (ML and MAP heads), as slices.
    pub fn spec(&self, i: usize) -> Option<ClassSpec<'a, &'a [f32], &'a [f32]>> {
        let (ml, map, prior) = (self.ml.get(i)?, self.map.get(i)?, self.priors.get(i)?);
        Some(ClassSpec {
            name: self.names.get(i)?.as_str(),
            rows: *self.rows.get(i)?,
            mean: prior.mean,
            variance: prior.var,
            ml_range: (ml.lo, ml.hi),
            ml_freqs: ml.freqs.as_ref(),
            map_range: (map.lo, map.hi),
            map_freqs: map.freqs.as_ref(),
        })
    }

    /// Encodes the table into `buf` and returns the written prefix (docs/FORMAT.md).
    ///
    /// # Errors
    ///
    /// [`EncodeError::BufferTooSmall`] when `buf` is too small.
    pub fn encode<'b>(&self, buf: &'b mut [u8]) -> Result<&'b mut [u8], EncodeError> {
        wire::encode(self, buf)
    }

    /// Number of bytes [`TableView::encode`] writes.
    pub fn encoded_len(&self) -> usize {
        wire::encoded_len(self).unwrap_or(usize::MAX)
    }

    /// ML scores of one detection into `out` (K entries); `scratch` is any K floats.
    ///
    /// # Errors
    ///
    /// As [`Table::ml`](crate::Table::ml), plus [`InferError::Length`] when a slice
    /// does not have K entries.
    #[inline(always)]
    pub fn ml_into(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if scratch.len() != self.k() {
            return Err(InferError::Length);
        }
        layer::ml_into(
            self.ml,
            self.settings.lambda_ml,
            self.settings.upper_tail,
            logits,
            objectness,
            out,
            scratch,
        )?;
        self.recalibrate(Head::Ml, out);
        Ok(())
    }

    /// MAP scores of one detection with backend `M` into `out` (K entries).
    ///
    /// # Errors
    ///
    /// As [`TableView::ml_into`].
    #[inline(always)]
    pub fn map_into<M: Backend>(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if scratch.len() != self.k() {
            return Err(InferError::Length);
        }
        layer::map_into::<_, M>(
            self.map,
            self.priors,
            self.settings.lambda_map,
            self.settings.upper_tail,
            logits,
            objectness,
            out,
            scratch,
        )?;
        self.recalibrate(Head::Map, out);
        Ok(())
    }

    /// Bayes scores of one detection with backend `M` into `out` (K entries);
    /// `scratch` holds one float per Bayes category (K or K + 1).
    ///
    /// # Errors
    ///
    /// [`InferError::NoBayesHead`] for a table without that head; otherwise as
    /// [`TableView::ml_into`].
    #[inline(always)]
    pub fn bayes_into<M: Backend>(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        let bayes = self.bayes.as_ref().ok_or(InferError::NoBayesHead)?;
        layer::check(logits, objectness, self.k(), out.len())?;
        bayes.score_into::<M>(logits, objectness, out, scratch)?;
        self.recalibrate(Head::Bayes, out);
        Ok(())
    }

    /// The open head's parameters (DESIGN §1.8), when the table has that head.
    #[inline]
    pub fn open(&self) -> Option<OpenParams> {
        self.bayes.and_then(|b| b.open)
    }

    /// Open-head scores of one detection with backend `M` into `out` (K entries);
    /// `scratch` holds one float per Bayes category (K or K + 1).
    ///
    /// # Errors
    ///
    /// [`InferError::NoOpenHead`] for a table without that head; otherwise as
    /// [`TableView::ml_into`].
    #[inline(always)]
    pub fn open_into<M: Backend>(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        let bayes = self.bayes.as_ref().ok_or(InferError::NoOpenHead)?;
        let params = bayes.open.as_ref().ok_or(InferError::NoOpenHead)?;
        layer::check(logits, objectness, self.k(), out.len())?;
        open::score_into::<M>(bayes, params, logits, objectness, out, scratch)?;
        self.recalibrate(Head::Open, out);
        Ok(())
    }
}

pub(crate) use crate::heads::{bayes::BayesBackend, layer::MapBackend, open::OpenBackend};

impl<F: AsRef<[f32]>, G: AsRef<[f32]>> TableView<'_, F, G> {
    /// Scores one detection with `head` and the backend a fixed-size
    /// [`Table`](crate::Table) uses for it by default (`Table::ml`, `Table::map`,
    /// `Table::bayes`), so that host tools reproduce the device's bits. `scratch` holds
    /// at least K floats, and at least one per category for the Bayes head.
    ///
    /// # Errors
    ///
    /// As [`TableView::ml_into`], [`TableView::map_into`] or [`TableView::bayes_into`].
    #[inline]
    pub fn score_into(
        &self,
        head: Head,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        let need = match head {
            Head::Ml | Head::Map => self.k(),
            Head::Bayes | Head::Open => self.bayes.map_or(0, |b| b.categories()),
        };
        let scratch = scratch.get_mut(..need).ok_or(InferError::Length)?;
        match head {
            Head::Ml => self.ml_into(logits, objectness, out, scratch),
            Head::Map => self.map_into::<MapBackend>(logits, objectness, out, scratch),
            Head::Bayes => self.bayes_into::<BayesBackend>(logits, objectness, out, scratch),
            Head::Open => self.open_into::<OpenBackend>(logits, objectness, out, scratch),
        }
    }
}

/// A table's storage, borrowed mutably for decoding: the one decoder behind every
/// table's (`TableInner::decode_with`). Sized from the header before parsing, so a
/// sequence longer than announced is malformed.
pub(crate) struct Slots<'t, 'a, F, G> {
    pub(crate) names: &'t mut [ClassName],
    /// The names as parsed, validated after the body is read.
    pub(crate) raw_names: &'t mut [&'a str],
    /// Frequencies each class had, ML and MAP.
    pub(crate) lens: &'t mut [(usize, usize)],
    pub(crate) rows: &'t mut [u64],
    pub(crate) priors: &'t mut [Gaussian],
    pub(crate) ml: &'t mut [Histogram<F>],
    pub(crate) map: &'t mut [Histogram<G>],
    pub(crate) settings: &'t mut Settings,
    pub(crate) bayes: Option<BayesStorage<'t>>,
    /// Room for each head's recalibration map (ML, MAP, Bayes, open): at most
    /// [`MAX_KNOTS`] knots each, empty for a table type without maps.
    pub(crate) recal: [&'t mut [Knot]; 4],
}

/// A Bayes head's storage, borrowed mutably.
pub(crate) struct BayesStorage<'t> {
    pub(crate) axes: &'t mut [Axis],
    pub(crate) terms: &'t mut [f32],
    pub(crate) rows: &'t mut [u64],
    pub(crate) log_prior: &'t mut [f32],
    pub(crate) lambda: &'t mut f32,
    pub(crate) log_lambda: &'t mut f32,
    /// The open head's parameters; `None` for a version-2 table.
    pub(crate) open: &'t mut Option<OpenParams>,
    /// Room for the objectness feature (DESIGN §1.6): its axis (0 or 1 entries) and its
    /// terms; `required` when the table type always has the feature.
    pub(crate) objectness_axis: &'t mut [Axis],
    pub(crate) objectness_terms: &'t mut [f32],
    pub(crate) objectness_required: bool,
    /// Set to whether the decoded table has the feature.
    pub(crate) has_objectness: &'t mut bool,
}

impl<'a, F: AsRef<[f32]> + AsMut<[f32]>, G: AsRef<[f32]> + AsMut<[f32]>> wire::BodySink<'a>
    for Slots<'_, 'a, F, G>
{
    fn capacity(&self) -> usize {
        self.names.len()
    }

    fn freqs(&mut self, class: usize, head: Head) -> &mut [f32] {
        match head {
            Head::Ml => self.ml.get_mut(class).map(|h| h.freqs.as_mut()),
            Head::Map => self.map.get_mut(class).map(|h| h.freqs.as_mut()),
            Head::Bayes | Head::Open => None,
        }
        .unwrap_or_default()
    }

    fn class(&mut self, class: usize, f: ClassFields<'a>) {
        if let (Some(name), Some(len), Some(rows), Some(prior), Some(ml), Some(map)) = (
            self.raw_names.get_mut(class),
            self.lens.get_mut(class),
            self.rows.get_mut(class),
            self.priors.get_mut(class),
            self.ml.get_mut(class),
            self.map.get_mut(class),
        ) {
            *name = f.name;
            *len = (f.ml_len, f.map_len);
            *rows = f.rows;
            (prior.mean, prior.var) = (f.mean, f.variance);
            (ml.lo, ml.hi) = f.ml_range;
            (map.lo, map.hi) = f.map_range;
        }
    }

    fn bayes(&mut self) -> BayesSlots<'_> {
        match &mut self.bayes {
            Some(b) => BayesSlots {
                rows: b.rows,
                axes: b.axes,
                terms: b.terms,
                objectness_axis: b.objectness_axis,
                objectness_terms: b.objectness_terms,
            },
            None => BayesSlots {
                rows: &mut [],
                axes: &mut [],
                terms: &mut [],
                objectness_axis: &mut [],
                objectness_terms: &mut [],
            },
        }
    }

    fn recal(&mut self, slot: usize) -> &mut [Knot] {
        match self.recal.get_mut(slot) {
            Some(k) => k,
            None => &mut [],
        }
    }
}

impl<'a, F: AsRef<[f32]> + AsMut<[f32]>, G: AsRef<[f32]> + AsMut<[f32]>> Slots<'_, 'a, F, G> {
    /// Parses `body` (announced by `header`) into the storage and validates every
    /// class, the Bayes head and the maps in place: nothing the size of a class is
    /// copied. Returns the number of knots of each head's map (0: none).
    pub(crate) fn decode(
        mut self,
        header: &Header,
        body: &'a [u8],
    ) -> Result<[usize; 4], DecodeError> {
        let has_bayes = header.bins_bayes > 0;
        if has_bayes != self.bayes.is_some() {
            return Err(DecodeError::Malformed);
        }
        let parsed = wire::parse_body_into(body, header.parts(), &mut self)?;
        let k = self.names.len();
        if parsed.classes != k || usize::from(header.k) != k {
            return Err(DecodeError::Malformed);
        }
        *self.settings = parsed.settings;
        let (bins_ml, bins_map) = (usize::from(header.bins_ml), usize::from(header.bins_map));
        for i in 0..k {
            let class = u16::try_from(i).unwrap_or(u16::MAX);
            let (ml_len, map_len) = self.lens.get(i).copied().unwrap_or_default();
            if ml_len != bins_ml {
                return Err(TableError::BinCount {
                    head: Head::Ml,
                    class,
                }
                .into());
            }
            if map_len != bins_map {
                return Err(TableError::BinCount {
                    head: Head::Map,
                    class,
                }
                .into());
            }
            self.validate_class(i, bins_ml, bins_map)?;
        }
        check_unique_names(self.names)?;
        if header.version >= NAME_RULE_VERSION {
            check_name_rule(self.names)?;
        }
        if let (Some(b), Some((lambda, lens))) = (self.bayes, parsed.bayes) {
            let bins = usize::from(header.bins_bayes);
            let expected = [b.rows.len(), b.axes.len(), b.terms.len()];
            if lens != expected {
                return Err(TableError::BayesShape.into());
            }
            *b.lambda = lambda;
            let cats = b.rows.len();
            let feature = match (parsed.objectness, b.objectness_axis.first_mut()) {
                (Some(n), Some(axis)) => {
                    if Some(n) != bins.checked_mul(cats) {
                        return Err(TableError::BayesShape.into());
                    }
                    let terms = b.objectness_terms.get(..n).ok_or(DecodeError::Malformed)?;
                    Some((axis, terms))
                }
                (None, _) if !b.objectness_required => None,
                (found, _) => {
                    return Err(DecodeError::ObjectnessMismatch {
                        found: found.is_some(),
                    })
                }
            };
            *b.has_objectness = feature.is_some();
            let features = k + usize::from(feature.is_some());
            *b.log_lambda = bayes::validate(
                k,
                bins,
                lambda,
                b.axes,
                b.terms,
                b.rows,
                b.log_prior,
                feature,
            )?;
            *b.open = match parsed.open {
                Some((t, e)) => Some(OpenParams::new(t, e, features, bins, lambda)?),
                None => None,
            };
        }
        let has_open = has_bayes && parsed.open.is_some();
        for ((&head, &n), knots) in HEADS.iter().zip(&parsed.maps).zip(&self.recal) {
            if n == 0 {
                continue;
            }
            let map_err = |error| TableError::Map { head, error };
            if n > MAX_KNOTS {
                return Err(map_err(crate::MapError::KnotCount).into());
            }
            if n > knots.len() {
                return Err(DecodeError::MapCapacity {
                    head,
                    capacity: u16::try_from(knots.len()).unwrap_or(u16::MAX),
                    found: u16::try_from(n).unwrap_or(u16::MAX),
                });
            }
            let present = match head {
                Head::Ml | Head::Map => true,
                Head::Bayes => has_bayes,
                Head::Open => has_open,
            };
            if !present {
                return Err(map_err(crate::MapError::NoHead).into());
            }
            recal::check(knots.get(..n).unwrap_or_default()).map_err(map_err)?;
        }
        Ok(parsed.maps)
    }

    /// Validates class `i` as parsed (raw fields, frequencies in place), with the checks
    /// of [`ClassSpec`]; fills in its name and the derived fields.
    fn validate_class(
        &mut self,
        i: usize,
        bins_ml: usize,
        bins_map: usize,
    ) -> Result<(), TableError> {
        let (Some(ml), Some(map), Some(prior), Some(&rows), Some(&name)) = (
            self.ml.get(i),
            self.map.get(i),
            self.priors.get(i),
            self.rows.get(i),
            self.raw_names.get(i),
        ) else {
            return Err(TableError::ClassCount);
        };
        let spec = ClassSpec {
            name,
            rows,
            mean: prior.mean,
            variance: prior.var,
            ml_range: (ml.lo, ml.hi),
            ml_freqs: ml.freqs.as_ref(),
            map_range: (map.lo, map.hi),
            map_freqs: map.freqs.as_ref(),
        };
        let c = spec.validate_decoded(i, bins_ml, bins_map)?;
        let (name, prior) = (c.name, c.prior);
        let ml_width = (c.ml.width, c.ml.inv_width);
        let map_width = (c.map.width, c.map.inv_width);
        if let (Some(n), Some(p), Some(ml), Some(map)) = (
            self.names.get_mut(i),
            self.priors.get_mut(i),
            self.ml.get_mut(i),
            self.map.get_mut(i),
        ) {
            *n = name;
            *p = prior;
            (ml.width, ml.inv_width) = ml_width;
            (map.width, map.inv_width) = map_width;
        }
        Ok(())
    }
}

/// Checks the whole name rule of DESIGN §6.15 ([`check_class_name`]) on every name of a
/// decoded table of format version [`NAME_RULE_VERSION`] or later; older versions only
/// hold names of 1 to `NAME_MAX` bytes other than `background`, checked as they are
/// stored.
pub(crate) fn check_name_rule(names: &[ClassName]) -> Result<(), TableError> {
    for (i, n) in names.iter().enumerate() {
        check_class_name(n.as_str()).map_err(|error| TableError::Name {
            class: u16::try_from(i).unwrap_or(u16::MAX),
            error,
        })?;
    }
    Ok(())
}

/// Checks that no name repeats an earlier one (O(K^2), decode time only).
pub(crate) fn check_unique_names(names: &[ClassName]) -> Result<(), TableError> {
    for (i, n) in names.iter().enumerate() {
        if names.iter().take(i).any(|m| m == n) {
            return Err(TableError::DuplicateName {
                class: u16::try_from(i).unwrap_or(u16::MAX),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::name::{CharKind, NameError};

    /// The decoder's name check of tables from format version `NAME_RULE_VERSION` on:
    /// the names an older table may store, refused with the rule they break.
    #[test]
    fn name_rule_of_new_tables() {
        let names = |list: &[&str]| -> std::vec::Vec<ClassName> {
            list.iter().map(|n| ClassName::stored(n).unwrap()).collect()
        };
        assert_eq!(check_name_rule(&names(&["car", "traffic light"])), Ok(()));
        let cases: &[(&[&str], u16, NameError)] = &[
            (
                &["car", "*/\n#include"],
                1,
                NameError::Char {
                    ch: '\n',
                    at: 2,
                    kind: CharKind::Control,
                },
            ),
            (
                &["\u{1b}[2J", "car"],
                0,
                NameError::Char {
                    ch: '\u{1b}',
                    at: 0,
                    kind: CharKind::Control,
                },
            ),
            (
                &["car", "bus", "rac\u{202E}"],
                2,
                NameError::Char {
                    ch: '\u{202E}',
                    at: 3,
                    kind: CharKind::Invisible,
                },
            ),
            (&["car", "bus "], 1, NameError::Padded),
        ];
        for &(list, class, error) in cases {
            assert_eq!(
                check_name_rule(&names(list)),
                Err(TableError::Name { class, error }),
                "{list:?}"
            );
        }
    }
}
