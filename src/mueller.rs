//! Mueller matrices: classical (real 4×4, acting on Stokes vectors) and generalized (complex 4×4,
//! acting on generalized Stokes parameters), S1.6–S1.7.

pub mod batch;

use core::ops::Mul;

use nalgebra::{Matrix2, Matrix3, Matrix4, Vector3, Vector4};
use num_complex::Complex;

use crate::error::{Error, ensure_finite};
use crate::jones::JonesMatrix;
use crate::real::Real;
use crate::stokes::{GeneralizedStokes, Stokes};

/// A classical (real 4×4) Mueller matrix acting on [`Stokes`] vectors: `S′ = M S`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mueller<T: Real>(pub(crate) Matrix4<T>);

impl<T: Real> Mueller<T> {
    /// A Mueller matrix from its entries.
    ///
    /// Only finiteness is checked: use [`Mueller::is_physically_realizable`] to test that it maps
    /// every valid Stokes vector to a valid one.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if an entry is NaN or infinite.
    pub fn from_matrix(m: Matrix4<T>) -> Result<Self, Error> {
        ensure_finite("Mueller matrix entry", m.iter().copied())?;
        Ok(Self(m))
    }

    /// The identity.
    #[must_use]
    pub fn identity() -> Self {
        Self(Matrix4::identity())
    }

    /// The entries as an nalgebra matrix.
    #[inline]
    #[must_use]
    pub fn matrix(&self) -> Matrix4<T> {
        self.0
    }

    /// `M₀₀`, the intensity throughput of unpolarized light (as
    /// [`crate::interaction::polarization::Throughput::m00`], without importing the trait).
    #[inline]
    #[must_use]
    pub fn m00(&self) -> T {
        self.0[(0, 0)]
    }

    /// `factor · M` (as [`crate::interaction::polarization::Throughput::scaled`]).
    #[inline]
    #[must_use]
    pub fn scaled(&self, factor: T) -> Self {
        Self(self.0 * factor)
    }

    /// `M S`, the raw product (as [`crate::interaction::polarization::Throughput::apply`]; a
    /// realizable `M` maps valid Stokes vectors to valid ones up to rounding).
    #[inline]
    #[must_use]
    pub fn apply(&self, s: &Stokes<T>) -> Stokes<T> {
        Stokes(self.0 * s.0)
    }

    /// The Mueller matrix of a Jones matrix, in closed form (S1.7 with p₁ = p₂).
    ///
    /// # Formula
    /// ```text
    /// S1.7 (p₁ = p₂):  M = A_mül (J* ⊗ J) A_mül⁻¹,   equivalently   M_kl = ½ tr(σ_k J σ_l J†)
    /// with σ₀ = I, σ₁ = diag(1, −1), σ₂ = [[0, 1], [1, 0]], σ₃ = [[0, −i], [i, 0]].
    /// For H_l = J σ_l J† (Hermitian):  M_0l = ½(H₁₁ + H₂₂),  M_1l = ½(H₁₁ − H₂₂),
    ///                                  M_2l = Re H₁₂,        M_3l = −Im H₁₂.
    /// ```
    /// No 4×4 complex product is formed; the literal formula is the test oracle.
    ///
    /// # Examples
    /// ```
    /// use gmueller::{jones::JonesMatrix, mueller::Mueller};
    /// let m = Mueller::from_jones(&JonesMatrix::<f64>::linear_polarizer(0.0));
    /// assert!((m.matrix()[(0, 1)] - 0.5).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn from_jones(j: &JonesMatrix<T>) -> Self {
        let m = &j.0;
        let (a, b, c, d) = (m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]);
        let half = T::lit(0.5);
        let (aa, bb, cc, dd) = (a.norm_sqr(), b.norm_sqr(), c.norm_sqr(), d.norm_sqr());
        let ac = a * c.conj();
        let bd = b * d.conj();
        let ab = a * b.conj();
        let cd = c * d.conj();
        let bc = b * c.conj();
        let ad = a * d.conj();
        // H_l = J σ_l J†: (H11, H22, H12) for l = 0..3.
        let h11 = [aa + bb, aa - bb, ab.re + ab.re, ab.im + ab.im];
        let h22 = [cc + dd, cc - dd, cd.re + cd.re, cd.im + cd.im];
        // l = 3: H12 = i (b c̄ − a d̄).
        let h12_3 = Complex::new(-(bc.im - ad.im), bc.re - ad.re);
        let h12 = [ac + bd, ac - bd, bc + ad, h12_3];
        let mut out = Matrix4::zeros();
        for l in 0..4 {
            out[(0, l)] = half * (h11[l] + h22[l]);
            out[(1, l)] = half * (h11[l] - h22[l]);
            out[(2, l)] = h12[l].re;
            out[(3, l)] = -h12[l].im;
        }
        Self(out)
    }
}

impl<T: Real> Mul for Mueller<T> {
    type Output = Mueller<T>;
    /// Composition: `(M₂ * M₁)` is M₁ followed by M₂.
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        Self(self.0 * rhs.0)
    }
}

impl<T: Real> Mul<Stokes<T>> for Mueller<T> {
    type Output = Stokes<T>;
    /// `S′ = M S`. Valid whenever `M` is physically realizable (e.g. built from Jones matrices).
    #[inline]
    fn mul(self, rhs: Stokes<T>) -> Stokes<T> {
        Stokes(self.0 * rhs.0)
    }
}

/// The Pauli basis in the crate's order: σ₀ = I, σ₁ = diag(1, −1), σ₂ = [[0, 1], [1, 0]],
/// σ₃ = [[0, −i], [i, 0]] (so that `S_k = tr(σ_k C)`).
fn pauli<T: Real>(k: usize) -> Matrix2<Complex<T>> {
    let o = Complex::new(T::one(), T::zero());
    let z = Complex::new(T::zero(), T::zero());
    let i = Complex::new(T::zero(), T::one());
    match k {
        0 => Matrix2::new(o, z, z, o),
        1 => Matrix2::new(o, z, z, -o),
        2 => Matrix2::new(z, o, o, z),
        _ => Matrix2::new(z, -i, i, z),
    }
}

/// Cloude's coherency matrix `H = ¼ Σ_ij M_ij (σ_i ⊗ σ_j*)` (see [`Mueller::coherency_matrix`]).
fn coherency<T: Real>(m: &Matrix4<T>) -> Matrix4<Complex<T>> {
    let mut h = Matrix4::zeros();
    let q = T::lit(0.25);
    for i in 0..4 {
        let si = pauli::<T>(i);
        for j in 0..4 {
            let sj = pauli::<T>(j).map(|z| z.conj());
            let w = m[(i, j)] * q;
            h += crate::stack::kron(&si, &sj) * Complex::new(w, T::zero());
        }
    }
    h
}

/// The eigenvalues (unsorted) of a Hermitian 4×4 matrix with entries of order 1, by the cyclic
/// complex Jacobi method (Golub & Van Loan, *Matrix Computations*, §8.5, with the phase of
/// `a_pq` removed by a diagonal unitary first).
///
/// # Formula
/// ```text
/// a_pq = g e^{iφ}:  D = diag(1, …, e^{−iφ} at q, …),   A′ = D† A D  has  a′_pq = g ≥ 0
/// ϑ = (a_qq − a_pp) / (2g),  t = sgn ϑ / (|ϑ| + √(ϑ² + 1)),  c = 1/√(1 + t²),  s = t c
/// a_pp ← a_pp − t g,  a_qq ← a_qq + t g,  a_pq ← 0
/// a_rp ← c a′_rp − s a′_rq,  a_rq ← s a′_rp + c a′_rq      (r ∉ {p, q}; Hermitian mirror)
/// ```
/// Sweeps until the off-diagonal Frobenius norm is below `ε ‖A‖_F` (at most 40 sweeps; a
/// sweep of 6 rotations converges quadratically, repeated eigenvalues included). Weyl's
/// inequality then bounds each eigenvalue error by that norm plus the rotations' rounding.
fn hermitian_eigenvalues<T: Real>(mut a: Matrix4<Complex<T>>) -> Vector4<T> {
    let frob2 = a.iter().fold(T::zero(), |acc, z| acc + z.norm_sqr());
    let eps = T::EPSILON;
    for _ in 0..40 {
        let mut off = T::zero();
        for p in 0..3 {
            for q in (p + 1)..4 {
                off += a[(p, q)].norm_sqr();
            }
        }
        if !off.is_finite() || off <= eps * eps * frob2 {
            break;
        }
        for p in 0..3 {
            for q in (p + 1)..4 {
                let apq = a[(p, q)];
                let g = apq.re.hypot(apq.im);
                if g == T::zero() {
                    continue;
                }
                let u_conj = Complex::new(apq.re / g, -apq.im / g); // e^{−iφ}
                let (app, aqq) = (a[(p, p)].re, a[(q, q)].re);
                let theta = (aqq - app) / (g + g);
                let sign = if theta < T::zero() {
                    -T::one()
                } else {
                    T::one()
                };
                let t = sign / (theta.abs() + theta.hypot(T::one()));
                let c = T::one() / t.hypot(T::one());
                let sn = t * c;
                for r in 0..4 {
                    if r == p || r == q {
                        continue;
                    }
                    let arp = a[(r, p)];
                    let arq = a[(r, q)] * u_conj;
                    let new_rp = arp * c - arq * sn;
                    let new_rq = arp * sn + arq * c;
                    a[(r, p)] = new_rp;
                    a[(p, r)] = new_rp.conj();
                    a[(r, q)] = new_rq;
                    a[(q, r)] = new_rq.conj();
                }
                a[(p, p)] = Complex::new(app - t * g, T::zero());
                a[(q, q)] = Complex::new(aqq + t * g, T::zero());
                a[(p, q)] = Complex::new(T::zero(), T::zero());
                a[(q, p)] = Complex::new(T::zero(), T::zero());
            }
        }
    }
    Vector4::new(a[(0, 0)].re, a[(1, 1)].re, a[(2, 2)].re, a[(3, 3)].re)
}

/// `(M / s, s)` with `s = max |M_ij|` (`s = 0` for the zero matrix; all NaN if an entry is
/// not finite): the analysis functions below work on `M / s`, whose entries lie in
/// `[−1, 1]`, so no square or sum overflows or underflows and the results are scale invariant
/// (exactly, for scalings by powers of two).
fn normalized<T: Real>(m: &Matrix4<T>) -> (Matrix4<T>, T) {
    let s = m.iter().fold(T::zero(), |acc, x| acc.max(x.abs()));
    if !m.iter().all(|x| x.is_finite()) {
        return (Matrix4::repeat(T::lit(f64::NAN)), T::lit(f64::NAN));
    }
    if s == T::zero() {
        return (*m, s);
    }
    (m / s, s)
}

/// `num / den`, or 0 when `den = 0`.
fn ratio_or_zero<T: Real>(num: T, den: T) -> T {
    if den == T::zero() {
        T::zero()
    } else {
        num / den
    }
}

impl<T: Real> Mueller<T> {
    /// The diattenuation `D ∈ [0, 1]` (for a physical matrix): how much the transmitted intensity
    /// depends on the incident polarization.
    ///
    /// # Formula
    /// ```text
    /// D = √(M₀₁² + M₀₂² + M₀₃²) / M₀₀        (0-based indices)
    /// ```
    /// Computed on `M / max|M_ij|`: scale invariant, finite at every scale (f32
    /// `from_jones(10¹⁰·diag(2, 1))` gives 0.6, not ∞). Returns 0 when `M₀₀ = 0` (an opaque
    /// element), NaN if an entry is not finite.
    ///
    /// # Examples
    /// ```
    /// use gmueller::{jones::JonesMatrix, mueller::Mueller};
    /// let m = Mueller::from_jones(&JonesMatrix::<f64>::linear_polarizer(0.3));
    /// assert!((m.diattenuation() - 1.0).abs() < 1e-12);
    /// ```
    #[must_use]
    pub fn diattenuation(&self) -> T {
        let (m, _) = normalized(&self.0);
        ratio_or_zero(
            Vector3::new(m[(0, 1)], m[(0, 2)], m[(0, 3)]).norm(),
            m[(0, 0)],
        )
    }

    /// The polarizance `P ∈ [0, 1]` (for a physical matrix): the degree of polarization of the
    /// output for unpolarized input.
    ///
    /// # Formula
    /// ```text
    /// P = √(M₁₀² + M₂₀² + M₃₀²) / M₀₀        (0-based indices)
    /// ```
    /// Computed on `M / max|M_ij|` (scale invariant, as [`Mueller::diattenuation`]). Returns 0
    /// when `M₀₀ = 0`, NaN if an entry is not finite.
    ///
    /// # Examples
    /// ```
    /// use gmueller::{jones::JonesMatrix, mueller::Mueller};
    /// let m = Mueller::from_jones(&JonesMatrix::<f64>::linear_retarder(0.3, 1.0));
    /// assert!(m.polarizance().abs() < 1e-12);
    /// ```
    #[must_use]
    pub fn polarizance(&self) -> T {
        let (m, _) = normalized(&self.0);
        ratio_or_zero(
            Vector3::new(m[(1, 0)], m[(2, 0)], m[(3, 0)]).norm(),
            m[(0, 0)],
        )
    }

    /// The Gil–Bernabeu depolarization index `P_Δ ∈ [0, 1]`: 1 for non-depolarizing (e.g.
    /// Jones-derived) matrices, 0 for the ideal depolarizer `diag(1, 0, 0, 0)`.
    ///
    /// # Formula
    /// ```text
    /// P_Δ = √(Σ_ij M_ij² − M₀₀²) / (√3 M₀₀)         (Gil & Bernabeu 1985)
    /// ```
    /// Computed on `M / max|M_ij|` (scale invariant: 1 for every Jones-derived matrix at any
    /// scale; f32 `from_jones(10¹⁰·diag(2, 1))` gave 0 when `Σ M_ij²` overflowed). Returns 0 when
    /// `M₀₀ = 0`, NaN if an entry is not finite.
    ///
    /// # Examples
    /// ```
    /// use gmueller::mueller::Mueller;
    /// use nalgebra::Matrix4;
    /// let m = Mueller::from_matrix(Matrix4::from_diagonal(&nalgebra::Vector4::new(1.0_f64, 0.5, 0.5, 0.5))).unwrap();
    /// assert!((m.depolarization_index() - 0.5).abs() < 1e-15);
    /// ```
    #[must_use]
    pub fn depolarization_index(&self) -> T {
        let (m, _) = normalized(&self.0);
        let m00 = m[(0, 0)];
        // Σ_{ij} M_ij² − M₀₀² as the sum over the other fifteen entries: the difference lost
        // every digit for a nearly ideal depolarizer (diag(1, a, a, a), |a| ≲ 1e-4 gave P_Δ
        // with a relative error ≳ 1e-8 in f64).
        let mut sum = T::zero();
        for r in 0..4 {
            for c in 0..4 {
                if r + c > 0 {
                    sum += m[(r, c)] * m[(r, c)];
                }
            }
        }
        ratio_or_zero(sum.sqrt(), T::lit(3.0).sqrt() * m00)
    }

    /// Cloude's coherency matrix `H` (4×4 Hermitian), whose eigenvalues decide realizability.
    ///
    /// # Formula
    /// ```text
    /// H = ¼ Σ_ij M_ij (σ_i ⊗ σ_j*)            (Cloude 1986; σ in the crate's order, S1.3)
    /// ```
    /// with σ₀ = I, σ₁ = diag(1, −1), σ₂ = [[0, 1], [1, 0]], σ₃ = [[0, −i], [i, 0]] and `⊗` as
    /// [`crate::stack::kron`]. For `M` from a Jones matrix `J` (`M_ij = ½ tr(σ_i J σ_j J†)`), the
    /// completeness relation `Σ_i (σ_i)_ab (σ_i)_cd = 2 δ_ad δ_bc` gives
    /// `H = ½ vec_r(J) vec_r(J)†` — rank 1, positive semidefinite, `tr H = M₀₀`. A general `M`
    /// is a convex sum of Jones-derived matrices exactly when `H ⪰ 0`.
    ///
    /// # Examples
    /// ```
    /// use gmueller::{jones::JonesMatrix, mueller::Mueller};
    /// let m = Mueller::from_jones(&JonesMatrix::<f64>::linear_retarder(0.2, 0.7));
    /// let h = m.coherency_matrix();
    /// assert!((h.trace().re - 1.0).abs() < 1e-15 && (h - h.adjoint()).norm() < 1e-15);
    /// ```
    #[must_use]
    pub fn coherency_matrix(&self) -> Matrix4<Complex<T>> {
        coherency(&self.0)
    }

    /// The eigenvalues of [`Mueller::coherency_matrix`], sorted in descending order.
    ///
    /// They are real (H is Hermitian) and sum to `M₀₀`. Computed by a cyclic complex Jacobi
    /// eigensolver on the coherency matrix of `M / max|M_ij|` (fixed size, no allocation), then
    /// scaled back: finite for every finite `M` (the result overflows to ±∞ only if an eigenvalue
    /// exceeds `T::MAX`, possible for entries above `T::MAX/4`), with absolute error of a few
    /// `ε · max|M_ij|` — a rank-1 (Jones-derived) matrix has three eigenvalues within `64ε·M₀₀`
    /// of 0, including repeated and nearly repeated eigenvalues, where nalgebra's Hermitian
    /// QR iteration failed to converge in f32 and the result was NaN. All four are NaN if an
    /// entry of `M` is not finite.
    ///
    /// # Examples
    /// ```
    /// use gmueller::mueller::Mueller;
    /// use nalgebra::{Matrix4, Vector4};
    /// // The ideal depolarizer: H = ¼ I.
    /// let m = Mueller::from_matrix(Matrix4::from_diagonal(&Vector4::new(1.0_f64, 0.0, 0.0, 0.0))).unwrap();
    /// let l = m.coherency_eigenvalues();
    /// assert!(l.iter().all(|x| (x - 0.25).abs() < 1e-15));
    /// ```
    #[must_use]
    pub fn coherency_eigenvalues(&self) -> Vector4<T> {
        let (l, s) = self.normalized_coherency_eigenvalues();
        l * s
    }

    /// The eigenvalues of the coherency matrix of `M / s`, `s = max|M_ij|`, sorted descending,
    /// and `s`.
    fn normalized_coherency_eigenvalues(&self) -> (Vector4<T>, T) {
        let (m, s) = normalized(&self.0);
        if !s.is_finite() {
            return (Vector4::repeat(T::lit(f64::NAN)), s);
        }
        let mut l = hermitian_eigenvalues(coherency(&m));
        // Sort descending (4 elements: insertion sort, no allocation).
        for a in 1..4 {
            let mut b = a;
            while b > 0 && l[b - 1] < l[b] {
                l.swap_rows(b - 1, b);
                b -= 1;
            }
        }
        (l, s)
    }

    /// `true` if `M` is physically realizable in Cloude's sense: a convex (incoherent) sum of
    /// Jones-derived Mueller matrices, i.e. every eigenvalue of the coherency matrix `H` is
    /// `≥ −tol · tr H` (and `tr H = M₀₀ > 0`, or `M = 0`).
    ///
    /// The comparison is made on `M / max|M_ij|` (scale invariant; no overflow for entries near
    /// `T::MAX`). `false` if an entry is not finite.
    ///
    /// This is stronger than "maps valid Stokes vectors to valid Stokes vectors"
    /// (e.g. the handedness flip `diag(1, 1, 1, −1)` does that but is not realizable:
    /// its `H` has eigenvalues `(½, ½, ½, −½)`).
    ///
    /// # Examples
    /// ```
    /// use gmueller::{jones::JonesMatrix, mueller::Mueller};
    /// use nalgebra::{Matrix4, Vector4};
    /// assert!(Mueller::from_jones(&JonesMatrix::<f64>::linear_polarizer(0.4)).is_physically_realizable(1e-12));
    /// let flip = Mueller::from_matrix(Matrix4::from_diagonal(&Vector4::new(1.0_f64, 1.0, 1.0, -1.0))).unwrap();
    /// assert!(!flip.is_physically_realizable(1e-12));
    /// ```
    #[must_use]
    pub fn is_physically_realizable(&self, tol: T) -> bool {
        let (l, s) = self.normalized_coherency_eigenvalues();
        if !s.is_finite() {
            return false;
        }
        let trace = if s == T::zero() {
            T::zero()
        } else {
            self.0[(0, 0)] / s
        };
        if trace < T::zero() {
            return false;
        }
        l.iter().all(|&x| x >= -tol * trace)
    }

    /// The Lu–Chipman polar decomposition `M = M_Δ M_R M_D` (Lu & Chipman 1996, JOSA A 13, 1106).
    ///
    /// # Formula
    /// ```text
    /// D = (M₀₁, M₀₂, M₀₃)/M₀₀,   P = (M₁₀, M₂₀, M₃₀)/M₀₀,   m = M[1..4, 1..4]/M₀₀
    /// M_D = M₀₀ ⎡ 1  Dᵀ  ⎤,  m_D = √(1 − D²) I + (1 − √(1 − D²)) D̂ D̂ᵀ
    ///           ⎣ D  m_D ⎦
    /// M′ = M M_D⁻¹ = ⎡ 1    0ᵀ ⎤,  P_Δ = (P − m D)/(1 − D²),  m′ = (m − P_Δ Dᵀ) m_D⁻¹
    ///                ⎣ P_Δ  m′ ⎦
    /// m′ = m_Δ m_R  (polar decomposition, m_Δ = ±√(m′ m′ᵀ) symmetric, m_R a proper rotation,
    ///                the sign being that of det m′)
    /// M_Δ = ⎡ 1    0ᵀ  ⎤,   M_R = ⎡ 1  0ᵀ  ⎤
    ///       ⎣ P_Δ  m_Δ ⎦          ⎣ 0  m_R ⎦
    /// ```
    /// The polar decomposition is computed from the SVD `m′ = U Σ Vᵀ`: `m_R = s U Vᵀ`,
    /// `m_Δ = s U Σ Uᵀ` with `s = sign det m′` (Lu & Chipman's formula). When `m′` is singular
    /// (e.g. an ideal depolarizer) the decomposition is not unique: then the column of `U` of the
    /// smallest singular value is negated if needed to make `m_R` a proper rotation, and `m_Δ`
    /// is the corresponding positive semidefinite factor (still `m_Δ m_R = m′`). For `D = 0`,
    /// `M_D = M₀₀ I`.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] if `M₀₀ ≤ 0`; [`Error::Singular`] if `D ≥ 1 − √ε` (an ideal
    /// polarizer: `M_D` is not invertible and the decomposition not defined); [`Error::Singular`]
    /// if the 3×3 SVD fails to converge.
    ///
    /// # Examples
    /// ```
    /// use gmueller::{jones::JonesMatrix, mueller::Mueller};
    /// let r = Mueller::from_jones(&JonesMatrix::<f64>::linear_retarder(0.3, 1.2));
    /// let lc = r.lu_chipman().unwrap();
    /// assert!((lc.retardance() - 1.2).abs() < 1e-12 && lc.diattenuation() < 1e-12);
    /// ```
    pub fn lu_chipman(&self) -> Result<LuChipman<T>, Error> {
        let full = &self.0;
        let m00 = full[(0, 0)];
        if m00 <= T::zero() {
            return Err(Error::OutOfRange {
                what: "M00 of the Lu–Chipman decomposition",
                value: m00.to_f64(),
                expected: "> 0",
            });
        }
        let n = full / m00;
        let d = Vector3::new(n[(0, 1)], n[(0, 2)], n[(0, 3)]);
        let p = Vector3::new(n[(1, 0)], n[(2, 0)], n[(3, 0)]);
        let m: Matrix3<T> = n.fixed_view::<3, 3>(1, 1).into_owned();
        let dn = d.norm();
        if dn >= T::one() - T::EPSILON.sqrt() {
            return Err(Error::Singular {
                what: "Lu–Chipman diattenuator (D = 1)",
            });
        }
        let k = (T::one() - dn * dn).sqrt();
        // m_D = k I + (1 − k) D̂ D̂ᵀ = k I + (1 − k)/D² D Dᵀ; (1 − k)/D² = 1/(1 + k) avoids 0/0 at D = 0.
        let m_d = Matrix3::identity() * k + d * d.transpose() / (T::one() + k);
        // m_D⁻¹ = I/k − D Dᵀ / (k (1 + k))  (Sherman–Morrison on the rank-1 update).
        let m_d_inv = (Matrix3::identity() - d * d.transpose() / (T::one() + k)) / k;
        let p_delta = (p - m * d) / (k * k);
        let m_prime = (m - p_delta * d.transpose()) * m_d_inv;

        let svd = m_prime
            .try_svd(true, true, T::EPSILON, 10_000)
            .ok_or(Error::Singular {
                what: "Lu–Chipman m′ (SVD did not converge)",
            })?;
        let (Some(mut u), Some(v_t)) = (svd.u, svd.v_t) else {
            return Err(Error::Singular {
                what: "Lu–Chipman m′ (SVD did not converge)",
            });
        };
        let sigma = svd.singular_values;
        let det_m = m_prime.determinant();
        let (m_delta, m_r);
        let smin = sigma.min();
        let smax = sigma.max();
        let singular = smin <= T::lit(64.0) * T::EPSILON * smax;
        let r0 = u * v_t;
        if !singular && det_m < T::zero() {
            // Lu & Chipman: m_Δ = −√(m′m′ᵀ), m_R = −U Vᵀ (a proper rotation).
            m_delta = -(u * Matrix3::from_diagonal(&sigma) * u.transpose());
            m_r = -r0;
        } else {
            if r0.determinant() < T::zero() {
                let imin = sigma.imin();
                for r in 0..3 {
                    u[(r, imin)] = -u[(r, imin)];
                }
            }
            m_delta = u * Matrix3::from_diagonal(&sigma) * u.transpose();
            m_r = u * v_t;
        }

        let mut md = Matrix4::zeros();
        md[(0, 0)] = m00;
        md.fixed_view_mut::<1, 3>(0, 1)
            .copy_from(&(d.transpose() * m00));
        md.fixed_view_mut::<3, 1>(1, 0).copy_from(&(d * m00));
        md.fixed_view_mut::<3, 3>(1, 1).copy_from(&(m_d * m00));
        let mut mr = Matrix4::identity();
        mr.fixed_view_mut::<3, 3>(1, 1).copy_from(&m_r);
        let mut mdel = Matrix4::identity();
        mdel.fixed_view_mut::<3, 1>(1, 0).copy_from(&p_delta);
        mdel.fixed_view_mut::<3, 3>(1, 1).copy_from(&m_delta);
        Ok(LuChipman {
            depolarizer: Mueller(mdel),
            retarder: Mueller(mr),
            diattenuator: Mueller(md),
        })
    }
}

/// The factors of the Lu–Chipman decomposition `M = M_Δ M_R M_D` ([`Mueller::lu_chipman`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LuChipman<T: Real> {
    /// `M_Δ`: the depolarizer (with the polarizance `P_Δ` in its first column).
    pub depolarizer: Mueller<T>,
    /// `M_R`: the pure retarder, `diag(1, m_R)` with `m_R` a proper rotation.
    pub retarder: Mueller<T>,
    /// `M_D`: the diattenuator, carrying the transmittance `M₀₀`.
    pub diattenuator: Mueller<T>,
}

impl<T: Real> LuChipman<T> {
    /// The retardance of [`LuChipman::retarder`], in `[0, π]` radians.
    ///
    /// # Formula
    /// ```text
    /// R = acos(tr(M_R)/2 − 1)        (argument clamped to [−1, 1] against rounding)
    /// ```
    #[must_use]
    pub fn retardance(&self) -> T {
        let c = self.retarder.0.trace() * T::lit(0.5) - T::one();
        c.clamp(-T::one(), T::one()).acos()
    }

    /// The diattenuation of [`LuChipman::diattenuator`] (equal to that of the decomposed matrix).
    #[must_use]
    pub fn diattenuation(&self) -> T {
        self.diattenuator.diattenuation()
    }

    /// The product `M_Δ M_R M_D`, which reproduces the decomposed matrix.
    #[must_use]
    pub fn recompose(&self) -> Mueller<T> {
        self.depolarizer * self.retarder * self.diattenuator
    }
}

/// A generalized (two-point, complex 4×4) Mueller matrix (S1.7).
///
/// It acts on [`GeneralizedStokes`] parameters exactly as the pair of Jones matrices
/// `J(p₁)`, `J(p₂)` acts on the two-point CSD matrix: `C′ = J(p₁) C J(p₂)†` (S1.4–S1.6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeneralizedMueller<T: Real>(pub(crate) Matrix4<Complex<T>>);

impl<T: Real> GeneralizedMueller<T> {
    /// A generalized Mueller matrix from its entries.
    ///
    /// # Errors
    /// [`Error::NonFinite`] if an entry is NaN or infinite.
    pub fn from_matrix(m: Matrix4<Complex<T>>) -> Result<Self, Error> {
        ensure_finite(
            "generalized Mueller matrix entry",
            m.iter().flat_map(|z| [z.re, z.im]),
        )?;
        Ok(Self(m))
    }

    /// The entries as an nalgebra matrix.
    #[inline]
    #[must_use]
    pub fn matrix(&self) -> Matrix4<Complex<T>> {
        self.0
    }

    /// A classical Mueller matrix seen as a generalized one (real entries).
    #[must_use]
    pub fn from_mueller(m: &Mueller<T>) -> Self {
        Self(m.0.map(|x| Complex::new(x, T::zero())))
    }

    /// The generalized Mueller matrix of a pair of Jones matrices, in closed form (S1.7).
    ///
    /// # Formula
    /// ```text
    /// S1.7:  𝓜(p₁, p₂) = A_mül [J(p₂)* ⊗ J(p₁)] A_mül⁻¹,
    ///        equivalently  𝓜_kl = ½ tr(σ_k J₁ σ_l J₂†),   J₁ = J(p₁), J₂ = J(p₂)
    /// with σ₀ = I, σ₁ = diag(1, −1), σ₂ = [[0, 1], [1, 0]], σ₃ = [[0, −i], [i, 0]].
    /// For H_l = J₁ σ_l J₂†:  𝓜_0l = ½(H₁₁ + H₂₂),  𝓜_1l = ½(H₁₁ − H₂₂),
    ///                        𝓜_2l = ½(H₁₂ + H₂₁),  𝓜_3l = ½ i (H₁₂ − H₂₁).
    /// ```
    /// (From `S_k = tr(σ_k C)` and `C = ½ Σ_l S_l σ_l`.) `from_jones_pair(J, J)` is real and equals
    /// [`Mueller::from_jones`]. No 4×4 complex product is formed; the literal is the test oracle.
    ///
    /// # Examples
    /// ```
    /// use gmueller::{jones::JonesMatrix, mueller::{GeneralizedMueller, Mueller}};
    /// let j = JonesMatrix::<f64>::linear_retarder(0.3, 0.9);
    /// let g = GeneralizedMueller::from_jones_pair(&j, &j);
    /// let m = Mueller::from_jones(&j);
    /// assert!((g.matrix().map(|z| z.re) - m.matrix()).norm() < 1e-14);
    /// assert!(g.matrix().map(|z| z.im).norm() < 1e-14);
    /// ```
    #[must_use]
    pub fn from_jones_pair(j1: &JonesMatrix<T>, j2: &JonesMatrix<T>) -> Self {
        let a = &j1.0;
        let b_adj = j2.0.adjoint();
        let half = T::lit(0.5);
        let mut out = Matrix4::zeros();
        for l in 0..4 {
            let h = a * pauli::<T>(l) * b_adj;
            let (h11, h12, h21, h22) = (h[(0, 0)], h[(0, 1)], h[(1, 0)], h[(1, 1)]);
            let d = h12 - h21;
            out[(0, l)] = (h11 + h22) * half;
            out[(1, l)] = (h11 - h22) * half;
            out[(2, l)] = (h12 + h21) * half;
            out[(3, l)] = Complex::new(-d.im, d.re) * half;
        }
        Self(out)
    }
}

impl<T: Real> Mul for GeneralizedMueller<T> {
    type Output = GeneralizedMueller<T>;
    /// Composition: `(𝓜₂ * 𝓜₁)` is 𝓜₁ followed by 𝓜₂.
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        Self(self.0 * rhs.0)
    }
}

impl<T: Real> Mul<GeneralizedStokes<T>> for GeneralizedMueller<T> {
    type Output = GeneralizedStokes<T>;
    /// `S′ = 𝓜 S` (S1.6).
    #[inline]
    fn mul(self, rhs: GeneralizedStokes<T>) -> GeneralizedStokes<T> {
        GeneralizedStokes(self.0 * rhs.0)
    }
}
