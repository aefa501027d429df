//! Monte Carlo estimates with their standard errors, and the assertion that an estimate agrees
//! with an expected value within a stated number of standard errors.
//!
//! A Monte Carlo test averages `n` independent samples; its estimate misses the true mean by a
//! standard error `s/√n` (`s` the samples' standard deviation) times a standard normal number.
//! Asserting `|mean − expected| ≤ z · SE` then fails by chance with probability
//! `erfc(z/√2)` (6.3e-5 at `z = 4`, 6.8e-6 at `z = 4.5`): with a fixed seed the test is
//! deterministic, and with fresh seeds it fails rarely — unless the expected value is wrong,
//! which makes `|mean − expected|/SE` grow as `√n`. Show that a wrong formula is caught by
//! computing its `z` too ([`Estimate::z`]).

/// A running mean and variance (Welford's algorithm), for one real quantity.
///
/// ```
/// use gmueller::verify::stats::Estimate;
/// let mut e = Estimate::default();
/// for x in [1.0, 2.0, 3.0, 4.0] {
///     e.push(x);
/// }
/// assert_eq!(e.mean(), 2.5);
/// // sample variance 5/3, SE = √(5/3/4)
/// assert!((e.standard_error() - (5.0_f64 / 12.0).sqrt()).abs() < 1e-15);
/// assert!((e.z(2.0) - 0.5 / (5.0_f64 / 12.0).sqrt()).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Estimate {
    n: u64,
    mean: f64,
    m2: f64,
}

impl Estimate {
    /// Adds a sample.
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    /// The number of samples.
    pub fn count(&self) -> u64 {
        self.n
    }

    /// The sample mean (0 before any sample).
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// The standard error of the mean, `√(s²/n)` with the unbiased sample variance `s²`
    /// (0 with fewer than two samples).
    pub fn standard_error(&self) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        (self.m2 / (self.n - 1) as f64 / self.n as f64).sqrt()
    }

    /// `(mean − expected)/SE`: how many standard errors the estimate is from `expected`
    /// (`±∞` when the samples have no spread and the mean differs, 0 when both are equal).
    pub fn z(&self, expected: f64) -> f64 {
        let d = self.mean - expected;
        if d == 0.0 {
            0.0
        } else {
            d / self.standard_error()
        }
    }
}

/// Asserts `|mean − expected| ≤ sigmas · SE + abs` and prints both sides and `z` otherwise.
/// `abs` absorbs rounding where the samples have (almost) no spread, e.g. an entry that is
/// zero in every sample.
///
/// # Panics
/// When the estimate is further from `expected` than allowed.
pub fn assert_within(what: &str, estimate: &Estimate, expected: f64, sigmas: f64, abs: f64) {
    let d = (estimate.mean() - expected).abs();
    let allowed = sigmas * estimate.standard_error() + abs;
    assert!(
        d <= allowed,
        "{what}: Monte Carlo {} ± {} (n = {}) vs expected {expected}: off by {d:e} = {:.2} SE \
         (allowed {sigmas} SE + {abs:e})",
        estimate.mean(),
        estimate.standard_error(),
        estimate.count(),
        estimate.z(expected).abs(),
    );
}
