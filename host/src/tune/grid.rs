//! The grids a search walks: bin-count sets and log-spaced lambdas, bounded by
//! [`MAX_CANDIDATES`].

/// The most candidates (bin count and lambda pairs, over every head) one search
/// builds: about eight times the default grid (DESIGN §4). A larger grid is refused
/// before anything is read ([`TuneParams::check_size`](super::TuneParams::check_size)).
pub const MAX_CANDIDATES: usize = 20_000;

/// Parses a bin-count set: `N`, `A..B` (inclusive) or `A,B,C`; every count >= 1.
///
/// # Errors
///
/// A message naming what is wrong.
pub fn parse_bins(spec: &str) -> Result<Vec<usize>, String> {
    let num = |s: &str| -> Result<usize, String> {
        let n: usize = s
            .trim()
            .parse()
            .map_err(|_| format!("`{s}` is not a bin count"))?;
        if n == 0 || n > usize::from(u16::MAX) {
            return Err(format!("bin count {n} is not in 1..=65535"));
        }
        Ok(n)
    };
    let mut out: Vec<usize> = if let Some((a, b)) = spec.split_once("..") {
        let (a, b) = (num(a)?, num(b.trim_start_matches('='))?);
        if a > b {
            return Err(format!("empty range `{spec}`"));
        }
        (a..=b).collect()
    } else {
        spec.split(',').map(num).collect::<Result<_, _>>()?
    };
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// A log-spaced grid from `min` to `max` inclusive with `per_decade` points per decade,
/// rounded to `f32` (the precision the table stores), for the ML and MAP heads.
///
/// # Errors
///
/// When the bounds are not `0 < min <= max <= MAX_LAMBDA` or `per_decade` is 0.
pub fn lambda_grid(min: f64, max: f64, per_decade: usize) -> Result<Vec<f32>, String> {
    log_grid(min, max, per_decade, mlmap_core::MAX_LAMBDA)
}

/// [`lambda_grid`] for the Bayes head, whose lambda is at most
/// [`MAX_LAMBDA_BAYES`](mlmap_core::MAX_LAMBDA_BAYES) (1).
///
/// # Errors
///
/// When the bounds are not `0 < min <= max <= 1` or `per_decade` is 0.
pub fn bayes_lambda_grid(min: f64, max: f64, per_decade: usize) -> Result<Vec<f32>, String> {
    log_grid(min, max, per_decade, mlmap_core::MAX_LAMBDA_BAYES)
}

fn log_grid(min: f64, max: f64, per_decade: usize, limit: f32) -> Result<Vec<f32>, String> {
    if !(min > 0.0 && min <= max && max <= f64::from(limit)) || per_decade == 0 {
        return Err(format!(
            "lambda grid needs 0 < min <= max <= {limit} and at least one point per decade"
        ));
    }
    let decades = (max / min).log10();
    let steps = (decades * per_decade as f64).round();
    if steps >= MAX_CANDIDATES as f64 {
        return Err(format!(
            "the lambda grid would hold {} lambdas ({decades:.3} decades at {per_decade} per \
             decade); a search holds at most {MAX_CANDIDATES} candidates: give fewer lambdas \
             per decade",
            steps + 1.0
        ));
    }
    let steps = steps as usize;
    let mut out: Vec<f32> = (0..=steps)
        .map(|s| {
            let t = if steps == 0 {
                0.0
            } else {
                s as f64 / steps as f64
            };
            (min * (max / min).powf(t)) as f32
        })
        .filter(|&l| l > 0.0)
        .collect();
    out.dedup();
    Ok(out)
}
