//! The CIE 1931 colour-matching functions and the sRGB colour space (IEC 61966-2-1).

use super::lerp;
use super::tables::{CIE1931_INTEGRAL_UM, CIE1931_TABLE, SRGB_TO_XYZ, XYZ_TO_SRGB};
use crate::numerics::is_nan;
use crate::real::Real;

/// The first wavelength of [`CIE1931_TABLE`], 0.360 µm.
pub const CIE1931_MIN_UM: f64 = 0.360;

/// The last wavelength of [`CIE1931_TABLE`], 0.830 µm.
pub const CIE1931_MAX_UM: f64 = 0.830;

/// The white of sRGB in XYZ, `(0.9505, 1, 1.089)`: the row sums of [`SRGB_TO_XYZ`] (IEC
/// 61966-2-1's D65, to the standard's 4 decimals; CIE D65 itself is `(0.95047, 1, 1.08883)`).
pub const D65_WHITE_XYZ: [f64; 3] = [0.9505, 1.0, 1.089];

/// The CIE 1931 2° colour-matching functions `[x̄, ȳ, z̄]` at `lambda_um` (µm).
///
/// Linear interpolation between the 1 nm rows of [`CIE1931_TABLE`] (360–830 nm), so the
/// tabulated values are reproduced at `λ = 0.360, 0.361, …, 0.830` µm (exactly in `f64`, where
/// `λ·1000` rounds to the integer; in `f32` to within 1e-6, as `λ` itself is rounded: `0.502_f32`
/// is 501.99997 nm). `[0, 0, 0]` outside `[0.360, 0.830]` µm, where
/// the table stops (the functions are below `1.3·10⁻⁴` of their peaks at both ends); NaN for a
/// NaN wavelength.
///
/// # Examples
/// ```
/// use gmueller::spectral::cie1931;
/// assert_eq!(cie1931(0.555_f64)[1], 1.0); // ȳ peaks at 555 nm
/// let [x, y, _] = cie1931(0.5555_f32);    // halfway to 556 nm
/// assert!(x > cie1931(0.555_f32)[0] && y < 1.0);
/// assert_eq!(cie1931(0.9_f64), [0.0; 3]);
/// ```
#[must_use]
pub fn cie1931<T: Real>(lambda_um: T) -> [T; 3] {
    if is_nan(lambda_um) {
        return [lambda_um; 3];
    }
    // The position in rows: λ·1000 − 360 (nm from the first row). At a tabulated wavelength
    // λ·1000 rounds to the integer (its error, ≤ 1000·ulp(λ)/2, is below half an ulp of the
    // product), so the subtraction is exact and t = 0.
    let u = lambda_um * T::lit(1000.0) - T::lit(360.0);
    let last = CIE1931_TABLE.len() - 1;
    if !(u >= T::zero() && u <= T::lit(last as f64)) {
        return [T::zero(); 3];
    }
    let i = u.floor();
    let t = u - i;
    // 0 ≤ i ≤ 470: the cast is exact.
    let i = i.to_f64() as usize;
    if i == last {
        return CIE1931_TABLE[last].map(T::lit);
    }
    let (a, b) = (CIE1931_TABLE[i], CIE1931_TABLE[i + 1]);
    [
        lerp(a[0], b[0], t),
        lerp(a[1], b[1], t),
        lerp(a[2], b[2], t),
    ]
}

/// `[∫x̄ dλ, ∫ȳ dλ, ∫z̄ dλ]` of [`cie1931`] (λ in µm): `[0.1068654, 0.1068569, 0.1068919]`.
///
/// These are the integrals of the interpolated functions (the trapezoid rule over the table's
/// 1 nm rows, [`CIE1931_INTEGRAL_UM`]); `1000 ∫ȳ dλ` = 106.85691 is the familiar
/// "`CIE_Y_integral` = 106.857" in nm of spectral renderers.
///
/// # Examples
/// ```
/// use gmueller::spectral::cie1931_integral;
/// let [x, y, z] = cie1931_integral::<f64>();
/// assert!((y * 1000.0 - 106.857).abs() < 1e-3);
/// assert!((x / y - 1.0).abs() < 1e-4 && (z / y - 1.0).abs() < 4e-4); // illuminant E ≈ white
/// ```
#[must_use]
pub fn cie1931_integral<T: Real>() -> [T; 3] {
    CIE1931_INTEGRAL_UM.map(T::lit)
}

/// [`cie1931`] divided by `∫ȳ dλ` (λ in µm): the weights that make `XYZ = ∫ L(λ) w(λ) dλ` give
/// `Y = 1` for the equal-energy spectrum `L ≡ 1`.
///
/// A renderer that draws `λ` with density `p(λ)` (per µm) accumulates
/// `L(λ) · cie1931_normalized(λ) / p(λ)` per sample; for `λ` uniform on `[0.36, 0.83]`,
/// `p = 1/0.47`.
///
/// # Examples
/// ```
/// use gmueller::spectral::cie1931_normalized;
/// // Midpoint rule over 360–830 nm for L ≡ 1: Y ≈ 1.
/// let h = 0.47 / 4700.0;
/// let y: f64 = (0..4700).map(|i| cie1931_normalized(0.36 + (f64::from(i) + 0.5) * h)[1] * h).sum();
/// assert!((y - 1.0).abs() < 1e-6, "{y}");
/// ```
#[must_use]
pub fn cie1931_normalized<T: Real>(lambda_um: T) -> [T; 3] {
    let inv = T::lit(1.0 / CIE1931_INTEGRAL_UM[1]);
    cie1931(lambda_um).map(|v| v * inv)
}

fn apply<T: Real>(m: &[[f64; 3]; 3], v: [T; 3]) -> [T; 3] {
    m.map(|row| T::lit(row[0]) * v[0] + T::lit(row[1]) * v[1] + T::lit(row[2]) * v[2])
}

/// CIE XYZ → linear sRGB (IEC 61966-2-1, D65 white): `[R, G, B] = XYZ_TO_SRGB · [X, Y, Z]`.
///
/// No clamping: colours outside the sRGB gamut have negative components. XYZ scaled so that
/// the white has `Y = 1` maps [`D65_WHITE_XYZ`] to `(1, 1, 1)`.
///
/// # Examples
/// ```
/// use gmueller::spectral::{D65_WHITE_XYZ, xyz_to_linear_srgb};
/// let white = xyz_to_linear_srgb(D65_WHITE_XYZ);
/// assert!(white.iter().all(|c| (c - 1.0).abs() < 1e-4));
/// ```
#[must_use]
pub fn xyz_to_linear_srgb<T: Real>(xyz: [T; 3]) -> [T; 3] {
    apply(&XYZ_TO_SRGB, xyz)
}

/// Linear sRGB → CIE XYZ: `[X, Y, Z] = SRGB_TO_XYZ · [R, G, B]`, the inverse of
/// [`xyz_to_linear_srgb`] (to rounding).
///
/// # Examples
/// ```
/// use gmueller::spectral::linear_srgb_to_xyz;
/// assert_eq!(linear_srgb_to_xyz([1.0_f64, 1.0, 1.0]), [0.9505, 1.0, 1.089]);
/// ```
#[must_use]
pub fn linear_srgb_to_xyz<T: Real>(rgb: [T; 3]) -> [T; 3] {
    apply(&SRGB_TO_XYZ, rgb)
}

/// The sRGB transfer function (IEC 61966-2-1): linear `C` → encoded `V`,
/// `V = 12.92 C` for `C ≤ 0.0031308`, `V = 1.055 C^{1/2.4} − 0.055` above.
///
/// No clamping: a renderer clamps to `[0, 1]` first (negative `C` take the linear branch).
///
/// # Examples
/// ```
/// use gmueller::spectral::srgb_encode;
/// assert!((srgb_encode(1.0_f64) - 1.0).abs() < 1e-15); // 1.055 − 0.055
/// assert!((srgb_encode(0.001_f64) - 0.01292).abs() < 1e-15); // the linear segment
/// assert!((srgb_encode(0.18_f64) - 0.4614).abs() < 1e-4); // middle grey
/// ```
#[must_use]
pub fn srgb_encode<T: Real>(linear: T) -> T {
    if linear <= T::lit(0.0031308) {
        T::lit(12.92) * linear
    } else {
        T::lit(1.055) * linear.powf(T::lit(1.0 / 2.4)) - T::lit(0.055)
    }
}

/// The inverse sRGB transfer function (IEC 61966-2-1): encoded `V` → linear `C`,
/// `C = V/12.92` for `V ≤ 0.04045`, `C = ((V + 0.055)/1.055)^{2.4}` above.
///
/// # Examples
/// ```
/// use gmueller::spectral::{srgb_decode, srgb_encode};
/// let c = 0.3_f64;
/// assert!((srgb_decode(srgb_encode(c)) - c).abs() < 1e-15);
/// ```
#[must_use]
pub fn srgb_decode<T: Real>(encoded: T) -> T {
    if encoded <= T::lit(0.04045) {
        encoded / T::lit(12.92)
    } else {
        ((encoded + T::lit(0.055)) / T::lit(1.055)).powf(T::lit(2.4))
    }
}
