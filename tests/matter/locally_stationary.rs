//! Locally-stationary matter, S2.7–S2.9, S2.14 and S2.19 (`gmueller::matter`), against
//! independent computations:
//! - the **generator**'s promise — draws whose covariance is the given autocorrelation — by
//!   Monte Carlo (and a 10 % wider autocorrelation is rejected);
//! - **S2.7–S2.8** by Monte Carlo estimates of `⟨𝓜(p₁, p₂)⟩ = ⟨A_mül [J(p₂)* ⊗ J(p₁)] A_mül⁻¹⟩`
//!   from realizations of Gaussian-window matter (Silverman's exact construction), against
//!   `m̄((p₁+p₂)/2) R(p₁−p₂)`; evaluating m̄ at p₁, or dropping the window's factor from R, fails;
//! - **S2.9** by Monte Carlo of `J(p₁) C_i J(p₂)†` (S1.4) over the same realizations;
//! - **S2.14**: the angular spectrum's closed forms against quadrature of `∫ e^{−iq·ζ} m̄`, and
//!   the cost of `M̃ ≈ M̃(0)` against it;
//! - **S2.19**: the pBSDF against the quadrature of the region average of m̄, and against the
//!   region average of Monte Carlo realizations.

use std::f64::consts::{PI, TAU};

use gmueller::jones::JonesMatrix;
use gmueller::matter::{
    BoxRegion, Fluctuation, GaussianWindow, JonesFieldGenerator, LocallyStationary, MeanField,
    StationaryField,
};
use gmueller::mueller::{GeneralizedMueller, Mueller};
use gmueller::stokes::GeneralizedStokes;
use gmueller::verify::oracle;
use gmueller::verify::quadrature::{cube_quad, gauss_legendre};
use gmueller::verify::rng::SplitMix64;
use gmueller::verify::stats::{Estimate, assert_within};
use nalgebra::{Matrix2, Matrix3, Matrix4, Vector2, Vector3, Vector4};
use num_complex::Complex;

type C = Complex<f64>;

// ------------------------------------------------------------------------- the generator

/// `R(ξ) = exp(−½ ξᵀΛ⁻¹ξ)`.
fn gaussian_r(lambda: Matrix2<f64>) -> impl Fn(&Vector2<f64>) -> f64 + Copy {
    let inv = lambda.try_inverse().unwrap();
    move |xi: &Vector2<f64>| (-0.5 * xi.dot(&(inv * xi))).exp()
}

/// The generator's covariance by Monte Carlo on a 32 × 24 grid (one axis not a power of two),
/// anisotropic rotated Gaussian R: `⟨u(p) u(p+ξ)*⟩ = R(ξ)` and `⟨u(p) u(p+ξ)⟩ = 0` for complex
/// draws, `⟨u(p) u(p+ξ)⟩ = R(ξ)` and independent pairs for real ones, within 4.5 SE (each draw
/// averaged over the grid); an R 10 % wider is rejected.
#[test]
fn stationary_field_has_the_autocorrelation() {
    let lambda = Matrix2::new(0.09, 0.03, 0.03, 0.04);
    let r = gaussian_r(lambda);
    let (nx, ny, d) = (32usize, 24usize, 0.1);
    let field = StationaryField::new([nx, ny], [d, d], r).unwrap();
    let clip = field.covariance_error();
    println!("covariance error {clip:e}");
    assert!(clip < 1e-6);
    let offsets = [
        (0i64, 0i64),
        (1, 0),
        (0, 1),
        (2, 1),
        (-3, 2),
        (1, -2),
        (4, 0),
    ];
    let shift = |j: usize, (a, b): (i64, i64)| -> usize {
        let (x, y) = ((j % nx) as i64, (j / nx) as i64);
        let (x, y) = (
            (x + a).rem_euclid(nx as i64) as usize,
            (y + b).rem_euclid(ny as i64) as usize,
        );
        x + nx * y
    };
    let mut rng = SplitMix64(3);
    let mut u = vec![C::new(0.0, 0.0); field.len()];
    let n = field.len() as f64;
    // [offset][re ⟨u u*⟩, im ⟨u u*⟩, re ⟨u u⟩, real-pair ⟨a a⟩, ⟨a b⟩]
    let mut est = vec![[Estimate::default(); 5]; offsets.len()];
    for draw in 0..3000 {
        let real = draw % 2 == 1;
        if real {
            field.sample_real_pair(&mut || rng.unit(), &mut u);
        } else {
            field.sample_complex(&mut || rng.unit(), &mut u);
        }
        for (o, e) in offsets.iter().zip(est.iter_mut()) {
            let (mut cc, mut pc, mut aa, mut ab) = (C::new(0.0, 0.0), C::new(0.0, 0.0), 0.0, 0.0);
            for j in 0..field.len() {
                let l = shift(j, *o);
                cc += u[j] * u[l].conj();
                pc += u[j] * u[l];
                aa += u[j].re * u[l].re;
                ab += u[j].re * u[l].im;
            }
            if real {
                e[3].push(aa / n);
                e[4].push(ab / n);
            } else {
                e[0].push(cc.re / n);
                e[1].push(cc.im / n);
                e[2].push(pc.re / n);
            }
        }
    }
    let wider = gaussian_r(lambda * 1.1);
    let mut z_wider: f64 = 0.0;
    for (o, e) in offsets.iter().zip(&est) {
        let xi = Vector2::new(o.0 as f64 * d, o.1 as f64 * d);
        let what = format!("offset {o:?}");
        assert_within(&format!("{what} Re⟨u u*⟩"), &e[0], r(&xi), 4.5, clip);
        assert_within(&format!("{what} Im⟨u u*⟩"), &e[1], 0.0, 4.5, 1e-12);
        assert_within(&format!("{what} Re⟨u u⟩"), &e[2], 0.0, 4.5, 1e-12);
        assert_within(&format!("{what} real ⟨a a⟩"), &e[3], r(&xi), 4.5, clip);
        assert_within(&format!("{what} real ⟨a b⟩"), &e[4], 0.0, 4.5, 1e-12);
        z_wider = z_wider.max(e[0].z(wider(&xi)).abs());
        println!(
            "{what}: R = {:.5}, MC {:.5} ± {:.5}; 10 % wider R at {:.1} SE",
            r(&xi),
            e[0].mean(),
            e[0].standard_error(),
            e[0].z(wider(&xi)).abs()
        );
    }
    assert!(z_wider > 10.0, "a 10 % wider R was not rejected: {z_wider}");
}

/// The generator's validation: an R whose circulant embedding is not positive (a box
/// correlation, whose transform has negative lobes), a zero grid, a bad spacing and R(0) ≤ 0
/// are rejected; a 3-D field has unit variance.
#[test]
fn stationary_field_rejects_what_it_cannot_draw() {
    let boxed = |xi: &Vector2<f64>| if xi.amax() < 0.35 { 1.0 } else { 0.0 };
    assert!(matches!(
        StationaryField::new([16, 16], [0.1, 0.1], boxed),
        Err(gmueller::Error::NotPositiveDefinite { .. })
    ));
    let r = gaussian_r(Matrix2::identity() * 0.01);
    assert!(StationaryField::new([0, 16], [0.1, 0.1], r).is_err());
    assert!(StationaryField::new([16, 16], [0.1, -0.1], r).is_err());
    assert!(StationaryField::new([16, 16], [0.1, f64::NAN], r).is_err());
    assert!(StationaryField::new([16, 16], [0.1, 0.1], |_: &Vector2<f64>| 0.0).is_err());
    let f3 = StationaryField::new([12, 12, 12], [0.1; 3], |xi: &Vector3<f64>| {
        (-0.5 * xi.norm_squared() / 0.01).exp()
    })
    .unwrap();
    let mut rng = SplitMix64(5);
    let mut u = vec![C::new(0.0, 0.0); f3.len()];
    let mut e = Estimate::default();
    for _ in 0..500 {
        f3.sample_complex(&mut || rng.unit(), &mut u);
        e.push(u.iter().map(|z| z.norm_sqr()).sum::<f64>() / u.len() as f64);
    }
    assert_within("3-D ⟨|u|²⟩", &e, 1.0, 4.5, 0.0);
}

// ----------------------------------------------------------------- Gaussian-window matter

const GRID: usize = 16;
const SPACING: f64 = 0.1;
const WINDOW: f64 = 0.15;
const ELL: f64 = 0.15;

fn r3(xi: &Vector3<f64>) -> f64 {
    (-0.5 * xi.norm_squared() / (ELL * ELL)).exp()
}

fn jones_terms() -> [(Vector3<f64>, JonesMatrix<f64>); 2] {
    let general = JonesMatrix::from_matrix(Matrix2::new(
        C::new(0.9, 0.1),
        C::new(0.2, -0.1),
        C::new(0.05, 0.3),
        C::new(0.4, 0.0),
    ))
    .unwrap();
    [
        (Vector3::new(0.15, 0.0, 0.0), general),
        (
            Vector3::new(-0.1, 0.1, 0.05),
            JonesMatrix::linear_retarder(0.3, 1.1),
        ),
    ]
}

/// Silverman's construction: `J(p) = Σ_t e^{−¼|p − c_t|²/w²} J_t u_t(p)`.
fn window_generator(fluctuation: Fluctuation) -> JonesFieldGenerator<3> {
    let field = StationaryField::new([GRID; 3], [SPACING; 3], r3).unwrap();
    let terms = jones_terms();
    JonesFieldGenerator::new(
        field,
        terms.len(),
        move |t, p| {
            let d = p - terms[t].0;
            terms[t].1.scaled(C::from(
                (-0.25 * d.norm_squared() / (WINDOW * WINDOW)).exp(),
            ))
        },
        fluctuation,
    )
    .unwrap()
}

/// The same matter as the crate describes it (S2.8): `m̄ = Σ_t g^W(ζ − c_t) Mueller(J_t)`,
/// `R(ξ) = R₃(ξ) e^{−⅛ ξᵀW⁻¹ξ}`.
fn window_matter()
-> LocallyStationary<Vec<GaussianWindow<f64, 3>>, impl Fn(&Vector3<f64>) -> f64 + Copy> {
    let windows = jones_terms()
        .iter()
        .map(|(c, j)| {
            GaussianWindow::new(
                *c,
                Matrix3::identity() * (WINDOW * WINDOW),
                Mueller::from_jones(j),
            )
            .unwrap()
        })
        .collect();
    LocallyStationary::new(windows, |xi: &Vector3<f64>| {
        r3(xi) * (-0.125 * xi.norm_squared() / (WINDOW * WINDOW)).exp()
    })
}

fn index(i: [usize; 3]) -> usize {
    i[0] + GRID * (i[1] + GRID * i[2])
}

/// Pairs of grid points: (ξ = 0), (ξ along x), (oblique ξ, off-centre ζ), (ζ between the
/// windows), (ζ on a window's flank).
fn pairs() -> [(usize, usize); 5] {
    [
        (index([8, 8, 8]), index([8, 8, 8])),
        (index([9, 8, 8]), index([7, 8, 8])),
        (index([10, 7, 9]), index([8, 8, 8])),
        (index([5, 9, 7]), index([6, 8, 8])),
        (index([11, 8, 8]), index([9, 8, 8])),
    ]
}

/// Monte Carlo of the 16 complex entries of `𝓜(p_j, p_l)` (S1.7, the crate's closed form) for
/// each pair: `[pair][entry][re, im]`.
fn mueller_estimates(
    generator: &mut JonesFieldGenerator<3>,
    realizations: usize,
    seed: u64,
) -> Vec<[[Estimate; 2]; 16]> {
    let mut rng = SplitMix64(seed);
    let mut j = vec![JonesMatrix::identity(); generator.len()];
    let mut est = vec![[[Estimate::default(); 2]; 16]; pairs().len()];
    for _ in 0..realizations {
        generator.sample(&mut || rng.unit(), &mut j);
        for ((a, b), e) in pairs().iter().zip(est.iter_mut()) {
            let m = GeneralizedMueller::from_jones_pair(&j[*a], &j[*b]).matrix();
            for (i, z) in m.iter().enumerate() {
                e[i][0].push(z.re);
                e[i][1].push(z.im);
            }
        }
    }
    est
}

fn max_z(e: &[[Estimate; 2]; 16], expected: &Matrix4<f64>) -> f64 {
    expected
        .iter()
        .enumerate()
        .map(|(i, x)| e[i][0].z(*x).abs().max(e[i][1].z(0.0).abs()))
        .fold(0.0, f64::max)
}

/// S2.7–S2.8 by Monte Carlo: 6000 realizations of two overlapping Gaussian windows of matter
/// (a general complex Jones matrix and a retarder) times real Gaussian fluctuations in a 3-D
/// box, and 3000 with complex ones; `⟨𝓜(p₁, p₂)⟩` at five pairs agrees with
/// `m̄((p₁+p₂)/2) R(p₁−p₂)` within 4.5 SE in all 32 real parts, and equals the generator's exact
/// mean to rounding. Evaluating m̄ at p₁ instead of the midpoint, or R without the window's
/// `e^{−⅛ξᵀW⁻¹ξ}`, misses by many SE.
#[test]
fn s2_8_locally_stationary_autocorrelation_by_monte_carlo() {
    let matter = window_matter();
    for (fluctuation, realizations, seed) in [
        (Fluctuation::Real, 6000, 41),
        (Fluctuation::Complex, 3000, 42),
    ] {
        let mut generator = window_generator(fluctuation);
        let est = mueller_estimates(&mut generator, realizations, seed);
        let (mut z_mid, mut z_p1, mut z_nowindow): (f64, f64, f64) = (0.0, 0.0, 0.0);
        for ((a, b), e) in pairs().iter().zip(&est) {
            let (p1, p2) = (
                generator.field().position(*a),
                generator.field().position(*b),
            );
            let expected = matter.autocorrelation(&p1, &p2).matrix();
            let exact = generator.expected_mueller(*a, *b).matrix();
            assert!(
                (exact.map(|z| z.re) - expected).amax() < 1e-14
                    && exact.map(|z| z.im).amax() < 1e-14
            );
            for (i, x) in expected.iter().enumerate() {
                assert_within(
                    &format!("{fluctuation:?} pair ({a}, {b}) entry {i} re"),
                    &e[i][0],
                    *x,
                    4.5,
                    1e-14,
                );
                assert_within(
                    &format!("{fluctuation:?} pair ({a}, {b}) entry {i} im"),
                    &e[i][1],
                    0.0,
                    4.5,
                    1e-14,
                );
            }
            z_mid = z_mid.max(max_z(e, &expected));
            let at_p1 = matter.mean().mueller(&p1).matrix() * matter.correlation()(&(p1 - p2));
            z_p1 = z_p1.max(max_z(e, &at_p1));
            let no_window = matter.mean().mueller(&((p1 + p2) * 0.5)).matrix() * r3(&(p1 - p2));
            z_nowindow = z_nowindow.max(max_z(e, &no_window));
        }
        println!(
            "S2.8 ({fluctuation:?}, {realizations}): max |z| = {z_mid:.2}; m̄ at p₁: {z_p1:.1}; R without the window factor: {z_nowindow:.1}"
        );
        assert!(z_p1 > 8.0 && z_nowindow > 5.0, "{z_p1} {z_nowindow}");
    }
}

/// S2.7 for a mean Jones field that is *not* a window: a diattenuator whose axis turns along x
/// (`θ = κx`) in a Gaussian window. The generator's exact mean `⟨𝓜⟩ = c(ξ) 𝓜[J̄(p₁), J̄(p₂)]`
/// (S2.7 of S1.7) is checked by Monte Carlo within 4.5 SE; S2.8's factorisation
/// `m̄((p₁+p₂)/2) R(ξ)` then differs from it by `O(κ|ξ|)` (the first-order term of the turning
/// axis is antisymmetric in p₁ ↔ p₂, hence complex): the printed form is exact for Gaussian
/// windows and a local approximation otherwise.
#[test]
fn s2_7_slowly_varying_mean_factorises_to_first_order() {
    let field = StationaryField::new([GRID; 3], [SPACING; 3], r3).unwrap();
    let (kappa, w) = (1.5, 0.25);
    let jbar = move |p: &Vector3<f64>| {
        JonesMatrix::diattenuator(1.0, 0.3, kappa * p.x)
            .unwrap()
            .scaled(C::from((-0.25 * p.norm_squared() / w).exp()))
    };
    let mut generator =
        JonesFieldGenerator::new(field, 1, move |_, p| jbar(p), Fluctuation::Complex).unwrap();
    let est = mueller_estimates(&mut generator, 3000, 43);
    let mut rows = Vec::new();
    for ((a, b), e) in pairs().iter().zip(&est) {
        let exact = generator.expected_mueller(*a, *b).matrix();
        for (i, z) in exact.iter().enumerate() {
            assert_within(
                &format!("S2.7 pair ({a}, {b}) entry {i} re"),
                &e[i][0],
                z.re,
                4.5,
                1e-14,
            );
            assert_within(
                &format!("S2.7 pair ({a}, {b}) entry {i} im"),
                &e[i][1],
                z.im,
                4.5,
                1e-14,
            );
        }
        let (p1, p2) = (
            generator.field().position(*a),
            generator.field().position(*b),
        );
        let xi = p1 - p2;
        // S2.8 with the window's exact factor, so that only the turning axis is approximated.
        let r = r3(&xi) * (-0.125 * xi.norm_squared() / w).exp();
        let factorised = Mueller::from_jones(&jbar(&((p1 + p2) * 0.5))).matrix() * r;
        let scale = exact.map(|z| z.norm()).amax();
        let diff = (exact - factorised.map(C::from)).map(|z| z.norm()).amax() / scale;
        let kx = kappa * xi.x.abs();
        rows.push((kx, diff));
        assert!(diff <= 1.5 * kx + 1e-14, "κ|ξ_x| = {kx}: {diff}");
    }
    println!("S2.7 vs S2.8 for a turning diattenuator, (κ|ξ_x|, relative difference): {rows:.4?}");
    assert!(
        rows.iter().any(|(kx, d)| *kx > 0.2 && *d > 0.05 * kx),
        "{rows:?}"
    );
}

/// S2.9 by Monte Carlo: for each realization `C′ = J(p₁) C_i(p₁ − p₂) J(p₂)†` (S1.4, Jones
/// matrices on the two-point CSD) and its `A_mül vec(C′)`, averaged, against
/// `LocallyStationary::interact` = `m̄ R S_i`, within 4.5 SE. The incident light is a
/// partially polarized Gaussian Schell-model field travelling along an oblique k̂.
#[test]
fn s2_9_interaction_by_monte_carlo() {
    let matter = window_matter();
    let mut generator = window_generator(Fluctuation::Real);
    let k = TAU / 0.5;
    let travel = Vector3::new(0.3, -0.2, 0.9).normalize();
    let c0 = Matrix2::new(
        C::new(1.0, 0.0),
        C::new(0.3, 0.4),
        C::new(0.3, -0.4),
        C::new(0.6, 0.0),
    );
    let csd = |xi: &Vector3<f64>| {
        let (s, c) = (k * travel.dot(xi)).sin_cos();
        c0 * (C::new(c, s) * (-0.5 * xi.norm_squared() / 0.04).exp())
    };
    let gsp =
        |m: &Matrix2<C>| oracle::a_mul() * Vector4::new(m[(0, 0)], m[(1, 0)], m[(0, 1)], m[(1, 1)]);
    let mut rng = SplitMix64(44);
    let mut j = vec![JonesMatrix::identity(); generator.len()];
    let mut est = vec![[[Estimate::default(); 2]; 4]; pairs().len()];
    for _ in 0..4000 {
        generator.sample(&mut || rng.unit(), &mut j);
        for ((a, b), e) in pairs().iter().zip(est.iter_mut()) {
            let xi = generator.field().position(*a) - generator.field().position(*b);
            let out = j[*a].matrix() * csd(&xi) * j[*b].matrix().adjoint();
            let s = gsp(&out);
            for i in 0..4 {
                e[i][0].push(s[i].re);
                e[i][1].push(s[i].im);
            }
        }
    }
    for ((a, b), e) in pairs().iter().zip(&est) {
        let (p1, p2) = (
            generator.field().position(*a),
            generator.field().position(*b),
        );
        let s_i = GeneralizedStokes::new(gsp(&csd(&(p1 - p2)))).unwrap();
        let expected = matter.interact(&p1, &p2, &s_i).vector();
        for i in 0..4 {
            assert_within(
                &format!("S2.9 pair ({a}, {b}) S{i} re"),
                &e[i][0],
                expected[i].re,
                4.5,
                1e-14,
            );
            assert_within(
                &format!("S2.9 pair ({a}, {b}) S{i} im"),
                &e[i][1],
                expected[i].im,
                4.5,
                1e-14,
            );
        }
    }
}

// ------------------------------------------------------------------------ S2.14, S2.19

/// Tensor Gauss–Legendre quadrature of `f` over the box `[lo, hi]` (per axis) with `n` nodes.
fn gl_box(f: impl Fn(&Vector3<f64>) -> C, lo: Vector3<f64>, hi: Vector3<f64>, n: usize) -> C {
    let rule = gauss_legendre(n);
    let mut sum = C::new(0.0, 0.0);
    let half = (hi - lo) * 0.5;
    let mid = (hi + lo) * 0.5;
    for (xa, wa) in rule.nodes.iter().zip(&rule.weights) {
        for (xb, wb) in rule.nodes.iter().zip(&rule.weights) {
            for (xc, wc) in rule.nodes.iter().zip(&rule.weights) {
                let p = mid + half.component_mul(&Vector3::new(*xa, *xb, *xc));
                sum += f(&p) * (wa * wb * wc);
            }
        }
    }
    sum * half.product()
}

/// S2.14 for a Gaussian window (anisotropic W, off-centre) and a box (off-centre): the closed
/// form of `M̃(q) = ∫ e^{−iq·ζ} m̄(ζ) d³ζ` against quadrature (trapezoid over ±9σ; Gauss–Legendre
/// on the box), to 1e-10, at `q = k(r̂₁ − r̂₂)` for several δ and one general q; every entry is
/// that scalar times M₀. With `e^{+iq·c}` the transforms miss.
#[test]
fn s2_14_angular_spectrum_matches_quadrature() {
    let m0 = Mueller::from_jones(&JonesMatrix::linear_retarder(0.4, 0.9)).matrix();
    let w = Matrix3::new(0.16, 0.05, 0.0, 0.05, 0.09, 0.02, 0.0, 0.02, 0.25);
    let c = Vector3::new(0.2, -0.1, 0.3);
    let gauss = GaussianWindow::new(c, w, Mueller::from_matrix(m0).unwrap()).unwrap();
    let w_inv = w.try_inverse().unwrap();
    let h = Vector3::new(0.5, 0.8, 0.3);
    let boxed = BoxRegion::new(c, h, Mueller::from_matrix(m0).unwrap()).unwrap();
    let k = TAU / 0.5;
    let r_hat = Vector3::new(0.3, 0.2, 0.93).normalize();
    let side = r_hat.cross(&Vector3::z()).normalize();
    let mut qs: Vec<Vector3<f64>> = [0.0, 0.01, 0.1, 0.3]
        .iter()
        .map(|d| {
            (r_hat + side * (d * 0.5)).normalize() * k - (r_hat - side * (d * 0.5)).normalize() * k
        })
        .collect();
    qs.push(Vector3::new(1.3, -2.1, 0.7));
    let mut z_sign: f64 = 0.0;
    for q in &qs {
        let phase = |p: &Vector3<f64>| C::new(0.0, -q.dot(p)).exp();
        // Gaussian: trapezoid on a cube of ±9 times the largest σ around c.
        let quad_g = cube_quad::<3>(
            |u| phase(&(u + c)) * (-0.5 * u.dot(&(w_inv * u))).exp(),
            4.5,
            121,
        );
        let quad_b = gl_box(|p| phase(p), c - h, c + h, 32);
        for (name, field, quad) in [
            ("Gaussian", &gauss as &dyn MeanField<f64, 3>, quad_g),
            ("box", &boxed as &dyn MeanField<f64, 3>, quad_b),
        ] {
            let m = field.angular_spectrum(q);
            let scalar = m[(0, 0)] / m0[(0, 0)];
            let err = (scalar - quad).norm() / quad.norm().max(1e-300);
            assert!(err < 1e-10, "{name} q = {q:?}: {scalar} vs {quad}: {err:e}");
            assert!(
                (m - m0.map(|x| scalar * x)).map(|z| z.norm()).amax()
                    < 1e-14 * m.map(|z| z.norm()).amax()
            );
            // The opposite shift sign: e^{+iq·c}.
            let flipped = scalar * C::new(0.0, 2.0 * q.dot(&c)).exp();
            z_sign = z_sign.max((flipped - quad).norm() / quad.norm());
        }
    }
    println!("S2.14 with e^{{+iq·c}}: largest relative miss {z_sign:.3}");
    assert!(z_sign > 0.1);
}

/// The cost of S2.14's approximation `M̃(k r̂₁ − k r̂₂) ≈ M̃(0)`, against quadrature of the
/// transform: for a Gaussian window of width s the relative error is `1 − e^{−½ qᵀWq}`, for a
/// box `1 − Π sinc(qₐhₐ)`; both ≈ `½ (k δ s_eff)²` for small δ (the region's diffraction angle
/// `1/(k s)` is the scale). Printed as a table; asserted: the quadrature's error equals the
/// formula, below 1 % where `kδs ≤ 0.1`, above 30 % where `kδs ≥ 1`.
#[test]
fn s2_14_approximation_cost_against_quadrature() {
    let s = 1.0;
    let gauss = GaussianWindow::new(
        Vector3::zeros(),
        Matrix3::identity() * (s * s),
        Mueller::identity(),
    )
    .unwrap();
    let half = s * 3f64.sqrt(); // the box of the same variance per axis: h²/3 = s²
    let boxed =
        BoxRegion::new(Vector3::zeros(), Vector3::repeat(half), Mueller::identity()).unwrap();
    let k = TAU / 0.5;
    let r_hat = Vector3::new(0.2, -0.1, 0.97).normalize();
    let side = r_hat.cross(&Vector3::z()).normalize();
    println!("   kδs   Gaussian (quadrature, formula)   box (quadrature, formula)   ½(kδs)²");
    for kds in [0.01, 0.03, 0.1, 0.3, 1.0, 3.0] {
        let delta = kds / (k * s);
        let q = (r_hat + side * (0.5 * delta).tan()).normalize() * k
            - (r_hat - side * (0.5 * delta).tan()).normalize() * k;
        let phase = |p: &Vector3<f64>| C::new(0.0, -q.dot(p)).exp();
        let quad_g = cube_quad::<3>(
            |u| phase(u) * (-0.5 * u.norm_squared() / (s * s)).exp(),
            9.0 * s,
            121,
        );
        let quad_b = gl_box(
            |p| phase(p),
            -Vector3::repeat(half),
            Vector3::repeat(half),
            40,
        );
        let zero_g = gauss.angular_spectrum(&Vector3::zeros())[(0, 0)];
        let zero_b = boxed.angular_spectrum(&Vector3::zeros())[(0, 0)];
        let cost_g = (zero_g - quad_g).norm() / quad_g.norm();
        let cost_b = (zero_b - quad_b).norm() / quad_b.norm();
        let formula_g = (0.5 * q.norm_squared() * s * s).exp() - 1.0;
        let sinc = |x: f64| if x == 0.0 { 1.0 } else { x.sin() / x };
        let prod: f64 = q.iter().map(|qa| sinc(qa * half)).product();
        let formula_b = (1.0 / prod - 1.0).abs();
        println!(
            "{kds:6.2}   {cost_g:10.3e} {formula_g:10.3e}          {cost_b:10.3e} {formula_b:10.3e}   {:.3e}",
            0.5 * kds * kds
        );
        assert!(
            (cost_g - formula_g).abs() < 1e-9 * formula_g.max(1.0),
            "{cost_g} {formula_g}"
        );
        assert!(
            (cost_b - formula_b).abs() < 1e-9 * formula_b.max(1.0),
            "{cost_b} {formula_b}"
        );
        if kds <= 0.1 {
            assert!(cost_g < 0.01 && cost_b < 0.01);
        }
        if kds >= 1.0 {
            assert!(cost_g > 0.3 && cost_b > 0.3);
        }
    }
}

/// S2.19: the pBSDF of a mixture of Gaussian windows (a polarizer, a retarder, a depolarizer,
/// overlapping) is the region average `∫ m̄ / ∫ w` by trapezoid quadrature over a cube (1e-10),
/// and the region average of the local Mueller matrices `Mueller(J(p))` of 400 realizations
/// (grid sum, `R(0) = 1`) agrees with it within 4.5 SE.
#[test]
fn s2_19_pbsdf_is_the_region_average() {
    let depolarizer =
        Mueller::from_matrix(Matrix4::from_diagonal(&Vector4::new(1.0, 0.2, 0.2, 0.1))).unwrap();
    let windows = vec![
        GaussianWindow::new(
            Vector3::new(0.2, 0.0, 0.0),
            Matrix3::identity() * 0.04,
            Mueller::from_jones(&JonesMatrix::linear_polarizer(0.3)),
        )
        .unwrap(),
        GaussianWindow::new(
            Vector3::new(-0.1, 0.15, 0.0),
            Matrix3::new(0.02, 0.005, 0.0, 0.005, 0.03, 0.0, 0.0, 0.0, 0.05),
            Mueller::from_jones(&JonesMatrix::linear_retarder(1.0, PI / 2.0)),
        )
        .unwrap(),
        GaussianWindow::new(
            Vector3::new(0.0, -0.1, 0.1),
            Matrix3::identity() * 0.03,
            depolarizer,
        )
        .unwrap(),
    ];
    let pbsdf = windows.pbsdf().matrix();
    // Trapezoid over the cube [−1.6, 1.6]³ (7σ beyond every window), all entries at once.
    let (n, half) = (81, 1.6);
    let step = 2.0 * half / (n - 1) as f64;
    let (mut weight, mut integral) = (0.0, Matrix4::zeros());
    for i in 0..n {
        for j in 0..n {
            for l in 0..n {
                let p = Vector3::new(i as f64, j as f64, l as f64) * step - Vector3::repeat(half);
                weight += windows
                    .iter()
                    .map(|w| w.window().value(&(p - w.center())))
                    .sum::<f64>();
                integral += windows.mueller(&p).matrix();
            }
        }
    }
    let dv = step.powi(3);
    let weight = weight * dv;
    assert!(
        (weight - windows.measure()).abs() < 1e-10 * weight,
        "{weight} {}",
        windows.measure()
    );
    let average = integral * dv / weight;
    assert!((average - pbsdf).amax() < 1e-10, "{average} vs {pbsdf}");
    // The same from realizations: depolarizer = Σ of Jones–Muellers? Use the two Jones windows
    // of `jones_terms` instead, whose mean field the generator realizes exactly.
    let matter = window_matter();
    let expected = matter.mean().pbsdf().matrix();
    let mut generator = window_generator(Fluctuation::Real);
    let dv = SPACING.powi(3);
    let mut rng = SplitMix64(45);
    let mut j = vec![JonesMatrix::identity(); generator.len()];
    let mut est = [[Estimate::default(); 4]; 4];
    for _ in 0..400 {
        generator.sample(&mut || rng.unit(), &mut j);
        let sum: Matrix4<f64> = j.iter().map(|m| Mueller::from_jones(m).matrix()).sum();
        let avg = sum * dv / matter.mean().measure();
        for r in 0..4 {
            for c in 0..4 {
                est[r][c].push(avg[(r, c)]);
            }
        }
    }
    for r in 0..4 {
        for c in 0..4 {
            assert_within(
                &format!("S2.19 MC ({r}, {c})"),
                &est[r][c],
                expected[(r, c)],
                4.5,
                1e-12,
            );
        }
    }
}
