//! The bytes of the statistics, edges and counts: `magic | version | postcard body |
//! CRC-32`, each body a plain `...Wire` structure of numbers, strings and vectors.

use serde::{Deserialize, Serialize};

use super::{CRC, MAGIC_COUNTS, MAGIC_EDGES, MAGIC_STATS, STATS_FORMAT_VERSION};
use crate::fit::bayes::BayesParams;
use crate::fit::stats::MomentParts;
use crate::fit::{FitError, FitParams};
use mlmap_core::{EdgeMode, UpperTail};

/// Checks the class names of serialized `what` (statistics, edges or counts) against
/// the rule of DESIGN §6.15, as the data readers do.
pub(super) fn check_names(classes: &[String], what: &str) -> Result<(), FitError> {
    crate::dataset::check_class_names(classes, |i, kind| {
        let class = match classes.get(i) {
            Some(name) => format!("class {i} ({name:?})"),
            None => "classes".to_string(),
        };
        format_error(format!("{what} with an invalid {class}: {kind}"))
    })
    .map(|_| ())
}

pub(super) fn format_error(reason: String) -> FitError {
    FitError::Format { reason }
}

/// `magic | version | postcard body | CRC-32`.
pub(super) fn encode<T: Serialize>(magic: &[u8; 8], body: &T) -> Vec<u8> {
    let mut out = Vec::from(&magic[..]);
    out.extend_from_slice(&STATS_FORMAT_VERSION.to_le_bytes());
    // Serializing plain structs of numbers, strings and vectors into a Vec cannot fail.
    out.extend(postcard::to_allocvec(body).unwrap_or_default());
    let crc = CRC.checksum(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// The kind of file a magic names, for messages.
pub(super) fn kind(magic: &[u8]) -> Option<&'static str> {
    match magic {
        m if m == MAGIC_STATS => Some("pass-(a) statistics"),
        m if m == MAGIC_EDGES => Some("fit edges"),
        m if m == MAGIC_COUNTS => Some("pass-(b) counts"),
        _ => None,
    }
}

pub(super) fn decode<T: for<'de> Deserialize<'de>>(
    magic: &[u8; 8],
    bytes: &[u8],
) -> Result<T, FitError> {
    let want = kind(magic).unwrap_or("fit statistics");
    let e = |s: String| format_error(s);
    let head = bytes.get(..8);
    if head != Some(&magic[..]) {
        return Err(e(match head.and_then(kind) {
            Some(found) => format!("these are {found}, not {want}"),
            None if bytes.len() < 8 => format!(
                "{} bytes are too short to hold {want} (truncated?)",
                bytes.len()
            ),
            None => format!("not {want} of mlmap (unknown magic bytes)"),
        }));
    }
    let version = match bytes.get(8..10) {
        Some(&[a, b]) => u16::from_le_bytes([a, b]),
        _ => return Err(e("truncated after the magic bytes".to_string())),
    };
    if version != STATS_FORMAT_VERSION {
        return Err(e(if version > STATS_FORMAT_VERSION {
            format!(
                "format version {version} is newer than this build of mlmap reads \
                 ({STATS_FORMAT_VERSION}); use a newer mlmap"
            )
        } else {
            format!("unknown format version {version}")
        }));
    }
    let Some(split) = bytes.len().checked_sub(4).filter(|&n| n >= 10) else {
        return Err(e("truncated: no checksum".to_string()));
    };
    let (data, stored) = bytes.split_at(split);
    let stored = <[u8; 4]>::try_from(stored).ok().map(u32::from_le_bytes);
    if stored != Some(CRC.checksum(data)) {
        return Err(e(
            "checksum mismatch: the bytes are corrupt or truncated".to_string()
        ));
    }
    let body = data.get(10..).unwrap_or(&[]);
    match postcard::take_from_bytes::<T>(body) {
        Ok((value, [])) => Ok(value),
        Ok((_, rest)) => Err(e(format!("{} unexpected bytes after the body", rest.len()))),
        Err(err) => Err(e(format!("the body cannot be decoded: {err}"))),
    }
}

/// [`FitParams`] on the wire (the layer's enums as codes).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct ParamsWire {
    pub(super) bins_ml: u64,
    pub(super) lambda_ml: f32,
    pub(super) bins_map: u64,
    pub(super) lambda_map: f32,
    pub(super) edges: u8,
    pub(super) upper_tail: u8,
    pub(super) bayes: Option<(u64, f32)>,
}

impl From<&FitParams> for ParamsWire {
    fn from(p: &FitParams) -> Self {
        Self {
            bins_ml: p.bins_ml as u64,
            lambda_ml: p.lambda_ml,
            bins_map: p.bins_map as u64,
            lambda_map: p.lambda_map,
            edges: p.edges.code(),
            upper_tail: p.upper_tail.code(),
            bayes: p.bayes.map(|b| (b.bins as u64, b.lambda)),
        }
    }
}

impl ParamsWire {
    pub(super) fn into_params(self) -> Result<FitParams, FitError> {
        let bad = || format_error("invalid fit settings".to_string());
        let bins = |b: u64| usize::try_from(b).map_err(|_| bad());
        let params = FitParams {
            bins_ml: bins(self.bins_ml)?,
            lambda_ml: self.lambda_ml,
            bins_map: bins(self.bins_map)?,
            lambda_map: self.lambda_map,
            edges: EdgeMode::from_code(self.edges).ok_or_else(bad)?,
            upper_tail: UpperTail::from_code(self.upper_tail).ok_or_else(bad)?,
            bayes: match self.bayes {
                Some((b, lambda)) => Some(BayesParams {
                    bins: bins(b)?,
                    lambda,
                    objectness: false,
                }),
                None => None,
            },
        };
        params.validate().map_err(|_| bad())?;
        Ok(params)
    }
}

#[derive(Debug, Serialize, Deserialize)]
pub(super) struct StatsWire {
    pub(super) classes: Vec<String>,
    pub(super) params: Option<ParamsWire>,
    pub(super) rows: u64,
    pub(super) moments: Vec<MomentParts>,
    pub(super) bayes_min: Vec<f64>,
    pub(super) bayes_max: Vec<f64>,
    pub(super) bayes_rows: Vec<u64>,
}

#[derive(Debug, Serialize, Deserialize)]
pub(super) struct EdgesWire {
    pub(super) params: ParamsWire,
    pub(super) classes: Vec<String>,
    pub(super) ml: Vec<(f32, f32)>,
    pub(super) map: Vec<(f32, f32)>,
    pub(super) bayes: Option<(u64, Vec<(f32, f32)>)>,
}

#[derive(Debug, Serialize, Deserialize)]
pub(super) struct CountsWire {
    pub(super) edges: EdgesWire,
    pub(super) rows: u64,
    pub(super) ml: Vec<Vec<u64>>,
    pub(super) map: Vec<Vec<u64>>,
    pub(super) bayes: Option<Vec<u64>>,
}
