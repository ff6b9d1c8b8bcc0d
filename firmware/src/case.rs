//! The shapes of the checked cases (values in `expected.rs`).

use mlmap::InferError;

/// What one head must answer for a detection.
pub struct Expect<const K: usize> {
    /// The scores, computed in float64 on the host.
    pub scores: [f64; K],
    /// No class has any evidence: every score must be exactly `OS / K` in `f32`.
    pub uniform: bool,
    /// The predicted class, unless the two best scores are too close to call.
    pub argmax: Option<usize>,
}

/// What the open head (DESIGN §1.8) must answer for a detection.
pub struct OpenExpect<const K: usize> {
    /// The scores `OS * q * softmax(z / T)`, computed in float64 on the host.
    pub scores: [f64; K],
    /// The decided class (DESIGN §1.7): the detector's, the largest logit, the lower
    /// index among equal ones.
    pub decision: usize,
}

/// A valid detection.
pub struct Case<const K: usize> {
    /// What the case exercises.
    pub label: &'static str,
    /// Class logits.
    pub logits: [f32; K],
    /// Objectness.
    pub objectness: f32,
    /// The ML head's answer.
    pub ml: Expect<K>,
    /// The MAP head's answer.
    pub map: Expect<K>,
    /// The Bayes head's answer (`uniform` is never set: outside every axis the answer is
    /// `OS * pi[c]`, checked within the tolerance like any other).
    pub bayes: Expect<K>,
    /// The open head's answer.
    pub open: OpenExpect<K>,
}

/// An input the layer must reject.
pub struct ErrorCase<const K: usize> {
    /// What the case exercises.
    pub label: &'static str,
    /// Class logits.
    pub logits: [f32; K],
    /// Objectness.
    pub objectness: f32,
    /// The error every head must return.
    pub error: InferError,
}

/// A detection as int8 codes of the quantized section, with its dequantized logits
/// (`case.logits`, computed in float32 on the host) and their expected scores.
pub struct QCase<const K: usize> {
    /// The codes.
    pub codes: [i8; K],
    /// The dequantized logits and what each head must answer for them.
    pub case: Case<K>,
}

/// A detection scored by the small table with a recalibration map on every head
/// (DESIGN §1.9).
pub struct MapCase<const K: usize> {
    /// What the case exercises.
    pub label: &'static str,
    /// Class logits.
    pub logits: [f32; K],
    /// Objectness.
    pub objectness: f32,
    /// The scores of the ML, MAP, Bayes and open heads after their maps, computed in
    /// float64 by the numpy reference (zeros for an error case).
    pub scores: [[f64; K]; 4],
    /// The error every head must return instead.
    pub error: Option<InferError>,
}

/// What one window of the drift monitor's replay (DESIGN §7) must report, from the numpy
/// reference (`tools/monitor_ref.py`).
pub struct WindowCase<const K: usize> {
    /// Index of the window, from 0.
    pub window: u32,
    /// Detections in the window (fewer than W for the last, partial one).
    pub rows: u32,
    /// The PSI of each logit.
    pub psi: [f64; K],
    /// Their maximum.
    pub psi_max: f64,
    /// The logit of the maximum, unless two PSI are too close to call.
    pub psi_logit: Option<u16>,
    /// Share of the detections with a logit out of support.
    pub oos_rate: f64,
    /// Mean known-probability of the open head.
    pub q_mean: f64,
    /// The alarms of psi_max, oos_rate and q_mean.
    pub alarms: (bool, bool, bool),
}

/// A detection and its conformal class set (DESIGN §8) from the numpy reference
/// (`tools/conformal_ref.py`).
pub struct SetCase<const K: usize> {
    /// What the case is.
    pub label: &'static str,
    /// Class logits.
    pub logits: [f32; K],
    /// Objectness.
    pub objectness: f32,
    /// The set: class `c` in bit `c`.
    pub mask: u64,
    /// Whether the set is compared: no score lies within 1e-5 of its threshold.
    pub compared: bool,
}
