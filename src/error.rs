//! The crate's error type, returned by every validated constructor.

use core::fmt;

/// Why a value was rejected at construction.
///
/// Validation happens once, when a type is built (`Stokes::new`, `Frame::new`, …); after that the
/// math is infallible. Values are reported as `f64` whatever the scalar type.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// An input was NaN or infinite.
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// A scalar input lies outside its allowed range.
    OutOfRange {
        /// Which input.
        what: &'static str,
        /// The value received.
        value: f64,
        /// The allowed range, in words (e.g. `"[0, 1]"`).
        expected: &'static str,
    },
    /// A matrix that must be Hermitian (or symmetric) is not, within the stated tolerance.
    NotHermitian {
        /// Which matrix.
        what: &'static str,
        /// The largest `|A − A†|` entry found.
        asymmetry: f64,
    },
    /// A matrix that must be positive (semi-)definite is not.
    NotPositiveDefinite {
        /// Which matrix.
        what: &'static str,
        /// The smallest eigenvalue (or failing pivot) found.
        min_eigenvalue: f64,
    },
    /// A Stokes vector with `S0 < |(S1, S2, S3)|`: more polarized intensity than intensity.
    InvalidStokes {
        /// `S0`.
        s0: f64,
        /// `|(S1, S2, S3)|`.
        polarized: f64,
    },
    /// Basis vectors that are zero, parallel, not unit length, not orthogonal, or left-handed.
    InvalidBasis {
        /// What is wrong, in words.
        reason: &'static str,
    },
    /// A matrix that must be invertible is singular (or numerically so).
    Singular {
        /// Which matrix.
        what: &'static str,
    },
    /// A physically unrealizable combination of otherwise valid inputs.
    Unrealizable {
        /// What is violated, in words.
        reason: &'static str,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::NonFinite { what } => write!(f, "{what} must be finite (got NaN or infinity)"),
            Error::OutOfRange {
                what,
                value,
                expected,
            } => write!(f, "{what} = {value} is out of range: expected {expected}"),
            Error::NotHermitian { what, asymmetry } => write!(
                f,
                "{what} must be Hermitian: largest |A − A†| entry is {asymmetry:e}"
            ),
            Error::NotPositiveDefinite {
                what,
                min_eigenvalue,
            } => write!(
                f,
                "{what} must be positive (semi-)definite: smallest eigenvalue {min_eigenvalue:e}"
            ),
            Error::InvalidStokes { s0, polarized } => write!(
                f,
                "invalid Stokes vector: S0 = {s0} is less than |(S1, S2, S3)| = {polarized}"
            ),
            Error::InvalidBasis { reason } => write!(f, "invalid basis: {reason}"),
            Error::Singular { what } => write!(f, "{what} is singular"),
            Error::Unrealizable { reason } => write!(f, "not physically realizable: {reason}"),
        }
    }
}

impl std::error::Error for Error {}

/// Returns `Err(Error::NonFinite)` unless every value is finite.
pub(crate) fn ensure_finite<T: crate::real::Real>(
    what: &'static str,
    values: impl IntoIterator<Item = T>,
) -> Result<(), Error> {
    if values.into_iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Error::NonFinite { what })
    }
}
