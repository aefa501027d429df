//! The channels' inverse coherences in bases of their own, in which they are diagonal: the
//! form in which the medium evaluates its coherence weights, exact whatever their condition.
//!
//! # Formula
//! ```text
//! Ξ_α = Q Θ_α⁻¹ Qᵀ = B_α diag(μ₁, μ₂, Ξ_zz) B_αᵀ,   B_α = [b̂₁ b̂₂ d̂]            (S2.18)
//! b̂₁, b̂₂: the eigenvectors of Θ⊥_α⁻¹ (eigenvalues μ₁ ≥ μ₂) in the packet's transverse plane
//! ln K³_α = ln((2π)^{3/2} σ²) − ½ ln|C| − ½ |L⁻¹ B_αᵀ h|²,   C = L Lᵀ                (a Gaussian lobe)
//!   Incoherent:                     C = diag(μ₁, μ₂, Ξ_zz)           ((2π)^{3/2} σ² = ∫p)
//!   Partial, Gaussian PSD, exact:   C = B_αᵀ Λ B_α + diag(μ₁, μ₂, Ξ_zz)   (Λ the spectral covariance)
//! ```
//! For a Gaussian PSD `p = σ² (2π)^{3/2} 𝒩_Λ`, so `(2π)^{3/2} ∫ p 𝒩_Ξ(h − ·) = (2π)^{3/2} σ² |Λ + Ξ|^{−1/2}
//! exp(−½ hᵀ(Λ + Ξ)⁻¹h)` (the closed form of [`crate::psd::ClosedForm`], in `B_α`'s axes), and the
//! incoherent weight `|Θ_α|^{1/2} g^{Ξ_α}(h) ∫p` is the same with `Λ = 0`. An isotropic PSD is
//! the same function in every orthonormal basis: the medium hands the blur `B_αᵀ h` and the
//! diagonal `diag(μ₁, μ₂, Ξ_zz)` ([`ChannelBasis`]).
//!
//! # Why
//! In world axes a 3-D Gaussian whose variances span more than `1/ε` cannot be held in `T`:
//! every entry carries an error `ε λ_max`, which is the whole of the small variances. A packet
//! of a 2.7·10³ λ coherence width and a 0.27 λ `σ_zz` (ratio 10⁸) lost its transverse
//! coherence in `f32` (the scattering coefficient came out 0, `tests/medium/f32.rs`); a short
//! `σ_zz` beside a long correlation length did the same to the `Partial` blur `Λ + Ξ` (ratio
//! `(ℓ/σ_zz)²`). In `B_α` nothing large meets anything small: the matrices are formed and
//! factored in `f64`, and each term of `|L⁻¹ B_αᵀ h|²` is a square of one projection, whose only
//! rounding is `ε |row| |h|` — what an `f32` exit direction carries anyway.

use nalgebra::{Matrix2, Matrix3, Vector3};

use crate::error::Error;
use crate::frame::Frame;
use crate::gaussian::Gaussian;
use crate::numerics::cholesky;
use crate::packet::{Channel, WavePacket};
use crate::real::Real;

/// The inverse coherence of a channel in the packet basis `(x̂, ŷ, d̂)`, in `f64`:
/// `Qᵀ Ξ_α Q = blockdiag(Θ⊥_α⁻¹, Ξ_zz)` (S2.18 with `Θ_α = blockdiag(Θ⊥_α, σ_zz²)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PacketXi {
    /// `Θ⊥_α⁻¹` (rad²/length², packet basis).
    pub(crate) transverse: Matrix2<f64>,
    /// `Ξ_zz` (`1/σ_zz²`, raised as [`packet_inverse_coherence`] says).
    pub(crate) zz: f64,
}

impl PacketXi {
    /// The 3×3 block-diagonal matrix `blockdiag(Θ⊥⁻¹, Ξ_zz)`.
    pub(crate) fn matrix(&self) -> Matrix3<f64> {
        let t = &self.transverse;
        Matrix3::new(
            t[(0, 0)],
            t[(0, 1)],
            0.0,
            t[(1, 0)],
            t[(1, 1)],
            0.0,
            0.0,
            0.0,
            self.zz,
        )
    }
}

/// [`PacketXi`] of a channel: `Θ⊥_α⁻¹` and `Ξ_zz`, in `f64` (`Θ_½ = (Θ_x + Θ_y)/2` formed in
/// `f64` too: the mean rounded to `T` moves the small eigenvalue of a rotated anisotropic shape
/// by `ε λ_max`, 3 % in `f32` at a condition of 5·10⁵).
///
/// A longitudinal variance `1/σ_zz²` below `64 ε₆₄` times the largest transverse one `1/w²`
/// (`σ_zz ≳ 1.2e7 w`) is raised to it, and so is that of unbounded longitudinal coherence
/// (`σ_zz = ∞`, monochromatic light) when `unbounded_ok`: the limit, which moves a blur
/// `∫ p 𝒩_Ξ(h − ·)` by a relative `~64 ε₆₄ λ_max(Θ⊥⁻¹)/Λ_zz` (`Λ_zz` the PSD's spectral variance
/// along d̂): `1e-14 (ℓ/w)²`.
///
/// # Errors
/// [`Error::Singular`] for unbounded longitudinal coherence unless `unbounded_ok`.
pub(crate) fn packet_inverse_coherence<T: Real>(
    packet: &WavePacket<T>,
    channel: Channel,
    unbounded_ok: bool,
) -> Result<PacketXi, Error> {
    let inv_zz = packet.inverse_longitudinal_variance().to_f64();
    if inv_zz == 0.0 && !unbounded_ok {
        return Err(Error::Singular {
            what: "3-D shape matrix with unbounded longitudinal coherence (set σ_zz with \
                   WavePacket::with_longitudinal_coherence)",
        });
    }
    let f64_shape = |c: Channel| packet.shape(c).map(|x| x.to_f64());
    let s = match channel {
        Channel::Half => (f64_shape(Channel::X) + f64_shape(Channel::Y)) * 0.5,
        c => f64_shape(c),
    };
    let det = s[(0, 0)] * s[(1, 1)] - s[(0, 1)] * s[(1, 0)];
    let inv = Matrix2::new(s[(1, 1)], -s[(0, 1)], -s[(1, 0)], s[(0, 0)]) / det;
    let (_, hi) = eigen2(&inv);
    Ok(PacketXi {
        transverse: inv,
        zz: inv_zz.max(64.0 * f64::EPSILON * hi),
    })
}

/// `(λ_min, λ_max)` of a symmetric 2×2 matrix in `f64`, the small one as `det/λ_max`.
fn eigen2(m: &Matrix2<f64>) -> (f64, f64) {
    let (a, b, d) = (m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
    let hi = 0.5 * (a + d) + (0.5 * (a - d)).hypot(b);
    let lo = if hi > 0.0 {
        (a * d - b * b).max(0.0) / hi
    } else {
        0.0
    };
    (lo, hi)
}

/// A channel's basis `B_α = [b̂₁ b̂₂ d̂]` (world, `f64`) and its inverse coherence in it,
/// `diag(μ₁, μ₂, Ξ_zz)` (module formula).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ChannelBasis {
    pub(crate) axes: [Vector3<f64>; 3],
    pub(crate) xi: [f64; 3],
}

impl ChannelBasis {
    /// The basis of the channel whose inverse coherence in the packet basis is `xi`.
    pub(crate) fn new<T: Real>(xi: &PacketXi, frame: &Frame<T>) -> Self {
        let m = &xi.transverse;
        let (a, b, d) = (m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
        let (lo, hi) = eigen2(m);
        let (s, c) = (0.5 * b.atan2(0.5 * (a - d))).sin_cos();
        let v = |w: Vector3<T>| w.map(|x| x.to_f64());
        let (x, y, z) = (v(frame.x), v(frame.y), v(frame.k));
        Self {
            axes: [x * c + y * s, y * c - x * s, z],
            xi: [hi, lo, xi.zz],
        }
    }

    /// `B_αᵀ A B_α` of a world matrix `A` (`T`), in `f64`.
    pub(crate) fn project<T: Real>(&self, a: &Matrix3<T>) -> Matrix3<f64> {
        let b = Matrix3::from_columns(&self.axes);
        let m = b.transpose() * a.map(|x| x.to_f64()) * b;
        (m + m.transpose()) * 0.5
    }

    /// `diag(μ₁, μ₂, Ξ_zz)`.
    pub(crate) fn diagonal(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::from(self.xi))
    }

    /// The axes rounded to `T` (the rows of `B_αᵀ`).
    pub(crate) fn rows<T: Real>(&self) -> [Vector3<T>; 3] {
        self.axes.map(|a| a.map(T::lit))
    }

    /// `diag(μ₁, μ₂, Ξ_zz)` as a Gaussian in `T` (diagonal Cholesky factor); `None` when a
    /// variance is not representable.
    pub(crate) fn gaussian<T: Real>(&self) -> Option<Gaussian<T, 3>> {
        let l = Matrix3::from_diagonal(&Vector3::from(self.xi.map(|x| T::lit(x.sqrt()))));
        Gaussian::from_cholesky(l)
    }
}

/// A coherence weight of Gaussian form in a channel's basis (module formula):
/// `ln K³ = c − ½ Σᵢ (nᵢ·h)²` with the rows `nᵢ` of `L⁻¹ B_αᵀ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PacketLobe<T: Real> {
    rows: [Vector3<T>; 3],
    /// `c = ln((2π)^{3/2} σ²) − ½ ln|C|` (may be `−∞`: a PSD of zero variance).
    constant: T,
}

impl<T: Real> PacketLobe<T> {
    /// The lobe of covariance `c` (in `h`, in the basis `basis`) and amplitude
    /// `ln_amplitude = ln((2π)^{3/2} σ²)`; `None` unless `c` factors in `f64` and the rows and
    /// `ln|C|` are representable in `T`.
    pub(crate) fn new(c: &Matrix3<f64>, basis: &ChannelBasis, ln_amplitude: f64) -> Option<Self> {
        let l = cholesky(c).ok()?;
        // L⁻¹ (lower triangular), then its rows in world axes.
        let mut inv = Matrix3::<f64>::zeros();
        for j in 0..3 {
            inv[(j, j)] = l[(j, j)].recip();
            for i in (j + 1)..3 {
                let s: f64 = (j..i).map(|m| l[(i, m)] * inv[(m, j)]).sum();
                inv[(i, j)] = -s / l[(i, i)];
            }
        }
        let rows: [Vector3<f64>; 3] =
            core::array::from_fn(|i| (0..3).map(|j| basis.axes[j] * inv[(i, j)]).sum());
        let ln_det: f64 = (0..3).map(|i| 2.0 * l[(i, i)].ln()).sum();
        let constant = ln_amplitude - 0.5 * ln_det;
        let finite = rows
            .iter()
            .all(|r| r.iter().all(|x| T::lit(*x).is_finite()))
            && ln_det.is_finite()
            && !constant.is_nan();
        finite.then(|| Self {
            rows: rows.map(|r| r.map(T::lit)),
            constant: T::lit(constant),
        })
    }

    /// `ln K³` at `h` (rad/length, world).
    #[inline]
    pub(crate) fn log_weight(&self, h: &Vector3<T>) -> T {
        let q = self.rows.iter().fold(T::zero(), |acc, n| {
            let t = n.dot(h);
            acc + t * t
        });
        self.constant - T::lit(0.5) * q
    }
}
