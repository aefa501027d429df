//! The verification kit's strategies with user-controlled ranges, standard elements,
//! depolarizers, CSD matrices, s/p frames, N-dimensional shapes and PSDs: every generated object
//! passes the crate's validation (2000 fixed-seed draws each, fresh ones under
//! `GMUELLER_PROPTEST_SEARCH`), stays inside the ranges asked for, and reaches the boundaries
//! it promises — each coverage is counted and asserted at a quarter or less of its expected
//! share, so that a fresh-seed run fails by chance with probability < 1e-4.

use gmueller::frame::Frame;
use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::packet::{CoherenceShape, WavePacket};
use gmueller::psd::Psd;
use gmueller::stokes::{CsdMatrix, Stokes};
use gmueller::verify::strategy::{self, JonesElement, sample};
use gmueller::verify::{check, oracle, tol};
use nalgebra::{Matrix2, Matrix3, Matrix4, SVector, Vector2, Vector3};
use num_complex::Complex;

const N: usize = 2000;

#[test]
fn stokes_vectors_stay_in_the_ranges_asked_for() {
    for s in sample(strategy::stokes_vector_in(1e-30, 1e-20, 0.3, 0.6), N) {
        Stokes::new(s[0], s[1], s[2], s[3]).expect("the crate accepts it");
        check::assert_valid_stokes("stokes_vector_in", s, tol::Tol::new(0.0, 1e-12));
        assert!((1e-30..1e-20).contains(&s[0]), "S0 = {:e}", s[0]);
        let dop = s.fixed_rows::<3>(1).norm() / s[0];
        assert!((0.3 - 1e-12..=0.6 + 1e-12).contains(&dop), "DoP {dop}");
    }
    // dop_lo = dop_hi = 1 is the cone.
    for s in sample(strategy::stokes_vector_in(1.0, 2.0, 1.0, 1.0), 200) {
        let dop = s.fixed_rows::<3>(1).norm() / s[0];
        tol::assert_close("DoP on the cone", dop, 1.0, tol::F64);
    }
}

#[test]
fn packets_with_the_callers_ranges_are_realizable() {
    let r = strategy::PacketRanges {
        shape_lo: 1e-4,
        shape_hi: 1e-2,
        max_condition: 1e4,
        s0_lo: 1e6,
        s0_hi: 1e8,
        max_s1_ratio: 0.5,
        closeness: 0.01,
    };
    let mut high_condition = 0;
    for (s, tx, ty) in sample(strategy::packet_parts_in(r), N) {
        assert!((1e6..1e8).contains(&s[0]) && s[1].abs() <= 0.5 * s[0] + 1e-9);
        for t in [tx, ty] {
            let e = t.symmetric_eigenvalues();
            let (lo, hi) = (e.min(), e.max());
            assert!(lo > 0.0 && (1e-4 * (1.0 - 1e-12)..=1e-2 * (1.0 + 1e-12)).contains(&hi));
            assert!(hi / lo <= 1e4 * (1.0 + 1e-9), "condition {}", hi / lo);
            high_condition += usize::from(hi / lo > 1e3);
        }
        let f = strategy::mu_squared(&s) / strategy::bochner_bound(&tx, &ty);
        assert!((0.99 - 1e-9..=1.0 + 1e-9).contains(&f), "|μ|²/bound = {f}");
        let frame = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let stokes = Stokes::new(s[0], s[1], s[2], s[3]).unwrap();
        let shape = |m: Matrix2<f64>| CoherenceShape::new(m).expect("SPD");
        WavePacket::new(stokes, shape(tx), shape(ty), frame, 0.5)
            .expect("the crate accepts the packet");
    }
    println!(
        "coverage: shapes of condition > 1e3 (max 1e4): {high_condition}/{}",
        2 * N
    );
    // The condition is log-uniform in [1, 1e4]: a quarter of the shapes above 1e3.
    assert!(
        high_condition * 16 > 2 * N,
        "condition > 1e3: {high_condition}/{}",
        2 * N
    );
}

#[test]
fn polar_angles_dense_near_grazing_reach_it() {
    let p = strategy::PolarAngles {
        dense_near_grazing: true,
        ..strategy::PolarAngles::default()
    };
    let v = sample(strategy::polar_angle_with(p), N);
    let max = 89.99f64.to_radians();
    let mut within_a_tenth_degree = 0;
    for &t in &v {
        assert!((0.0..=max).contains(&t), "θ = {t}");
        let from_grazing = std::f64::consts::FRAC_PI_2 - t;
        within_a_tenth_degree += usize::from(t != max && from_grazing < 0.1f64.to_radians());
    }
    // 3/4 of the draws are log-uniform in the distance 0.01°–90° from grazing: 1/4 of those
    // (3/16 of all) within 0.1°, against 0.08 % for the uniform mix.
    assert!(
        within_a_tenth_degree * 16 > N,
        "within 0.1° of grazing: {within_a_tenth_degree}/{N}"
    );
    let normal = v.iter().filter(|&&t| t == 0.0).count();
    let grazing = v.iter().filter(|&&t| t == max).count();
    println!(
        "coverage: polar angles (dense near grazing) within 0.1° of grazing {within_a_tenth_degree}/{N}, exactly 0 {normal}/{N}, exactly 89.99° {grazing}/{N}"
    );
    assert!(normal * 32 > N && grazing * 32 > N, "{normal}, {grazing}");
}

#[test]
fn standard_jones_elements_have_their_defining_properties() {
    let identity = Matrix2::<Complex<f64>>::identity();
    let mut kinds = [0usize; 6];
    for e in sample(strategy::jones_element(), N) {
        let j = e.matrix();
        let m = Mueller::from_jones(&JonesMatrix::from_matrix(j).unwrap()).matrix();
        check::assert_realizable("element", &m, 1e-12);
        check::assert_passive("element", &m, 1e-12);
        let close = |what: &str, a: Matrix2<Complex<f64>>, b: Matrix2<Complex<f64>>| {
            tol::assert_complex_close(what, a.iter().copied(), b.iter().copied(), tol::F64);
        };
        match e {
            JonesElement::LinearPolarizer { .. } | JonesElement::CircularPolarizer { .. } => {
                close("P² = P", j * j, j);
                close("P† = P", j.adjoint(), j);
                kinds[usize::from(matches!(e, JonesElement::CircularPolarizer { .. }))] += 1;
            }
            JonesElement::LinearRetarder { .. }
            | JonesElement::Rotator { .. }
            | JonesElement::CircularRetarder { .. } => {
                close("J†J = I", j.adjoint() * j, identity);
                kinds[2 + match e {
                    JonesElement::LinearRetarder { .. } => 0,
                    JonesElement::Rotator { .. } => 1,
                    _ => 2,
                }] += 1;
            }
            JonesElement::Diattenuator { tx, ty, .. } => {
                close("D† = D", j.adjoint(), j);
                // Eigenvalues tx, ty: trace and determinant.
                tol::assert_close("tr", (j[(0, 0)] + j[(1, 1)]).re, tx + ty, tol::F64);
                let det = j[(0, 0)] * j[(1, 1)] - j[(0, 1)] * j[(1, 0)];
                tol::assert_close("det", det.re, tx * ty, tol::F64);
                kinds[5] += 1;
            }
        }
    }
    println!(
        "coverage: Jones elements (polarizer, circular polarizer, retarder, rotator, circular retarder, diattenuator) {kinds:?} of {N}"
    );
    assert!(kinds.iter().all(|&k| k * 12 > N), "shares {kinds:?}");
}

#[test]
fn depolarizers_are_realizable_and_reach_the_tetrahedrons_boundary() {
    let mut on_boundary = 0;
    let mut strongly_depolarizing = 0;
    for m in sample(strategy::depolarizer(), N) {
        check::assert_realizable("depolarizer", &m, 1e-12);
        tol::assert_close("M00", m[(0, 0)], 1.0, tol::F64);
        let mm = Mueller::from_matrix(m).unwrap();
        let eig = mm.coherency_eigenvalues();
        on_boundary += usize::from(eig.min() < 1e-9 * eig.sum());
        strongly_depolarizing += usize::from(mm.depolarization_index() < 0.3);
    }
    println!(
        "coverage: depolarizers on the realizability boundary {on_boundary}/{N}, depolarization index < 0.3 {strongly_depolarizing}/{N}"
    );
    // A zero weight in each of the four slots with probability 1/4: some zero in 68 %.
    assert!(on_boundary * 4 > N, "on the boundary: {on_boundary}/{N}");
    assert!(
        strongly_depolarizing * 100 > N,
        "P_Δ < 0.3: {strongly_depolarizing}/{N}"
    );
}

#[test]
fn muellers_near_the_boundary_are_within_the_distance_asked_for() {
    for m in sample(strategy::realizable_mueller_near_boundary(1e-6), N) {
        check::assert_realizable("near boundary", &m, 1e-12);
        let eig = Mueller::from_matrix(m).unwrap().coherency_eigenvalues();
        assert!(eig.min() <= 1e-6 * eig.sum() * (1.0 + 1e-6), "{eig:?}");
    }
}

#[test]
fn csd_matrices_are_realizable() {
    let mut rank_one = 0;
    for c in sample(strategy::one_point_csd(3.0), N) {
        let csd = CsdMatrix::one_point(c).expect("the crate accepts it");
        let s = csd.to_stokes().unwrap();
        check::assert_valid_stokes("one-point CSD", s.vector(), tol::F64);
        tol::assert_all_close(
            "Stokes of the CSD",
            s.vector().iter().copied(),
            oracle::stokes_of_csd(&c).iter().copied(),
            tol::F64,
        );
        rank_one += usize::from(s.degree_of_polarization() > 1.0 - 1e-9);
    }
    println!("coverage: one-point CSDs fully polarized (rank 1) {rank_one}/{N}");
    assert!(rank_one * 4 > N, "fully polarized: {rank_one}/{N}");

    let mut two_point_rank_one = 0;
    for c in sample(strategy::two_point_csd(0.0, 1.0), N) {
        for (what, one) in [("C(r1, r1)", c.at_1), ("C(r2, r2)", c.at_2)] {
            CsdMatrix::<f64>::one_point(one)
                .unwrap_or_else(|e| panic!("{what} is a one-point CSD: {e}"));
        }
        CsdMatrix::two_point(c.cross).expect("the crate accepts the cross CSD");
        // The joint 4×4 matrix is positive semidefinite.
        let mut g = Matrix4::<Complex<f64>>::zeros();
        g.fixed_view_mut::<2, 2>(0, 0).copy_from(&c.at_1);
        g.fixed_view_mut::<2, 2>(2, 2).copy_from(&c.at_2);
        g.fixed_view_mut::<2, 2>(0, 2).copy_from(&c.cross);
        g.fixed_view_mut::<2, 2>(2, 0).copy_from(&c.cross.adjoint());
        let eig = g.symmetric_eigenvalues();
        let scale = eig.amax();
        assert!(eig.min() >= -1e-12 * scale, "joint eigenvalues {eig:?}");
        // The electromagnetic degree of coherence (Tervo, Setälä & Friberg 2003),
        // μ² = tr(C₁₂ C₁₂†)/(tr C₁₁ tr C₂₂) ≤ 1, = 1 for a fully coherent (rank-1) field.
        let mu = tsf_coherence(&c);
        assert!(mu <= 1.0 + 1e-12, "|μ| = {mu}");
        let d1 = c.at_1[(0, 0)].re * c.at_1[(1, 1)].re - c.at_1[(0, 1)].norm_sqr();
        let t1 = (c.at_1[(0, 0)] + c.at_1[(1, 1)]).re;
        two_point_rank_one += usize::from(d1 <= 1e-9 * t1 * t1);
    }
    // m = 1 (fully polarized at each point) in a quarter of the draws.
    assert!(
        two_point_rank_one * 16 > N,
        "rank 1 at r₁: {two_point_rank_one}/{N}"
    );
    let coherent = sample(strategy::two_point_csd(1.0, 1.0), 200)
        .into_iter()
        .filter(|c| tsf_coherence(c) > 1.0 - 1e-9)
        .count();
    println!(
        "coverage: two-point CSDs fully polarized at r₁ {two_point_rank_one}/{N}; at c = 1 fully coherent {coherent}/200"
    );
    // With c = 1, the rank-1 draws (a quarter) are fully coherent (μ = 1).
    assert!(
        coherent * 16 > 200,
        "fully coherent at c = 1: {coherent}/200"
    );
}

fn tsf_coherence(c: &strategy::TwoPointCsd) -> f64 {
    let t = |m: &Matrix2<Complex<f64>>| (m[(0, 0)] + m[(1, 1)]).re;
    let cc = c.cross * c.cross.adjoint();
    (t(&cc) / (t(&c.at_1) * t(&c.at_2))).sqrt()
}

#[test]
fn sp_frames_are_right_handed_and_reach_normal_incidence() {
    let mut normal = 0;
    let mut grazing = 0;
    for (d, n, f) in sample(strategy::sp_frame(), N) {
        let (x, y, k) = (f.x(), f.y(), f.k());
        tol::assert_close("|x|", x.norm(), 1.0, tol::F64);
        tol::assert_close("x·y", x.dot(&y), 0.0, tol::F64);
        tol::assert_all_close(
            "x × y = k",
            x.cross(&y).iter().copied(),
            k.iter().copied(),
            tol::F64,
        );
        tol::assert_all_close("k = d", k.iter().copied(), d.iter().copied(), tol::F64);
        // ŝ lies in the surface (perpendicular to the plane of incidence).
        tol::assert_close("ŝ·n̂", x.dot(&n), 0.0, tol::F64);
        let cos = d.dot(&n).abs();
        normal += usize::from(cos > 1.0 - 1e-15);
        grazing += usize::from(cos < 2e-4);
    }
    println!(
        "coverage: s/p frames at exact normal incidence {normal}/{N}, within 2e-4 of grazing {grazing}/{N}"
    );
    assert!(normal * 32 > N && grazing * 32 > N, "{normal}, {grazing}");
}

#[test]
fn n_dimensional_shapes_have_their_condition() {
    let mut near_max = 0;
    for m in sample(strategy::spd_conditioned::<3>(0.5, 2.0, 1e3), N) {
        tol::assert_all_close(
            "symmetric",
            m.iter().copied(),
            m.transpose().iter().copied(),
            tol::F64,
        );
        let e = m.symmetric_eigenvalues();
        let (lo, hi) = (e.min(), e.max());
        assert!(
            lo > 0.0 && (0.5 - 1e-12..=2.0 + 1e-12).contains(&hi),
            "{e:?}"
        );
        assert!(hi / lo <= 1e3 * (1.0 + 1e-9), "condition {}", hi / lo);
        near_max += usize::from(hi / lo > 5e2);
        let _: Matrix3<f64> = m;
        m.cholesky().expect("SPD");
    }
    println!("coverage: 3-D shapes of condition > 500 (max 1e3): {near_max}/{N}");
    assert!(near_max * 40 > N, "condition > 500: {near_max}/{N}");
}

#[test]
fn psds_are_valid_in_their_ranges() {
    let r = strategy::PsdRanges::default();
    for p in sample(strategy::gaussian_psd::<2>(r), N) {
        let var = p.variance();
        assert!(
            (r.rms_lo.powi(2) * (1.0 - 1e-12)..=r.rms_hi.powi(2) * (1.0 + 1e-12)).contains(&var)
        );
        let v0 = p.value(&Vector2::zeros());
        assert!(v0.is_finite() && v0 > 0.0);
        // ∫p = (2π) σ² (unitary transform, n = 2).
        tol::assert_close("∫p", p.integral(), std::f64::consts::TAU * var, tol::F64);
    }
    for p in sample(strategy::gaussian_psd::<3>(r), 500) {
        let v0 = p.value(&SVector::<f64, 3>::zeros());
        assert!(v0.is_finite() && v0 > 0.0);
    }
    let mut near_bound = 0;
    for p in sample(strategy::kcorrelation_psd::<2>(r, 3.0), N) {
        let g = p.gamma();
        assert!(g > 1.0 && g <= 4.0 + 1e-12, "γ = {g}");
        near_bound += usize::from(g < 1.01);
        let v = p.value(&Vector2::new(10.0, 0.0));
        assert!(v.is_finite() && v > 0.0);
    }
    println!("coverage: K-correlation PSDs with γ within 0.01 of its bound 1: {near_bound}/{N}");
    assert!(near_bound * 8 > N, "γ within 0.01 of 1: {near_bound}/{N}");
    for p in sample(strategy::kcorrelation_psd::<3>(r, 3.0), 500) {
        assert!(p.gamma() > 2.0);
    }
    for p in sample(strategy::mixture_psd::<2>(r, 8), 500) {
        assert!((1..=8).contains(&p.components().len()));
        let total: f64 = p.components().iter().map(|c| c.variance()).sum();
        tol::assert_close("σ² of the mixture", p.variance(), total, tol::F64);
    }
}
