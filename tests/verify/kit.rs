//! The verification kit (`gmueller::verify`, feature `verify`) tested on its own: every object a
//! strategy generates passes the crate's validation, the strategies reach the boundaries they
//! promise (coverage counted over a fixed-seed sample and asserted), and each assertion rejects a
//! deliberately wrong input.

use gmueller::gaussian::Gaussian;
use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::stokes::Stokes;
use gmueller::verify::{check, strategy, tol};
use nalgebra::{Matrix2, Matrix4, Vector4};
use num_complex::Complex;

use gmueller::verify::strategy::sample;

const N: usize = 2000;

#[test]
fn stokes_vectors_are_valid_and_reach_both_ends_of_the_polarization() {
    let v = sample(strategy::stokes_vector(), N);
    let mut near_unpolarized = 0;
    let mut near_full = 0;
    for s in &v {
        Stokes::new(s[0], s[1], s[2], s[3]).expect("the crate accepts it");
        check::assert_valid_stokes("stokes_vector", *s, tol::F64);
        let dop = s.fixed_rows::<3>(1).norm() / s[0];
        near_unpolarized += usize::from(dop < 0.01);
        near_full += usize::from(dop > 0.99);
    }
    // DoP is uniform in [0, 1]: about 1 % of the cases at each end (asserted > 0.25 %, so
    // that a fresh-seed search fails by chance with probability < 1e-4).
    assert!(
        near_unpolarized * 400 > N && near_full * 400 > N,
        "DoP < 0.01: {near_unpolarized}/{N}, > 0.99: {near_full}/{N}"
    );
}

#[test]
fn stokes_on_the_cone_are_fully_polarized() {
    for s in sample(strategy::stokes_on_cone(), N) {
        Stokes::new(s[0], s[1], s[2], s[3]).expect("the crate accepts it");
        check::assert_valid_stokes("stokes_on_cone", s, tol::F64);
        let dop = s.fixed_rows::<3>(1).norm() / s[0];
        tol::assert_close("DoP on the cone", dop, 1.0, tol::F64);
    }
}

#[test]
fn unitary_jones_matrices_are_unitary_and_lossless() {
    for j in sample(strategy::unitary_jones(), N) {
        let jj = j.adjoint() * j;
        tol::assert_complex_close(
            "J†J",
            jj.iter().copied(),
            Matrix2::<Complex<f64>>::identity().iter().copied(),
            tol::F64,
        );
        let m = Mueller::from_jones(&JonesMatrix::from_matrix(j).unwrap()).matrix();
        check::assert_realizable("unitary", &m, 1e-12);
        // Lossless and non-depolarizing: M is 1 ⊕ a rotation of the Poincaré sphere.
        tol::assert_close("M00", m[(0, 0)], 1.0, tol::F64);
        let r = m.fixed_view::<3, 3>(1, 1).into_owned();
        tol::assert_all_close(
            "RᵀR",
            (r.transpose() * r).iter().copied(),
            nalgebra::Matrix3::<f64>::identity().iter().copied(),
            tol::F64,
        );
    }
}

#[test]
fn hermitian_jones_matrices_are_hermitian() {
    for j in sample(strategy::hermitian_jones(2.0), N) {
        tol::assert_complex_close(
            "J − J†",
            (j - j.adjoint()).iter().copied(),
            [Complex::new(0.0, 0.0); 4],
            tol::Tol::new(0.0, 0.0),
        );
    }
}

#[test]
fn realizable_muellers_pass_cloude_and_reach_the_boundary() {
    let v = sample(strategy::realizable_mueller(4), N);
    let mut rank_one = 0;
    let mut depolarizing = 0;
    for m in &v {
        check::assert_realizable("realizable_mueller", m, 1e-10);
        let l = Mueller::from_matrix(*m).unwrap().coherency_eigenvalues();
        // Rank 1 (one Jones matrix, on the boundary): the second eigenvalue is ~0.
        if l[1] <= 1e-12 * l[0] {
            rank_one += 1;
        } else {
            depolarizing += 1;
        }
        // And it maps valid Stokes vectors to valid ones.
        let s = Vector4::new(1.0, 0.6, -0.0, 0.8);
        check::assert_valid_stokes("M S", m * s, tol::Tol::new(1e-12, 1e-12));
    }
    // One to four terms, uniformly: about a quarter are single Jones matrices.
    assert!(
        rank_one * 10 > N && depolarizing * 10 > N,
        "rank 1: {rank_one}/{N}, depolarizing: {depolarizing}/{N}"
    );
}

#[test]
fn conditioned_shapes_are_positive_definite_and_reach_their_condition() {
    let max = 1e4;
    let v = sample(strategy::spd2_conditioned(0.1, 10.0, max), N);
    let (mut ill, mut round) = (0, 0);
    for m in &v {
        Gaussian::<f64, 2>::new(*m).expect("positive definite");
        let e = m.symmetric_eigenvalues();
        let cond = e.max() / e.min();
        assert!(
            (1.0 - 1e-9..=max * (1.0 + 1e-9)).contains(&cond),
            "condition {cond} of {m}"
        );
        ill += usize::from(cond > 0.5 * max);
        round += usize::from(cond < 2.0);
    }
    // Log-uniform in [1, 1e4]: ln 2 / ln 1e4 ≈ 7.5 % at each end.
    assert!(
        ill * 20 > N && round * 20 > N,
        "condition > max/2: {ill}/{N}, < 2: {round}/{N}"
    );
}

#[test]
fn unit_vectors_have_unit_length() {
    for u in sample(strategy::unit_vector3(), N) {
        tol::assert_close("|u|", u.norm(), 1.0, tol::F64);
    }
}

#[test]
fn the_assertions_reject_wrong_inputs() {
    let fails = |f: &(dyn Fn() + std::panic::RefUnwindSafe)| std::panic::catch_unwind(f).is_err();
    // Outside the cone by 1e-9 relative: rejected at the f64 tolerance, accepted at 1e-6.
    let s = Vector4::new(1.0, 1.0 + 1e-9, 0.0, 0.0);
    assert!(fails(&|| check::assert_valid_stokes(
        "outside",
        s,
        tol::F64
    )));
    check::assert_valid_stokes("outside, loose", s, tol::Tol::new(0.0, 1e-6));
    assert!(fails(&|| check::assert_valid_stokes(
        "negative",
        Vector4::new(-1e-3, 0.0, 0.0, 0.0),
        tol::F64
    )));
    // At extreme scales with a purely relative tolerance (the squares of 1e±300 would under-
    // or overflow): on the cone accepted, 1e-9 outside rejected.
    let rel = tol::Tol::new(0.0, 1e-12);
    for scale in [1e-300, 1e300] {
        check::assert_valid_stokes("on the cone", Vector4::new(1.0, 0.6, 0.0, 0.8) * scale, rel);
        let out = Vector4::new(1.0, 0.6 * (1.0 + 1e-9), 0.0, 0.8 * (1.0 + 1e-9)) * scale;
        assert!(
            fails(&|| check::assert_valid_stokes("outside", out, rel)),
            "scale {scale:e}"
        );
    }
    // The handedness flip is not realizable; the identity is.
    let flip = Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, 1.0, -1.0));
    assert!(fails(&|| check::assert_realizable("flip", &flip, 1e-12)));
    check::assert_realizable("identity", &Matrix4::identity(), 1e-12);
    // Mueller equality on the matrix's own scale.
    let a = Matrix4::from_fn(|r, c| (r * 4 + c) as f64);
    let mut b = a;
    b[(3, 0)] += 1e-9 * a.amax();
    check::assert_mueller_close("close", &a, &b, tol::Tol::new(0.0, 1e-8));
    assert!(fails(&|| check::assert_mueller_close(
        "apart",
        &a,
        &b,
        tol::Tol::new(0.0, 1e-10)
    )));
    assert!(fails(&|| tol::assert_close("apart", 1.0, 1.1, tol::F64)));
}

#[test]
fn the_s1_7_oracle_agrees_with_the_closed_form_and_rejects_the_row_stacked_one() {
    use gmueller::verify::oracle;
    let fails = |f: &(dyn Fn() + std::panic::RefUnwindSafe)| std::panic::catch_unwind(f).is_err();
    let v = sample(strategy::complex_matrix2(1.0), 500);
    let mut rejected = 0;
    for j in &v {
        let closed = Mueller::from_jones(&JonesMatrix::from_matrix(*j).unwrap()).matrix();
        let literal = oracle::mueller_literal(j);
        check::assert_mueller_close("S1.7", &literal, &closed, tol::F64);
        // The row-stacked form A (J ⊗ J*) A⁻¹ (the wrong vec convention for S1.1).
        let wrong = (oracle::a_mul() * oracle::kron(j, &j.map(|z| z.conj())) * oracle::a_mul_inv())
            .map(|z| z.re);
        if fails(&|| check::assert_mueller_close("row-stacked", &wrong, &closed, tol::F64)) {
            rejected += 1;
        }
    }
    // A deliberately wrong formula: every general draw must expose it.
    assert_eq!(
        rejected,
        v.len(),
        "row-stacked form accepted in {} cases",
        v.len() - rejected
    );
}

#[test]
fn packets_are_realizable_and_reach_the_bochner_bound() {
    use gmueller::frame::Frame;
    use gmueller::packet::{CoherenceShape, WavePacket};
    let frame = Frame::new(
        nalgebra::Vector3::x(),
        nalgebra::Vector3::y(),
        nalgebra::Vector3::z(),
    )
    .unwrap();
    let build = |(s, tx, ty): (Vector4<f64>, Matrix2<f64>, Matrix2<f64>)| {
        WavePacket::new(
            Stokes::new(s[0], s[1], s[2], s[3]).unwrap(),
            CoherenceShape::new(tx).unwrap(),
            CoherenceShape::new(ty).unwrap(),
            frame,
            0.5,
        )
        .unwrap_or_else(|e| panic!("{e}: S {s:?}, Θx {tx}, Θy {ty}"));
        strategy::mu_squared(&s) / strategy::bochner_bound(&tx, &ty)
    };
    // Near the bound: every packet within 1 % of it, and realizable.
    let near: Vec<f64> = sample(strategy::packet_parts(0.01), N)
        .into_iter()
        .map(build)
        .collect();
    assert!(
        near.iter()
            .all(|r| (0.99 - 1e-12..=1.0 + 1e-12).contains(r))
    );
    // Across the range: realizable, ~1 % within 1 % of the bound, ~half below half of it.
    let all: Vec<f64> = sample(strategy::packet_parts(1.0), N)
        .into_iter()
        .map(build)
        .collect();
    let at_bound = all.iter().filter(|r| **r >= 0.99).count();
    let low = all.iter().filter(|r| **r < 0.5).count();
    println!("packets within 1 % of the Bochner bound: {at_bound}/{N}; below half: {low}/{N}");
    assert!(
        at_bound * 400 > N && low * 3 > N,
        "{at_bound}, {low} of {N}"
    );
}

#[test]
fn frames_are_right_handed_and_orthonormal() {
    for f in sample(strategy::frame(), N) {
        let (x, y, k) = (f.x(), f.y(), f.k());
        for (what, v) in [("|x|", x.norm()), ("|y|", y.norm()), ("|k|", k.norm())] {
            tol::assert_close(what, v, 1.0, tol::F64);
        }
        tol::assert_all_close(
            "x × y = k",
            x.cross(&y).iter().copied(),
            k.iter().copied(),
            tol::F64,
        );
    }
}

#[test]
fn geometries_reach_normal_grazing_specular_and_back_scatter() {
    use gmueller::frame::Frame;
    use gmueller::verify::strategy::ExitKind;
    let v = sample(strategy::incidence_and_exit(), N);
    let grazing = 89.99f64.to_radians().cos();
    let (mut normal, mut graze, mut kinds) = (0, 0, [0usize; 4]);
    for (travel, exit, kind) in &v {
        tol::assert_close("|travel|", travel.norm(), 1.0, tol::F64);
        tol::assert_close("|exit|", exit.norm(), 1.0, tol::F64);
        assert!(travel.z < 0.0 && exit.z > 0.0, "{travel:?} → {exit:?}");
        // The crate builds the s/p frame of every incidence, normal incidence included.
        Frame::sp(*travel, nalgebra::Vector3::z()).expect("an s/p frame");
        normal += usize::from(travel.z == -1.0);
        graze += usize::from((travel.z + grazing).abs() < 1e-15);
        let k = match kind {
            ExitKind::Specular => {
                let mirror = travel - 2.0 * travel.z * nalgebra::Vector3::z();
                tol::assert_all_close(
                    "specular",
                    exit.iter().copied(),
                    mirror.iter().copied(),
                    tol::F64,
                );
                0
            }
            ExitKind::BackScatter => {
                tol::assert_all_close(
                    "back-scatter",
                    exit.iter().copied(),
                    (-travel).iter().copied(),
                    tol::F64,
                );
                1
            }
            ExitKind::Grazing => {
                tol::assert_close("grazing exit", exit.z, grazing, tol::F64);
                2
            }
            ExitKind::Any => 3,
        };
        kinds[k] += 1;
    }
    // 1/8 of the incidences exactly normal, 1/8 exactly grazing; a quarter of each exit kind.
    assert!(
        normal * 16 > N && graze * 16 > N,
        "normal {normal}, grazing {graze} of {N}"
    );
    assert!(
        kinds.iter().all(|k| k * 8 > N),
        "exit kinds {kinds:?} of {N}"
    );
}

#[test]
fn the_quadratures_reproduce_known_integrals() {
    use gmueller::verify::quadrature::{
        Hemisphere, cube_quad, gauss_legendre, hemisphere_integral, integrate,
    };
    // n-point Gauss–Legendre is exact for degree ≤ 2n − 1: ∫ x^k over [−1, 1].
    let r = gauss_legendre(12);
    for k in 0..24 {
        let got: f64 = r
            .nodes
            .iter()
            .zip(&r.weights)
            .map(|(x, w)| w * x.powi(k))
            .sum();
        let want = if k % 2 == 0 {
            2.0 / (k as f64 + 1.0)
        } else {
            0.0
        };
        tol::assert_close(&format!("∫ x^{k}"), got, want, tol::Tol::new(1e-14, 1e-14));
    }
    // Adaptive: ∫₀^π sin = 2, and a narrow peak ∫ e^{−x²/2σ²} = σ√(2π) on [−1, 1], σ = 1e-3.
    tol::assert_close(
        "∫ sin",
        integrate(&mut f64::sin, 0.0, std::f64::consts::PI, 4, 1e-13),
        2.0,
        tol::F64,
    );
    let s = 1e-3;
    // On one panel both rules miss the peak between their nodes, agree on ~0 and accept it
    // (documented at `integrate`): the panels must resolve the integrand's features.
    let mut f = |x: f64| (-0.5 * (x / s).powi(2)).exp();
    assert!(integrate(&mut f, -1.0, 1.0, 1, 1e-14) < 1e-6);
    let peak = integrate(&mut f, -1.0, 1.0, 101, 1e-14);
    tol::assert_close(
        "narrow peak",
        peak,
        s * std::f64::consts::TAU.sqrt(),
        tol::Tol::new(0.0, 1e-10),
    );
    // The hemisphere in exit-tangent coordinates: ∫ d²r_t = π, ∫ cos θ_o d²r_t = 2π/3, either side.
    for side in [Hemisphere::Above, Hemisphere::Below] {
        let [area, cz] =
            hemisphere_integral(nalgebra::Vector2::new(0.3, -0.2), 64, side, &mut |r| {
                [1.0, r.z.abs()]
            });
        tol::assert_close(
            "∫ d²r_t",
            area,
            std::f64::consts::PI,
            tol::Tol::new(0.0, 1e-9),
        );
        tol::assert_close(
            "∫ cos θ_o d²r_t",
            cz,
            std::f64::consts::TAU / 3.0,
            tol::Tol::new(0.0, 1e-6),
        );
    }
    // A 2-D Gaussian on the cube [−8, 8]²: 2π.
    let g = cube_quad::<2>(
        |x| Complex::new((-0.5 * x.norm_squared()).exp(), 0.0),
        8.0,
        161,
    );
    tol::assert_close(
        "∫ e^{−|x|²/2}",
        g.re,
        std::f64::consts::TAU,
        tol::Tol::new(0.0, 1e-10),
    );
}

#[test]
fn coherence_shapes_have_their_widths() {
    for m in sample(
        strategy::coherence_shape(0.3, 50.0, std::f64::consts::PI),
        N,
    ) {
        Gaussian::<f64, 2>::new(m).expect("positive definite");
        let e = m.symmetric_eigenvalues();
        for l in e.iter() {
            assert!(
                (0.09 * (1.0 - 1e-12)..2500.0 * (1.0 + 1e-12)).contains(l),
                "eigenvalue {l} of {m}"
            );
        }
        tol::assert_close("symmetric", m[(0, 1)], m[(1, 0)], tol::F64);
    }
}

/// The chi-square quantile against tables (NIST/SEMATECH e-Handbook, Table 1.3.6.7.4, upper
/// critical values at α = 0.001), and the test's pooling: a bin with draws but no expectation
/// is an infinite discrepancy.
#[test]
fn chi_square_quantiles_match_the_tables() {
    use gmueller::verify::chi2::{chi_square, chi2_quantile_999};
    for (dof, table) in [(10, 29.588), (20, 45.315), (50, 86.661), (100, 149.449)] {
        // The tables give three decimals: agreement to half a unit of the last one.
        tol::assert_close(
            "χ²₀.₉₉₉",
            chi2_quantile_999(dof),
            table,
            tol::Tol::new(5e-4, 0.0),
        );
    }
    // Counts equal to their expectations: χ² = 0 with bins − 1 degrees of freedom.
    let (chi2, dof) = chi_square(&[50, 30, 20], &[0.5, 0.3, 0.2], 100);
    assert!(chi2.abs() < 1e-12 && dof == 2, "{chi2}, {dof}");
    // A draw where the pdf says nothing can fall.
    let (chi2, _) = chi_square(&[99, 1], &[1.0, 0.0], 100);
    assert!(chi2.is_infinite());
}

/// The exact chi-square quantile at other levels (NIST/SEMATECH Table 1.3.6.7.4: α = 0.05,
/// 0.01; and the median of χ²₁, 0.454936, Abramowitz & Stegun 26.4) and small `dof`.
#[test]
fn chi_square_quantiles_at_other_levels() {
    use gmueller::verify::chi2::chi2_quantile;
    for (dof, p, table) in [
        (1, 0.95, 3.841),
        (2, 0.99, 9.210),
        (5, 0.95, 11.070),
        (30, 0.99, 50.892),
        (1, 0.5, 0.454936),
        (1, 0.999, 10.828),
        (3, 0.999, 16.266),
    ] {
        tol::assert_close(
            "χ²_p",
            chi2_quantile(dof, p),
            table,
            tol::Tol::new(0.0, 2e-4),
        );
    }
}
