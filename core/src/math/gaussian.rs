//! The prior: a Gaussian over one class's training logits (DESIGN §1.1, §1.2; paper
//! §III-B).
//!
//! The pdf is evaluated in `f32` as `norm * exp(d * d * neg_half_inv_var)` with
//! `d = x - mean`, `norm = 1 / sqrt(2 pi var)` and `neg_half_inv_var = -1 / (2 var)`,
//! both precomputed when the table is built. The value may exceed 1 (it is a density).

use crate::math::{self, Backend};

/// Smallest variance a host fit writes: a constant class (zero sample variance) is
/// floored to this. Logits are `f32`, whose 24-bit mantissa cannot resolve a spread
/// below `1e-6` around values of order 1; a standard deviation of `1e-6` is the
/// narrowest prior the data can justify, and keeps `norm` near `4e5`.
pub const VARIANCE_FLOOR: f64 = 1e-12;

/// A prior that does not satisfy the table invariants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GaussianError {
    /// The mean is not finite.
    Mean,
    /// The variance is not finite and positive, or `1 / (2 var)` overflows.
    Variance,
}

impl GaussianError {
    /// The one sentence describing the error, shared by `Display` and `defmt`.
    pub const fn message(self) -> &'static str {
        match self {
            Self::Mean => "prior mean is not finite",
            Self::Variance => "prior variance is not finite and positive (or 1/(2 var) overflows)",
        }
    }
}

impl core::fmt::Display for GaussianError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.message())
    }
}

impl core::error::Error for GaussianError {}

/// A validated univariate Gaussian prior `N(x | mean, var)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gaussian {
    pub(crate) mean: f32,
    pub(crate) var: f32,
    pub(crate) neg_half_inv_var: f32,
    pub(crate) norm: f32,
}

impl Gaussian {
    /// All zeros (invalid), for storage that is filled before use.
    pub(crate) const ZERO: Self = Self {
        mean: 0.0,
        var: 0.0,
        neg_half_inv_var: 0.0,
        norm: 0.0,
    };

    /// Validates and builds a prior.
    ///
    /// # Errors
    ///
    /// [`GaussianError::Mean`] for a non-finite mean; [`GaussianError::Variance`] for a
    /// variance that is not finite and positive or whose derived constants overflow.
    ///
    /// # Panics
    ///
    /// Never.
    pub fn new(mean: f32, var: f32) -> Result<Self, GaussianError> {
        if !mean.is_finite() {
            return Err(GaussianError::Mean);
        }
        if !(var.is_finite() && var > 0.0) {
            return Err(GaussianError::Variance);
        }
        let neg_half_inv_var = -0.5 / var;
        let norm = 1.0 / math::sqrt(2.0 * core::f32::consts::PI * var);
        if !(neg_half_inv_var.is_finite() && norm.is_finite() && norm > 0.0) {
            return Err(GaussianError::Variance);
        }
        Ok(Self {
            mean,
            var,
            neg_half_inv_var,
            norm,
        })
    }

    /// The mean `mu`.
    #[inline]
    pub fn mean(&self) -> f32 {
        self.mean
    }

    /// The variance `sigma^2` (sample variance of the training logits).
    #[inline]
    pub fn variance(&self) -> f32 {
        self.var
    }

    /// The pdf at `x` with the `exp` of backend `M`; 0 for `±inf` (and NaN).
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn pdf<M: Backend>(&self, x: f32) -> f32 {
        if !x.is_finite() {
            return 0.0;
        }
        let d = x - self.mean;
        // d * d may overflow to +inf; the exponent is then -inf and exp gives 0.
        self.norm * M::exp(d * d * self.neg_half_inv_var)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;

    #[test]
    fn standard_normal_values() {
        // 1/sqrt(2 pi) = 0.3989422804014327, exp(-1/2)/sqrt(2 pi) = 0.24197072451914337.
        let g = Gaussian::new(0.0, 1.0).unwrap();
        let cases: &[(f32, f64)] = &[
            (0.0, 0.398_942_280_401_432_7),
            (1.0, 0.241_970_724_519_143_37),
            (-1.0, 0.241_970_724_519_143_37),
        ];
        for &(x, want) in cases {
            let got = g.pdf::<Libm>(x);
            assert!(
                ((got as f64 - want) / want).abs() < 1e-6,
                "pdf({x}) = {got}, want {want}"
            );
        }
        assert_eq!(g.pdf::<Libm>(f32::INFINITY), 0.0);
        assert_eq!(g.pdf::<Libm>(f32::NEG_INFINITY), 0.0);
        assert_eq!(g.pdf::<Libm>(3e38), 0.0);
    }

    #[test]
    fn rejects_invalid_parameters() {
        assert_eq!(Gaussian::new(f32::NAN, 1.0), Err(GaussianError::Mean));
        assert_eq!(Gaussian::new(0.0, 0.0), Err(GaussianError::Variance));
        assert_eq!(Gaussian::new(0.0, -1.0), Err(GaussianError::Variance));
        assert_eq!(
            Gaussian::new(0.0, f32::INFINITY),
            Err(GaussianError::Variance)
        );
        assert_eq!(Gaussian::new(0.0, 1e-40), Err(GaussianError::Variance));
        assert!(Gaussian::new(0.0, VARIANCE_FLOOR as f32).is_ok());
    }
}
