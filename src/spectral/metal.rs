//! Measured complex indices `n + iκ` of metals, tabulated against wavelength.

use num_complex::Complex;

use super::lerp;
use super::tables;
use crate::error::Error;
use crate::numerics::is_nan;
use crate::real::Real;

/// A metal whose measured complex index of refraction `n + iκ` is tabulated (Mitsuba 3.9.1's
/// `data/ior` files, from the luxpop.com database; see the [module docs](super) for sources).
///
/// The index follows the crate's convention (`e^{−iωt}`, [`crate::fresnel`]): `κ ≥ 0` absorbs,
/// so the value goes into [`crate::fresnel::coefficients`] or a conductor material as it is.
/// Wavelengths are vacuum wavelengths in µm; divide the index by the surrounding medium's real
/// index for the relative index `η` of a metal under a dielectric.
///
/// # Examples
/// ```
/// use gmueller::spectral::Metal;
/// let gold = Metal::Au.index(0.65_f64);
/// assert!(gold.re < 0.25 && gold.im > 3.0); // n small, κ large: a good red mirror
/// let (lo, hi) = Metal::Au.range_um();
/// assert_eq!(Metal::Au.index(0.2_f64), Metal::Au.index(lo)); // held below the table
/// assert!(Metal::Au.try_index(0.2_f64).is_err());
/// assert!(Metal::Au.try_index(hi).is_ok());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Metal {
    /// Silver, 0.2988–0.8856 µm (56 rows).
    Ag,
    /// Aluminium, 0.2988–0.8856 µm (56 rows).
    Al,
    /// Gold, 0.2988–0.8856 µm (56 rows).
    Au,
    /// Chromium, 0.3002–0.8856 µm (28 rows; LLNL/CXRO + Palik; no rows between 0.611, 0.700
    /// and 0.816 µm).
    Cr,
    /// Copper, 0.3024–0.8856 µm (55 rows).
    Cu,
    /// Nickel, 0.3024–0.8856 µm (34 rows; Palik's handbook).
    Ni,
    /// Tungsten, 0.3024–0.8856 µm (54 rows; LLNL/CXRO + Palik).
    W,
}

impl Metal {
    /// Every tabulated metal.
    pub const ALL: [Metal; 7] = [
        Metal::Ag,
        Metal::Al,
        Metal::Au,
        Metal::Cr,
        Metal::Cu,
        Metal::Ni,
        Metal::W,
    ];

    /// The English name (`"gold"`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Metal::Ag => "silver",
            Metal::Al => "aluminium",
            Metal::Au => "gold",
            Metal::Cr => "chromium",
            Metal::Cu => "copper",
            Metal::Ni => "nickel",
            Metal::W => "tungsten",
        }
    }

    /// Where the table comes from (file and the attribution in its header).
    #[must_use]
    pub fn source(self) -> &'static str {
        match self {
            Metal::Ag => tables::AG_SOURCE,
            Metal::Al => tables::AL_SOURCE,
            Metal::Au => tables::AU_SOURCE,
            Metal::Cr => tables::CR_SOURCE,
            Metal::Cu => tables::CU_SOURCE,
            Metal::Ni => tables::NI_SOURCE,
            Metal::W => tables::W_SOURCE,
        }
    }

    /// The table: rows `[λ (µm), n, κ]`, `λ` strictly increasing.
    #[must_use]
    pub fn table(self) -> &'static [[f64; 3]] {
        match self {
            Metal::Ag => &tables::AG,
            Metal::Al => &tables::AL,
            Metal::Au => &tables::AU,
            Metal::Cr => &tables::CR,
            Metal::Cu => &tables::CU,
            Metal::Ni => &tables::NI,
            Metal::W => &tables::W,
        }
    }

    /// The first and last tabulated wavelengths, µm.
    #[must_use]
    pub fn range_um(self) -> (f64, f64) {
        let t = self.table();
        (t[0][0], t[t.len() - 1][0])
    }

    /// The complex index `n + iκ` at the vacuum wavelength `lambda_um` (µm).
    ///
    /// Linear interpolation of `n` and of `κ` between the tabulated rows (the tabulated values
    /// exactly at a tabulated wavelength, `λ = T::lit(row[0])`). Outside
    /// [`range_um`](Self::range_um) the first or last row's value is held (constant
    /// extrapolation); use [`try_index`](Self::try_index) to refuse such wavelengths. A NaN
    /// wavelength gives NaN.
    #[must_use]
    pub fn index<T: Real>(self, lambda_um: T) -> Complex<T> {
        let t = self.table();
        if is_nan(lambda_um) {
            return Complex::new(lambda_um, lambda_um);
        }
        let [first, last] = [t[0], t[t.len() - 1]];
        if lambda_um <= T::lit(first[0]) {
            return Complex::new(T::lit(first[1]), T::lit(first[2]));
        }
        if lambda_um >= T::lit(last[0]) {
            return Complex::new(T::lit(last[1]), T::lit(last[2]));
        }
        // The last row at or below λ: 0 ≤ i ≤ len − 2 by the two tests above.
        let i = t.partition_point(|row| T::lit(row[0]) <= lambda_um) - 1;
        let (a, b) = (t[i], t[i + 1]);
        let x0 = T::lit(a[0]);
        let s = (lambda_um - x0) / (T::lit(b[0]) - x0);
        Complex::new(lerp(a[1], b[1], s), lerp(a[2], b[2], s))
    }

    /// [`index`](Self::index), or an error for a wavelength outside the table.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a NaN or infinite wavelength, [`Error::OutOfRange`] for one
    /// outside [`range_um`](Self::range_um) (the ends included in the range).
    pub fn try_index<T: Real>(self, lambda_um: T) -> Result<Complex<T>, Error> {
        if !lambda_um.is_finite() {
            return Err(Error::NonFinite { what: "wavelength" });
        }
        let (lo, hi) = self.range_um();
        if lambda_um < T::lit(lo) || lambda_um > T::lit(hi) {
            return Err(Error::OutOfRange {
                what: "wavelength (µm) of a tabulated metal",
                value: lambda_um.to_f64(),
                expected: "the metal's range_um()",
            });
        }
        Ok(self.index(lambda_um))
    }
}
