//! Dispersion of transparent media: the Sellmeier and Cauchy equations, and two glasses.

use super::tables;
use crate::error::{Error, ensure_finite};
use crate::real::Real;

/// The helium d line, 587.5618 nm, in µm (where catalogues quote `n_d`).
pub const LINE_D_UM: f64 = 0.5875618;

/// The hydrogen F line, 486.1327 nm, in µm.
pub const LINE_F_UM: f64 = 0.4861327;

/// The hydrogen C line, 656.2725 nm, in µm.
pub const LINE_C_UM: f64 = 0.6562725;

/// The Abbe number `V_d = (n_d − 1)/(n_F − n_C)` of a dispersion `index(λ)` (λ in µm), at the
/// lines [`LINE_D_UM`], [`LINE_F_UM`], [`LINE_C_UM`].
///
/// # Examples
/// ```
/// use gmueller::spectral::{Glass, abbe_number};
/// let v = abbe_number(|l: f64| Glass::NBk7.index(l));
/// assert!((v - 64.17).abs() < 0.01); // Schott's catalogue value
/// ```
#[must_use]
pub fn abbe_number<T: Real>(index: impl Fn(T) -> T) -> T {
    let nd = index(T::lit(LINE_D_UM));
    (nd - T::one()) / (index(T::lit(LINE_F_UM)) - index(T::lit(LINE_C_UM)))
}

/// The Sellmeier dispersion formula with `N` terms:
///
/// ```text
/// n(λ) = √(1 + Σᵢ Bᵢ λ² / (λ² − Cᵢ))          λ in µm, Cᵢ in µm²
/// ```
///
/// (Schott's form; a resonance at wavelength `λᵢ` has `Cᵢ = λᵢ²`.) Accurate over the range its
/// coefficients were fitted on; [`index`](Self::index) evaluates the formula at any `λ` and is
/// infinite at a pole `λ² = Cᵢ` and NaN where the sum makes `n²` negative.
///
/// # Examples
/// ```
/// use gmueller::spectral::Sellmeier;
/// // Malitson's fused silica, built by hand.
/// let silica = Sellmeier::new(
///     [0.6961663, 0.4079426, 0.8974794],
///     [0.0684043_f64.powi(2), 0.1162414_f64.powi(2), 9.896161_f64.powi(2)],
/// )?;
/// assert!((silica.index(0.5875618) - 1.4585).abs() < 5e-5);
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sellmeier<T: Real, const N: usize> {
    b: [T; N],
    c: [T; N],
}

impl<T: Real, const N: usize> Sellmeier<T, N> {
    /// The formula with strengths `b` (`Bᵢ`, dimensionless) and `c` (`Cᵢ`, µm²).
    ///
    /// # Errors
    /// [`Error::NonFinite`] if a coefficient is NaN or infinite, [`Error::OutOfRange`] if a
    /// `Cᵢ` is negative.
    pub fn new(b: [T; N], c: [T; N]) -> Result<Self, Error> {
        ensure_finite("Sellmeier coefficient", b.iter().chain(c.iter()).copied())?;
        if let Some(&ci) = c.iter().find(|&&ci| ci < T::zero()) {
            return Err(Error::OutOfRange {
                what: "Sellmeier C (µm²)",
                value: ci.to_f64(),
                expected: "C ≥ 0",
            });
        }
        Ok(Self { b, c })
    }

    /// The strengths `Bᵢ`.
    #[must_use]
    pub fn b(&self) -> &[T; N] {
        &self.b
    }

    /// The `Cᵢ`, µm².
    #[must_use]
    pub fn c(&self) -> &[T; N] {
        &self.c
    }

    /// The refractive index at the vacuum wavelength `lambda_um` (µm).
    #[must_use]
    pub fn index(&self, lambda_um: T) -> T {
        let l2 = lambda_um * lambda_um;
        let mut n2 = T::one();
        for (&b, &c) in self.b.iter().zip(&self.c) {
            n2 += b * l2 / (l2 - c);
        }
        n2.sqrt()
    }
}

/// Cauchy's dispersion formula with `N` coefficients:
///
/// ```text
/// n(λ) = A₀ + A₁/λ² + A₂/λ⁴ + … + A_{N−1}/λ^{2(N−1)}          λ in µm, Aᵢ in µm^{2i}
/// ```
///
/// A fit for the visible range of transparent media; [`index`](Self::index) evaluates it at any
/// `λ`.
///
/// # Examples
/// ```
/// use gmueller::spectral::Cauchy;
/// // A BK7-like glass: A = 1.5046, B = 0.00420 µm².
/// let glass = Cauchy::new([1.5046, 0.00420])?;
/// assert!((glass.index(0.5875618_f64) - 1.5168).abs() < 2e-4);
/// # Ok::<(), gmueller::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cauchy<T: Real, const N: usize> {
    a: [T; N],
}

impl<T: Real, const N: usize> Cauchy<T, N> {
    /// The formula with coefficients `a` (`A₀, A₁, …`, `Aᵢ` in µm^{2i}).
    ///
    /// # Errors
    /// [`Error::NonFinite`] if a coefficient is NaN or infinite.
    pub fn new(a: [T; N]) -> Result<Self, Error> {
        ensure_finite("Cauchy coefficient", a.iter().copied())?;
        Ok(Self { a })
    }

    /// The coefficients `Aᵢ`.
    #[must_use]
    pub fn coefficients(&self) -> &[T; N] {
        &self.a
    }

    /// The refractive index at the vacuum wavelength `lambda_um` (µm) (Horner's rule in `1/λ²`).
    #[must_use]
    pub fn index(&self, lambda_um: T) -> T {
        let inv2 = T::one() / (lambda_um * lambda_um);
        self.a
            .iter()
            .rev()
            .fold(T::zero(), |acc, &a| acc * inv2 + a)
    }
}

/// A glass whose Sellmeier coefficients are published (see the [module docs](super)).
///
/// # Examples
/// ```
/// use gmueller::spectral::Glass;
/// let n = Glass::FusedSilica.index(0.5875618_f64);
/// assert!((n - 1.4585).abs() < 5e-5);
/// assert!(Glass::NBk7.try_index(0.2_f64).is_err()); // below Schott's tabulated range
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Glass {
    /// Schott N-BK7 (borosilicate crown), catalogue of 2018-06-01; `n_d = 1.5168`,
    /// `V_d = 64.17`. Range: 0.3126–2.3254 µm, where the catalogue tabulates its indices.
    NBk7,
    /// Fused silica (amorphous silicon dioxide), Malitson (1965) at 20 °C; `n_d = 1.4585`. Range:
    /// 0.21–3.71 µm, where Malitson measured.
    FusedSilica,
}

impl Glass {
    /// Every tabulated glass.
    pub const ALL: [Glass; 2] = [Glass::NBk7, Glass::FusedSilica];

    /// The name (`"N-BK7"`, `"fused silica"`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Glass::NBk7 => "N-BK7",
            Glass::FusedSilica => "fused silica",
        }
    }

    /// Where the coefficients come from.
    #[must_use]
    pub fn source(self) -> &'static str {
        match self {
            Glass::NBk7 => {
                "SCHOTT optical glass catalogue 2018-06-01 (opticalglass 1.1.1 SCHOTT.xls)"
            }
            Glass::FusedSilica => {
                "I. H. Malitson, Interspecimen comparison of the refractive index of fused \
                 silica, J. Opt. Soc. Am. 55, 1205 (1965)"
            }
        }
    }

    /// The wavelengths (µm) the coefficients were fitted over: outside them
    /// [`index`](Self::index) extrapolates and [`try_index`](Self::try_index) refuses.
    #[must_use]
    pub fn range_um(self) -> (f64, f64) {
        match self {
            Glass::NBk7 => tables::N_BK7_RANGE_UM,
            Glass::FusedSilica => (0.21, 3.71),
        }
    }

    /// The Sellmeier formula of the glass.
    #[must_use]
    pub fn sellmeier<T: Real>(self) -> Sellmeier<T, 3> {
        let (b, c) = match self {
            Glass::NBk7 => (tables::N_BK7_B, tables::N_BK7_C),
            Glass::FusedSilica => (tables::FUSED_SILICA_B, tables::FUSED_SILICA_C),
        };
        Sellmeier {
            b: b.map(T::lit),
            c: c.map(T::lit),
        }
    }

    /// The refractive index at the vacuum wavelength `lambda_um` (µm): the Sellmeier formula,
    /// evaluated at any `λ` (an extrapolation outside [`range_um`](Self::range_um)).
    #[must_use]
    pub fn index<T: Real>(self, lambda_um: T) -> T {
        self.sellmeier().index(lambda_um)
    }

    /// [`index`](Self::index), or an error outside the range of the fit.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a NaN or infinite wavelength, [`Error::OutOfRange`] for one
    /// outside [`range_um`](Self::range_um).
    pub fn try_index<T: Real>(self, lambda_um: T) -> Result<T, Error> {
        if !lambda_um.is_finite() {
            return Err(Error::NonFinite { what: "wavelength" });
        }
        let (lo, hi) = self.range_um();
        if lambda_um < T::lit(lo) || lambda_um > T::lit(hi) {
            return Err(Error::OutOfRange {
                what: "wavelength (µm) of a glass's Sellmeier fit",
                value: lambda_um.to_f64(),
                expected: "the glass's range_um()",
            });
        }
        Ok(self.index(lambda_um))
    }
}
