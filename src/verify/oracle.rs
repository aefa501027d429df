//! Oracles: the seed's formulas written literally from the papers, deliberately slow and
//! obvious, never calling the crate's closed forms:
//! - S1: the column and row stacks ([`vec_columns`], [`vec_rows`]), S1.3's `A_mül`, the
//!   Kronecker product, S1.2's `A_mül vec(C)` ([`generalized_stokes`]), S1.4–S1.5 (the CSD after
//!   a Jones pair, [`csd_after`], [`csd_after_stacked`]), S1.7 ([`generalized_mueller`], and
//!   its real one-point case [`mueller_literal`]), Stokes of a CSD;
//! - S2.3's τ from projections and dot products and S2.4's `T = A_mül (τ ⊗ τ) A_mül⁻¹`, s/p
//!   bases, the exit azimuth, Germer's Rayleigh–Rice polarization factors (SCATMECH's form);
//! - Lemma S2.1 as printed, corrected and by Fourier quadrature; Corollary S2.2 literally and by
//!   quadrature; the PSD blur `p * g^Σ` and S2.15's coherence integral by quadrature (which
//!   decide S2.17's constant); the surface section `Ξ` of a packet channel (S2.18) and the
//!   closed-form coherence integral of S2.10.
//!
//! Conventions are the crate's (see the crate docs, "Conventions"): column stacking,
//! `e^{−iωt}`, `g^Σ(x) = exp(−½ xᵀΣ⁻¹x)`. An oracle panics on an input outside its formula
//! (a singular matrix, a non-real result that must be real): it is a test's reference.
//!
//! ```
//! use gmueller::jones::JonesMatrix;
//! use gmueller::mueller::Mueller;
//! use gmueller::verify::{check, oracle, tol::F64};
//! use nalgebra::Matrix2;
//! use num_complex::Complex;
//! let j = Matrix2::new(Complex::new(0.3, 0.1), Complex::new(-0.2, 0.5),
//!                      Complex::new(0.0, -0.4), Complex::new(0.7, 0.2));
//! // S1.7 literally against the crate's closed form.
//! let closed = Mueller::from_jones(&JonesMatrix::from_matrix(j)?).matrix();
//! check::assert_mueller_close("S1.7", &oracle::mueller_literal(&j), &closed, F64);
//! # Ok::<(), gmueller::Error>(())
//! ```

use nalgebra::{Matrix2, Matrix3, Matrix4, Vector2, Vector3};
use num_complex::Complex;

type C64 = Complex<f64>;

fn c(re: f64, im: f64) -> C64 {
    Complex::new(re, im)
}

/// S1.3, as printed: `S = A_mül vec(C)` with `vec(C) = (C_xx, C_yx, C_xy, C_yy)`.
pub fn a_mul() -> Matrix4<C64> {
    let (o, z, i) = (c(1.0, 0.0), c(0.0, 0.0), c(0.0, 1.0));
    Matrix4::new(
        o, z, z, o, //
        o, z, z, -o, //
        z, o, o, z, //
        z, -i, i, z,
    )
}

/// `A_mül⁻¹`, written out (`½ A_mül†`); [`a_mul_inverse_is_inverse`] checks it.
pub fn a_mul_inv() -> Matrix4<C64> {
    let (h, z, hi) = (c(0.5, 0.0), c(0.0, 0.0), c(0.0, 0.5));
    Matrix4::new(
        h, h, z, z, //
        z, z, h, hi, //
        z, z, h, -hi, //
        h, -h, z, z,
    )
}

/// `A_mül A_mül⁻¹ = I` to rounding (a self-check of the two literals above).
pub fn a_mul_inverse_is_inverse() -> bool {
    (a_mul() * a_mul_inv() - Matrix4::identity()).norm() < 1e-15
}

/// The Kronecker product, entry by entry: `(A ⊗ B)[2i + k, 2j + l] = A[i, j] B[k, l]`.
pub fn kron(a: &Matrix2<C64>, b: &Matrix2<C64>) -> Matrix4<C64> {
    Matrix4::from_fn(|r, col| a[(r / 2, col / 2)] * b[(r % 2, col % 2)])
}

/// S1.7 with `p₁ = p₂`, literally: `M = A_mül (J* ⊗ J) A_mül⁻¹` (real: the imaginary parts are
/// asserted to vanish to rounding).
pub fn mueller_literal(j: &Matrix2<C64>) -> Matrix4<f64> {
    let m = a_mul() * kron(&j.map(|z| z.conj()), j) * a_mul_inv();
    let scale = m.iter().map(|z| z.norm()).fold(0.0, f64::max);
    let imag = m.iter().map(|z| z.im.abs()).fold(0.0, f64::max);
    assert!(imag <= 1e-13 * scale.max(1e-300), "S1.7 is real: {imag:e}");
    m.map(|z| z.re)
}

/// S2.3 literally: `τ_ij = ê′_{i⊥} · ê_j` (rows: the new basis `to`, columns: the old basis
/// `from`), `ê′_⊥` the normalised projection of the new basis vector onto the old transverse
/// plane (normal `k̂ = ê₁ × ê₂`) — the map from field components in `from` to components in `to`.
/// For bases that share their propagation direction the projections are the vectors themselves.
pub fn tau(from: [Vector3<f64>; 2], to: [Vector3<f64>; 2]) -> Matrix2<f64> {
    let k = from[0].cross(&from[1]);
    let proj = |v: Vector3<f64>| {
        let p = v - k * v.dot(&k);
        p / p.norm()
    };
    let to = [proj(to[0]), proj(to[1])];
    Matrix2::from_fn(|i, j| to[i].dot(&from[j]))
}

/// S2.4 as its definition `T = A_mül (τ ⊗ τ) A_mül⁻¹` (τ real, so `τ* = τ`).
pub fn rotation_literal(from: [Vector3<f64>; 2], to: [Vector3<f64>; 2]) -> Matrix4<f64> {
    mueller_literal(&tau(from, to).map(|x| c(x, 0.0)))
}

/// The s/p basis of a beam travelling along the unit `d` at a surface with unit normal `n`:
/// `ŝ = (d × n)/|d × n|`, `p̂ = d × ŝ`. At normal incidence (`|d × n| < 1e-9`) `ŝ` is the crate's
/// documented fallback, the first tangent of Duff et al.'s basis of n̂, which for `n̂ = ẑ` is x̂
/// (`Frame::sp` docs; only `n̂ = ẑ` is supported here).
pub fn sp_basis(d: &Vector3<f64>, n: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let cr = d.cross(n);
    let s = if cr.norm() > 1e-9 {
        cr.normalize()
    } else {
        assert!((n - Vector3::z()).norm() < 1e-15, "fallback only for n̂ = ẑ");
        let x = Vector3::x();
        (x - d * d.dot(&x)).normalize()
    };
    [s, d.cross(&s)]
}

/// `(cos φ, sin φ)` of the exit azimuth as `Geometry::exit_azimuth` defines it: from the forward
/// tangent `û = n̂ × ŝ_in` toward `v̂ = n̂ × û`, read off the exit s vector
/// `ŝ_out = sin φ û − cos φ v̂`.
pub fn exit_azimuth(s_in: &Vector3<f64>, s_out: &Vector3<f64>, n: &Vector3<f64>) -> (f64, f64) {
    let u = n.cross(s_in);
    let v = n.cross(&u);
    (-s_out.dot(&v), s_out.dot(&u))
}

/// Germer's first-order (Rayleigh–Rice) polarization factors `[[ss, ps], [sp, pp]]` as SCATMECH
/// writes them (Appl. Opt. 36, 8798, 1997; `tests/data/README.md`), `ε` the substrate's
/// permittivity, principal square roots (`Re ≥ 0`).
pub fn rayleigh_rice_factors(
    eps: C64,
    cos_i: f64,
    cos_o: f64,
    cos_phi: f64,
    sin_phi: f64,
) -> Matrix2<C64> {
    let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
    let sin_o = (1.0 - cos_o * cos_o).max(0.0).sqrt();
    let qi = (eps - sin_i * sin_i).sqrt();
    let qs = (eps - sin_o * sin_o).sqrt();
    let em1 = eps - 1.0;
    let ss = em1 * cos_phi / ((cos_i + qi) * (cos_o + qs));
    let pp =
        em1 * (eps * sin_i * sin_o - qs * qi * cos_phi) / ((eps * cos_i + qi) * (eps * cos_o + qs));
    let ps = -em1 * qi * sin_phi / ((eps * cos_i + qi) * (cos_o + qs));
    let sp = -em1 * qs * sin_phi / ((cos_i + qi) * (eps * cos_o + qs));
    Matrix2::new(ss, ps, sp, pp)
}

/// The section of a packet channel's coherence by the surface (S2.18 at separations in the
/// surface): `Ξ = Bᵀ Q Θ⁻¹ Qᵀ B`, `Θ⁻¹ = blockdiag(Θ⊥⁻¹, 1/σ_zz²)`, `Q = [x̂ ŷ k̂]` the packet frame
/// (packet → world), `B = [t̂₁ t̂₂]` the surface tangents. Built from 3×3 products here (the
/// crate uses a 2×2 form).
pub fn section(
    q: &Matrix3<f64>,
    theta_perp: &Matrix2<f64>,
    inv_sigma_zz_sq: f64,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> Matrix2<f64> {
    let mut inv = Matrix3::zeros();
    inv.fixed_view_mut::<2, 2>(0, 0)
        .copy_from(&theta_perp.try_inverse().expect("Θ⊥ invertible"));
    inv[(2, 2)] = inv_sigma_zz_sq;
    let world = q * inv * q.transpose();
    let b = nalgebra::Matrix3x2::from_columns(&[*t1, *t2]);
    b.transpose() * world * b
}

/// The S2.10 coherence integral of one channel at `r̂₁ = r̂₂ = r̂`, divided by the area `|P|`
/// (the window drops out exactly: `tests/interaction/s2_10.rs`, module docs), for a Gaussian
/// autocorrelation `R(ξ) = σ² exp(−½ ξᵀ C⁻¹ ξ)`:
/// ```text
/// f(h) = ∫ e^{−i h·ξ} R(ξ) g^{Ξ⁻¹}(ξ) d²ξ = σ² 2π |G|^{−1/2} exp(−½ hᵀ G⁻¹ h),   G = C⁻¹ + Ξ
/// ```
/// (`g^{Ξ⁻¹}(ξ) = exp(−½ ξᵀ Ξ ξ)` the channel's two-point function on the surface). `C⁻¹ = 0`
/// with `σ² = 1` is the smooth mean surface (the specular lobe), with `σ² = R(0)` the
/// incoherent limit (coherence much narrower than the correlation length).
pub fn coherence_integral(
    sigma2: f64,
    c_inv: &Matrix2<f64>,
    xi: &Matrix2<f64>,
    h: &Vector2<f64>,
) -> f64 {
    let g = c_inv + xi;
    let det = g[(0, 0)] * g[(1, 1)] - g[(0, 1)] * g[(1, 0)];
    let gi = g.try_inverse().expect("G invertible");
    sigma2 * std::f64::consts::TAU / det.sqrt() * (-0.5 * h.dot(&(gi * h))).exp()
}

/// The unitary 2-D PSD of `R(ξ) = σ² exp(−½ ξᵀ C⁻¹ ξ)`: `p(ζ) = σ² |C|^{1/2} exp(−½ ζᵀ C ζ)`.
pub fn gaussian_psd(sigma2: f64, c: &Matrix2<f64>, zeta: &Vector2<f64>) -> f64 {
    sigma2 * c.determinant().sqrt() * (-0.5 * zeta.dot(&(c * zeta))).exp()
}

/// Classical Stokes parameters of a 2×2 coherency (CSD) matrix: `S0 = C_xx + C_yy`,
/// `S1 = C_xx − C_yy`, `S2 = 2 Re C_xy`, `S3 = 2 Im C_yx` (S1.2–S1.3).
pub fn stokes_of_csd(m: &Matrix2<C64>) -> nalgebra::Vector4<f64> {
    nalgebra::Vector4::new(
        (m[(0, 0)] + m[(1, 1)]).re,
        (m[(0, 0)] - m[(1, 1)]).re,
        2.0 * m[(0, 1)].re,
        2.0 * m[(1, 0)].im,
    )
}

// ---------------------------------------------------------------- S1: stacking, CSD, Mueller

/// The column stack (S1.1 as the crate defines it, `DESIGN`/crate docs "Conventions"):
/// `vec(C) = (C₁₁, C₂₁, C₁₂, C₂₂)`.
pub fn vec_columns(m: &Matrix2<C64>) -> nalgebra::Vector4<C64> {
    nalgebra::Vector4::new(m[(0, 0)], m[(1, 0)], m[(0, 1)], m[(1, 1)])
}

/// The row stack the seed's text describes, `(C₁₁, C₁₂, C₂₁, C₂₂)` (with which S1.1, S1.3 and
/// S1.7 as printed do not hold: the crate's Errata 1).
pub fn vec_rows(m: &Matrix2<C64>) -> nalgebra::Vector4<C64> {
    nalgebra::Vector4::new(m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)])
}

/// S1.2: the generalized Stokes parameters `A_mül vec(C)` of a (one- or two-point) CSD matrix,
/// complex in general (real for a one-point C).
pub fn generalized_stokes(csd: &Matrix2<C64>) -> nalgebra::Vector4<C64> {
    a_mul() * vec_columns(csd)
}

/// S1.4: the CSD after a pair of Jones matrices, `J(r₁) C(r₁, r₂) J(r₂)†`.
pub fn csd_after(j1: &Matrix2<C64>, j2: &Matrix2<C64>, csd: &Matrix2<C64>) -> Matrix2<C64> {
    j1 * csd * j2.adjoint()
}

/// S1.5: the same in stacked form, `[J(r₂)* ⊗ J(r₁)] vec(C)` (Lemma S1.1 with `A = J₁`,
/// `B = J₂*`), returned as `vec` of the result.
pub fn csd_after_stacked(
    j1: &Matrix2<C64>,
    j2: &Matrix2<C64>,
    csd: &Matrix2<C64>,
) -> nalgebra::Vector4<C64> {
    kron(&j2.map(|z| z.conj()), j1) * vec_columns(csd)
}

/// S1.7: the generalized Mueller matrix `𝓜(p₁, p₂) = A_mül [J(p₂)* ⊗ J(p₁)] A_mül⁻¹` (complex
/// 4×4; real when `J₁ = J₂`, see [`mueller_literal`]).
pub fn generalized_mueller(j1: &Matrix2<C64>, j2: &Matrix2<C64>) -> Matrix4<C64> {
    a_mul() * kron(&j2.map(|z| z.conj()), j1) * a_mul_inv()
}

// ---------------------------------------------------------------- S2.1–S2.2, S2.15–S2.17 by quadrature

/// `g^Σ(x) = exp(−½ xᵀ Σ⁻¹ x)` (unnormalised), with nalgebra's general inverse.
pub fn gaussian<const N: usize>(
    cov: &nalgebra::SMatrix<f64, N, N>,
    x: &nalgebra::SVector<f64, N>,
) -> f64 {
    let inv = cov.try_inverse().expect("Σ invertible");
    (-0.5 * (x.transpose() * inv * x)[0]).exp()
}

/// The unitary Fourier transform `(2π)^{−N/2} ∫ f(x) e^{−i q·x} dᴺx` by the trapezoid rule on
/// `[−half, half]ᴺ` with `n` points per axis ([`super::quadrature::cube_quad`]): spectrally
/// accurate for smooth integrands that have decayed at the faces (Gaussians: choose `half` at
/// ≳ 9 standard deviations, and `n` so that the step resolves both `f` and `e^{−i q·x}`).
pub fn fourier_transform<const N: usize>(
    f: impl Fn(&nalgebra::SVector<f64, N>) -> C64,
    q: &nalgebra::SVector<f64, N>,
    half: f64,
    n: usize,
) -> C64 {
    super::quadrature::cube_quad(|x| f(x) * C64::from_polar(1.0, -q.dot(x)), half, n)
        / std::f64::consts::TAU.powf(N as f64 / 2.0)
}

fn det<const N: usize>(m: &nalgebra::SMatrix<f64, N, N>) -> f64 {
    nalgebra::DMatrix::from_iterator(N, N, m.iter().copied()).determinant()
}

/// Lemma S2.1 as printed: `F{g^Σ(Bξ)}(q) = |Σ|^{1/2}/|B| · g^{Σ⁻¹}(B⁻¹ q)`, with `|B|` read as
/// the signed determinant. Wrong for a non-symmetric `B` (Errata 2): kept to show it fails.
pub fn lemma_s2_1_printed<const N: usize>(
    cov: &nalgebra::SMatrix<f64, N, N>,
    b: &nalgebra::SMatrix<f64, N, N>,
    q: &nalgebra::SVector<f64, N>,
) -> f64 {
    let arg = b.try_inverse().expect("B invertible") * q;
    det(cov).sqrt() / det(b) * (-0.5 * (arg.transpose() * cov * arg)[0]).exp()
}

/// Lemma S2.1 corrected (Errata 2): `F{g^Σ(Bξ)}(q) = |Σ|^{1/2}/|det B| · g^{Σ⁻¹}(B⁻ᵀ q)`,
/// written literally.
pub fn lemma_s2_1<const N: usize>(
    cov: &nalgebra::SMatrix<f64, N, N>,
    b: &nalgebra::SMatrix<f64, N, N>,
    q: &nalgebra::SVector<f64, N>,
) -> f64 {
    let arg = b.transpose().try_inverse().expect("B invertible") * q;
    det(cov).sqrt() / det(b).abs() * (-0.5 * (arg.transpose() * cov * arg)[0]).exp()
}

/// The left side of Lemma S2.1, `F{g^Σ(Bξ)}(q)`, by quadrature ([`fourier_transform`]) on a
/// cube reaching 9 standard deviations of `g^Σ(B·)` along each axis, `n` points per axis
/// (`n ≈ 301` gives ~1e-12 in 2-D for moderate `q` and a round `g^Σ(B·)`; 3-D needs `n³`
/// evaluations). The step `18 σ_max/n` must also resolve the narrowest width `σ_min` of
/// `C = B⁻¹ΣB⁻ᵀ`: `n ≳ 36 σ_max/σ_min` keeps it below `σ_min/2` (a fixed 241 missed 1e-6
/// relative at `σ_max/σ_min ≈ 30`; `examples/verify_derivation.rs` chooses `n` so).
pub fn lemma_s2_1_by_quadrature<const N: usize>(
    cov: &nalgebra::SMatrix<f64, N, N>,
    b: &nalgebra::SMatrix<f64, N, N>,
    q: &nalgebra::SVector<f64, N>,
    n: usize,
) -> C64 {
    let bi = b.try_inverse().expect("B invertible");
    let c = bi * cov * bi.transpose();
    let max_var = (0..N).map(|i| c[(i, i)]).fold(0.0, f64::max);
    fourier_transform(
        |x| C64::new(gaussian(cov, &(b * x)), 0.0),
        q,
        9.0 * max_var.sqrt(),
        n,
    )
}

/// Corollary S2.2 for one channel, literally: the transform of a packet term
/// `e^{−i k ŝ·ξ} g^Θ(Qᵀ ξ)` (`Θ` in the packet's coordinates, `Q` packet → world) is
/// `|Θ|^{1/2} g^{Θ⁻¹}(Qᵀ(q + k ŝ))`.
pub fn corollary_s2_2<const N: usize>(
    theta: &nalgebra::SMatrix<f64, N, N>,
    q_frame: &nalgebra::SMatrix<f64, N, N>,
    k_s: &nalgebra::SVector<f64, N>,
    q: &nalgebra::SVector<f64, N>,
) -> f64 {
    let arg = q_frame.transpose() * (q + k_s);
    det(theta).sqrt() * (-0.5 * (arg.transpose() * theta * arg)[0]).exp()
}

/// The left side of Corollary S2.2 by quadrature: `F{e^{−i k ŝ·ξ} g^Θ(Qᵀ ξ)}(q)` on
/// `[−half, half]ᴺ` with `n` points per axis.
pub fn corollary_s2_2_by_quadrature<const N: usize>(
    theta: &nalgebra::SMatrix<f64, N, N>,
    q_frame: &nalgebra::SMatrix<f64, N, N>,
    k_s: &nalgebra::SVector<f64, N>,
    q: &nalgebra::SVector<f64, N>,
    half: f64,
    n: usize,
) -> C64 {
    fourier_transform(
        |x| gaussian(theta, &(q_frame.transpose() * x)) * C64::from_polar(1.0, -k_s.dot(x)),
        q,
        half,
        n,
    )
}

/// The PSD blur as the crate defines it (`psd::BlurMethod::blur`), by quadrature: the unitary
/// convolution `(p * g^Σ)(h) = (2π)^{−N/2} ∫ p(ζ) g^Σ(h − ζ) dᴺζ` on `[−half, half]ᴺ` with
/// `n` points per axis (`Σ` the covariance of the coherence Gaussian, `Ξ` in S2.17).
pub fn blur_by_quadrature<const N: usize>(
    psd: &dyn Fn(&nalgebra::SVector<f64, N>) -> f64,
    cov: &nalgebra::SMatrix<f64, N, N>,
    h: &nalgebra::SVector<f64, N>,
    half: f64,
    n: usize,
) -> f64 {
    super::quadrature::cube_quad(|z| C64::new(psd(z) * gaussian(cov, &(h - z)), 0.0), half, n).re
        / std::f64::consts::TAU.powf(N as f64 / 2.0)
}

/// S2.15 directly, for one channel: `f(h) = ∫ e^{−i h·ξ} R(ξ) g^Θ(Qᵀ ξ) dᴺξ` (`R` the matter's
/// stationary autocorrelation, `Θ` the channel's shape in packet coordinates, `Q` packet →
/// world, `h = k(r̂ + ŝ)`), by quadrature on `[−half, half]ᴺ` with `n` points per axis.
/// S2.17 says `f = (2π)^{N/2} |Θ|^{1/2} (p * g^Ξ)(h)` with `Ξ = Q Θ⁻¹ Qᵀ` (the crate's Errata 3:
/// not the printed `8π³`).
pub fn coherence_integral_by_quadrature<const N: usize>(
    autocorrelation: &dyn Fn(&nalgebra::SVector<f64, N>) -> f64,
    theta: &nalgebra::SMatrix<f64, N, N>,
    q_frame: &nalgebra::SMatrix<f64, N, N>,
    h: &nalgebra::SVector<f64, N>,
    half: f64,
    n: usize,
) -> C64 {
    super::quadrature::cube_quad(
        |x| {
            C64::from_polar(
                autocorrelation(x) * gaussian(theta, &(q_frame.transpose() * x)),
                -h.dot(x),
            )
        },
        half,
        n,
    )
}
