//! `defmt::Format` for the types of the sections after a table (feature `defmt`): the
//! drift monitor (DESIGN §7) and the conformal class sets (DESIGN §8). Errors print their
//! variant's `message()` and then its values, as `Display` does.

use defmt::{write, Format, Formatter};

use crate::{
    Accumulators, Alarms, ConformalError, ConformalSpec, Monitor, MonitorError, MonitorParams,
    MonitorSpec, MonitorState, Thresholds, WindowReport, WindowSummary,
};

impl Format for MonitorError {
    fn format(&self, f: Formatter<'_>) {
        let m = self.message();
        match *self {
            Self::UnsupportedVersion { found } => write!(f, "{=str} (found {})", m, found),
            Self::ShapeMismatch { expected, found } => write!(
                f,
                "{=str} (found {} logits of {} bins, expected {} of {})",
                m, found.0, found.1, expected.0, expected.1
            ),
            Self::Reference { logit } => write!(f, "{=str} (logit {})", m, logit),
            _ => write!(f, "{=str}", m),
        }
    }
}

impl Format for ConformalError {
    fn format(&self, f: Formatter<'_>) {
        let m = self.message();
        match *self {
            Self::UnsupportedVersion { found } => write!(f, "{=str} (found {})", m, found),
            Self::MissingHead { head } => write!(f, "{=str} ({} head)", m, head),
            Self::ShapeMismatch { expected, found } => {
                write!(f, "{=str} (found {}, expected {})", m, found, expected)
            }
            Self::Threshold { class } => write!(f, "{=str} (class {})", m, class),
            _ => write!(f, "{=str}", m),
        }
    }
}

impl Format for Thresholds {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Thresholds {{ psi: {}, oos: {}, q: {} }}",
            self.psi, self.oos, self.q
        )
    }
}

impl Format for MonitorParams {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "MonitorParams {{ window: {}, alpha: {}, thresholds: {} }}",
            self.window, self.alpha, self.thresholds
        )
    }
}

impl Format for Alarms {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Alarms {{ psi: {}, oos: {}, q: {} }}",
            self.psi, self.oos, self.q
        )
    }
}

impl Format for WindowSummary {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "WindowSummary {{ window: {}, rows: {}, psi_max: {} (logit {}), oos_rate: {}, \
             q_mean: {}, alarms: {} }}",
            self.window,
            self.rows,
            self.psi_max,
            self.psi_logit,
            self.oos_rate,
            self.q_mean,
            self.alarms
        )
    }
}

impl Format for Accumulators {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Accumulators {{ window: {}, rows: {}, outside: {}, q_sum: {} }}",
            self.window, self.rows, self.outside, self.q_sum
        )
    }
}

impl<const K: usize> Format for WindowReport<K> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "WindowReport {{ summary: {}, psi: {=[?]} }}",
            self.summary,
            &self.psi[..]
        )
    }
}

impl Format for MonitorSpec<'_> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "MonitorSpec {{ K: {}, bins: {}, categories: {}, params: {} }}",
            self.k(),
            self.bins(),
            self.categories(),
            self.params()
        )
    }
}

impl Format for MonitorState<'_> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "MonitorState {{ {} }}", self.accumulators())
    }
}

impl<const K: usize, const B: usize, const C: usize> Format for Monitor<'_, K, B, C> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Monitor<{}, {}, {}> {{ {} }}",
            K,
            B,
            C,
            self.accumulators()
        )
    }
}

impl Format for ConformalSpec<'_> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "ConformalSpec {{ head: {}, alpha: {}, K: {} }}",
            self.head(),
            self.alpha(),
            self.k()
        )
    }
}
