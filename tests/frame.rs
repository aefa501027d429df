//! Frames and frame changes (S2.3, S2.4): T(φ) against the literal `A_mül (τ⊗τ) A_mül⁻¹` built
//! by hand, τ against field components computed from world-space dot products, the singular and
//! backward cases of S2.3, the s/p frame builder, validation, Mitsuba 3 `rotator` values and the
//! convention converters. Every law is checked in f32 and f64.

use crate::common;

use common::{
    F32, F64, Tol, angle, assert_all_close, assert_close, complex, complex_matrix2, entries4,
    matrix4_from_rows, unit_vector3,
};
use gmueller::frame::{
    Frame, convention, frame_change_mueller, jones_matrix_to_frames, jones_vector_to_frame,
    mueller_to_frames, reverses_handedness, rotation_angle, rotation_mueller, stokes_to_frame, tau,
};
use gmueller::jones::{JonesMatrix, JonesVector};
use gmueller::mueller::Mueller;
use gmueller::stokes::Stokes;
use gmueller::verify::oracle;
use gmueller::{Error, Real};
use nalgebra::{Matrix2, Matrix4, Vector2, Vector3, Vector4};
use num_complex::Complex;
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

// ------------------------------------------------------------------ helpers (independent oracles)

fn tol<T: Real>() -> Tol {
    if T::EPSILON.to_f64() > 1e-10 {
        F32
    } else {
        F64
    }
}

fn c(re: f64, im: f64) -> Complex<f64> {
    Complex::new(re, im)
}

/// The literal S2.4 product `A_mül (τ⊗τ) A_mül⁻¹` for a real τ (the kit's oracle: S1.3 typed in,
/// the Kronecker product by its index formula; it asserts the result is real).
fn literal_t(tau: &Matrix2<f64>) -> Matrix4<f64> {
    oracle::mueller_literal(&tau.map(|v| c(v, 0.0)))
}

/// Stokes parameters straight from the field components (the crate's definitions, §1).
fn stokes_of(j: &Vector2<Complex<f64>>) -> Vector4<f64> {
    let (ex, ey) = (j[0], j[1]);
    Vector4::new(
        ex.norm_sqr() + ey.norm_sqr(),
        ex.norm_sqr() - ey.norm_sqr(),
        2.0 * (ex * ey.conj()).re,
        2.0 * (ex.conj() * ey).im,
    )
}

/// S2.3 literally: normalized projections of the new basis on the old transverse plane, dotted
/// (the kit's oracle).
fn literal_tau(from: &Frame<f64>, to: &Frame<f64>) -> Matrix2<f64> {
    oracle::tau([from.x(), from.y()], [to.x(), to.y()])
}

/// Rodrigues: `v` turned by `theta` right-handedly about the unit `axis`.
fn rotate(v: &Vector3<f64>, axis: &Vector3<f64>, theta: f64) -> Vector3<f64> {
    v * theta.cos() + axis.cross(v) * theta.sin() + axis * axis.dot(v) * (1.0 - theta.cos())
}

/// A frame turned as a rigid body about `axis` by `theta`.
fn rotate_frame(f: &Frame<f64>, axis: &Vector3<f64>, theta: f64) -> Frame<f64> {
    Frame::new(
        rotate(&f.x(), axis, theta),
        rotate(&f.y(), axis, theta),
        rotate(&f.k(), axis, theta),
    )
    .expect("a rotated frame is a frame")
}

fn to_t<T: Real>(f: &Frame<f64>) -> Frame<T> {
    let cv = |v: Vector3<f64>| v.map(T::lit);
    Frame::new(cv(f.x()), cv(f.y()), cv(f.k())).expect("rounded frame within tolerance")
}

fn m2<T: Real>(m: &Matrix2<T>) -> Matrix2<f64> {
    m.map(|v| v.to_f64())
}

fn m4<T: Real>(m: &Matrix4<T>) -> Matrix4<f64> {
    m.map(|v| v.to_f64())
}

fn entries2(m: &Matrix2<f64>) -> Vec<f64> {
    vec![m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]]
}

use crate::common::frame;

fn jones_vector() -> impl Strategy<Value = Vector2<Complex<f64>>> {
    (complex(1.0), complex(1.0)).prop_map(|(a, b)| Vector2::new(a, b))
}

fn jv<T: Real>(j: &Vector2<Complex<f64>>) -> JonesVector<T> {
    JonesVector::new(
        Complex::new(T::lit(j[0].re), T::lit(j[0].im)),
        Complex::new(T::lit(j[1].re), T::lit(j[1].im)),
    )
    .unwrap()
}

fn jv_f64<T: Real>(j: &JonesVector<T>) -> Vector2<Complex<f64>> {
    j.vector().map(|z| c(z.re.to_f64(), z.im.to_f64()))
}

fn jm<T: Real>(m: &Matrix2<Complex<f64>>) -> JonesMatrix<T> {
    JonesMatrix::from_matrix(m.map(|z| Complex::new(T::lit(z.re), T::lit(z.im)))).unwrap()
}

fn stokes_t<T: Real>(v: &Vector4<f64>) -> Stokes<T> {
    Stokes::from_vector_unchecked(v.map(T::lit))
}

fn is_orthogonal(m: &Matrix2<f64>, tol: Tol) {
    assert_all_close(
        "τᵀτ = I",
        entries2(&(m.transpose() * m)),
        entries2(&Matrix2::identity()),
        tol,
    );
}

// ------------------------------------------------------------------ T(φ), S2.4

fn check_t_literal<T: Real>(psi: f64) {
    // τ for the new basis turned by ψ counter-clockwise about k̂; S2.4 holds with φ = −ψ.
    let tau_psi = Matrix2::new(psi.cos(), psi.sin(), -psi.sin(), psi.cos());
    let lit = literal_t(&tau_psi);
    let ours = m4(&rotation_mueller(T::lit(-psi)).matrix());
    assert_all_close(
        "T(−ψ) vs A(τ⊗τ)A⁻¹",
        entries4(&ours),
        entries4(&lit),
        tol::<T>(),
    );
    // …and the same from two frames.
    let f = Frame::from_direction_and_x(Vector3::new(0.3, -0.2, 0.9), Vector3::x()).unwrap();
    let g = f.rotated(psi);
    let ours = m4(&frame_change_mueller(&to_t::<T>(&f), &to_t::<T>(&g)).matrix());
    assert_all_close(
        "T(f → f rotated by ψ)",
        entries4(&ours),
        entries4(&lit),
        tol::<T>(),
    );
    let t = m2(&tau(&to_t::<T>(&f), &to_t::<T>(&g)));
    assert_all_close("τ = R(ψ)", entries2(&t), entries2(&tau_psi), tol::<T>());
}

fn check_identity_frames<T: Real>(f: &Frame<f64>) {
    let f = to_t::<T>(f);
    assert_eq!(
        tau(&f, &f),
        Matrix2::identity(),
        "τ(f, f) must be I exactly"
    );
    assert_eq!(frame_change_mueller(&f, &f).matrix(), Matrix4::identity());
    assert_eq!(rotation_angle(&f, &f), T::zero());
    assert!(!reverses_handedness(&f, &f));
}

fn check_composition<T: Real>(a: f64, b: f64) {
    let p = m4(&(rotation_mueller(T::lit(a)) * rotation_mueller(T::lit(b))).matrix());
    let s = m4(&rotation_mueller(T::lit(a) + T::lit(b)).matrix());
    assert_all_close("T(a)T(b) = T(a+b)", entries4(&p), entries4(&s), tol::<T>());
}

proptest! {
    #![proptest_config(common::proptest_config(128))]

    #[test]
    fn rotation_mueller_is_literal_a_mul_tau_kron_tau(psi in angle()) {
        check_t_literal::<f64>(psi);
        check_t_literal::<f32>(psi);
    }

    #[test]
    fn identical_frames_give_exact_identity(f in frame()) {
        check_identity_frames::<f64>(&f);
        check_identity_frames::<f32>(&f);
    }

    #[test]
    fn rotation_mueller_composes(a in angle(), b in angle()) {
        check_composition::<f64>(a, b);
        check_composition::<f32>(a, b);
    }
}

#[test]
fn rotation_mueller_at_zero_and_pi() {
    assert_eq!(rotation_mueller(0.0_f64).matrix(), Matrix4::identity());
    assert_eq!(rotation_mueller(0.0_f32).matrix(), Matrix4::identity());
    let i = entries4(&Matrix4::identity());
    assert_all_close(
        "T(π)",
        entries4(&rotation_mueller(PI).matrix()),
        i.clone(),
        F64,
    );
    let t32 = m4(&rotation_mueller(std::f32::consts::PI).matrix());
    assert_all_close("T(π) f32", entries4(&t32), i, F32);
}

/// Turning the frame by ψ = +45° (x̂′ = (x̂+ŷ)/√2, ŷ′ = (−x̂+ŷ)/√2): the field E = x̂ has components
/// (x̂′·E, ŷ′·E) = (1/√2, −1/√2), so by hand `S2 = 2 Re(E_x′ E_y′*) = −1`.
#[test]
fn forty_five_degree_frame_maps_s1_to_minus_s2() {
    let f = Frame::from_direction_and_x(Vector3::z(), Vector3::x()).unwrap();
    let g = f.rotated(FRAC_PI_4);
    let e = Vector3::x();
    let comps = Vector2::new(c(g.x().dot(&e), 0.0), c(g.y().dot(&e), 0.0));
    let by_fields = stokes_of(&comps);
    assert_all_close(
        "fields",
        by_fields.iter().copied(),
        [1.0, 0.0, -1.0, 0.0],
        F64,
    );
    let s = Stokes::new(1.0, 1.0, 0.0, 0.0).unwrap();
    let ours = stokes_to_frame(&s, &f, &g).vector();
    assert_all_close("T S", ours.iter().copied(), by_fields.iter().copied(), F64);
    let g32 = to_t::<f32>(&g);
    let f32_ = to_t::<f32>(&f);
    let s32 = Stokes::new(1.0_f32, 1.0, 0.0, 0.0).unwrap();
    let ours32 = stokes_to_frame(&s32, &f32_, &g32).vector().map(f64::from);
    assert_all_close(
        "T S f32",
        ours32.iter().copied(),
        by_fields.iter().copied(),
        F32,
    );
}

// ------------------------------------------------------------------ Stokes via T ≡ Jones via τ

fn check_stokes_jones_consistency<T: Real>(
    from: &Frame<f64>,
    to: &Frame<f64>,
    j: &Vector2<Complex<f64>>,
) {
    let (f, g) = (to_t::<T>(from), to_t::<T>(to));
    let j_t = jv::<T>(j);
    let via_jones = stokes_of(&jv_f64(&jones_vector_to_frame(&j_t, &f, &g)));
    let s = stokes_t::<T>(&stokes_of(j));
    let via_stokes = stokes_to_frame(&s, &f, &g).vector().map(|v| v.to_f64());
    assert_all_close(
        "Stokes(τj) = T Stokes(j)",
        via_stokes.iter().copied(),
        via_jones.iter().copied(),
        tol::<T>(),
    );
    // T is exactly the literal A_mül (τ⊗τ) A_mül⁻¹ of the τ returned (rotation or reflection).
    let lit = literal_t(&m2(&tau(&f, &g)));
    assert_all_close(
        "T = A(τ⊗τ)A⁻¹",
        entries4(&m4(&frame_change_mueller(&f, &g).matrix())),
        entries4(&lit),
        tol::<T>(),
    );
    // τ is orthogonal, and the reverse change is its transpose.
    let t = m2(&tau(&f, &g));
    is_orthogonal(&t, tol::<T>());
    let back = m2(&tau(&g, &f));
    assert_all_close(
        "τ(g, f) = τ(f, g)ᵀ",
        entries2(&back),
        entries2(&t.transpose()),
        tol::<T>(),
    );
    assert_close(
        "det τ",
        t.determinant(),
        if reverses_handedness(&f, &g) {
            -1.0
        } else {
            1.0
        },
        tol::<T>(),
    );
}

/// Same k̂: τ j equals the exact components of the world-space field, `(x̂′·E, ŷ′·E)`.
fn check_same_k_world_field<T: Real>(f: &Frame<f64>, psi: f64, j: &Vector2<Complex<f64>>) {
    let g = f.rotated(psi);
    let e: Vector3<Complex<f64>> =
        f.x().map(|v| c(v, 0.0)) * j[0] + f.y().map(|v| c(v, 0.0)) * j[1];
    let proj = |b: Vector3<f64>| b.x * e.x + b.y * e.y + b.z * e.z;
    let exact = [proj(g.x()), proj(g.y())];
    let ours = jv_f64(&jones_vector_to_frame(
        &jv::<T>(j),
        &to_t::<T>(f),
        &to_t::<T>(&g),
    ));
    common::assert_complex_close(
        "τ j = (x̂′·E, ŷ′·E)",
        ours.iter().copied(),
        exact,
        tol::<T>(),
    );
    assert_close(
        "φ = −ψ (mod 2π)",
        (rotation_angle(&to_t::<T>(f), &to_t::<T>(&g)).to_f64() + psi).sin(),
        0.0,
        tol::<T>(),
    );
}

proptest! {
    #![proptest_config(common::proptest_config(128))]

    #[test]
    fn stokes_by_t_equals_jones_by_tau_random_frames(
        from in frame(), to in frame(), j in jones_vector()
    ) {
        check_stokes_jones_consistency::<f64>(&from, &to, &j);
        check_stokes_jones_consistency::<f32>(&from, &to, &j);
    }

    #[test]
    fn stokes_by_t_equals_jones_by_tau_rotations_about_k(
        from in frame(), psi in angle(), j in jones_vector()
    ) {
        let to = from.rotated(psi);
        check_stokes_jones_consistency::<f64>(&from, &to, &j);
        check_stokes_jones_consistency::<f32>(&from, &to, &j);
        check_same_k_world_field::<f64>(&from, psi, &j);
        check_same_k_world_field::<f32>(&from, psi, &j);
    }

    /// Tilting the turned frame about its own x̂′ or ŷ′ keeps the projections orthogonal: then τ
    /// must equal S2.3's normalized-projection matrix literally.
    #[test]
    fn tau_equals_literal_projection_for_tilts_about_new_axes(
        f in frame(), psi in angle(), tilt in -1.5..1.5f64, about_x in any::<bool>()
    ) {
        let g0 = f.rotated(psi);
        let axis = if about_x { g0.x() } else { g0.y() };
        let g = rotate_frame(&g0, &axis, tilt);
        let lit = literal_tau(&f, &g);
        prop_assert!(!reverses_handedness(&f, &g));
        assert_all_close("τ vs literal S2.3", entries2(&tau(&f, &g)), entries2(&lit), Tol::new(1e-11, 1e-11));
        assert_all_close("τ vs literal S2.3 (f32)", entries2(&m2(&tau(&to_t::<f32>(&f), &to_t::<f32>(&g)))), entries2(&lit), Tol::new(2e-4, 2e-4));
    }

    /// General tilt: the turned frame is carried to k̂′ by the minimal rotation (parallel
    /// transport); φ must be exactly −ψ, and τ the closest rotation to the projection matrix
    /// P (polar decomposition: τᵀP symmetric with non-negative trace).
    #[test]
    fn tau_is_parallel_transport_angle_for_general_tilts(
        f in frame(), psi in angle(), dir in unit_vector3(), tilt in 0.0..1.5f64
    ) {
        let axis = f.k().cross(&dir);
        prop_assume!(axis.norm() > 1e-3);
        let axis = axis.normalize();
        let g = rotate_frame(&f.rotated(psi), &axis, tilt);
        let t = tau(&f, &g);
        let expected = Matrix2::new(psi.cos(), psi.sin(), -psi.sin(), psi.cos());
        assert_all_close("τ = R(ψ) after minimal tilt", entries2(&t), entries2(&expected), Tol::new(1e-11, 1e-11));
        let p = Matrix2::new(g.x().dot(&f.x()), g.x().dot(&f.y()), g.y().dot(&f.x()), g.y().dot(&f.y()));
        let s = t.transpose() * p;
        assert_close("τᵀP symmetric", s[(0, 1)], s[(1, 0)], Tol::new(1e-12, 1e-12));
        prop_assert!(s.trace() >= 0.0);
        assert_close("det P = k̂·k̂′", p.determinant(), f.k().dot(&g.k()), Tol::new(1e-12, 1e-12));
    }
}

// ------------------------------------------------------------------ singular and backward cases

/// S2.3's singular case: x̂′ = k̂ (x̂′⊥ undefined). The text takes the angle between ŷ′⊥ and ŷ;
/// τ's second row must be (ŷ′⊥·x̂, ŷ′⊥·ŷ), and τ must be a rotation, continuous with frames
/// tilted slightly so that k̂·k̂′ > 0.
#[test]
fn singular_case_uses_y_and_is_continuous() {
    let f = Frame::from_direction_and_x(Vector3::new(0.2, 0.4, -0.8), Vector3::new(1.0, 0.0, 0.3))
        .unwrap();
    for &alpha in &[0.0, 0.7, 2.0, -2.9] {
        // y′ in the old transverse plane at angle α from x̂; x′ = k̂; k′ = x′ × y′.
        let y_new = f.x() * f64::cos(alpha) + f.y() * f64::sin(alpha);
        let g = Frame::new(f.k(), y_new, f.k().cross(&y_new)).unwrap();
        let t = tau(&f, &g);
        let yp = y_new; // already in the transverse plane and unit
        assert_all_close(
            "second row",
            [t[(1, 0)], t[(1, 1)]],
            [yp.dot(&f.x()), yp.dot(&f.y())],
            F64,
        );
        is_orthogonal(&t, F64);
        assert_close("det τ", t.determinant(), 1.0, F64);
        // Nearby: turn g about ŷ′ by ±ε. One sign tilts k̂′ toward k̂ (k̂·k̂′ > 0): continuous.
        for eps in [1e-7, -1e-7] {
            let h = rotate_frame(&g, &g.y(), eps);
            let th = tau(&f, &h);
            if f.k().dot(&h.k()) > 0.0 {
                assert_all_close(
                    "continuity",
                    entries2(&th),
                    entries2(&t),
                    Tol::new(1e-6, 0.0),
                );
            } else {
                // Across k̂·k̂′ = 0 the projection changes orientation: the first row flips,
                // the second (the ŷ′ rule) stays continuous.
                assert!(reverses_handedness(&f, &h));
                assert_all_close(
                    "flip side",
                    entries2(&th),
                    [-t[(0, 0)], -t[(0, 1)], t[(1, 0)], t[(1, 1)]],
                    Tol::new(1e-6, 0.0),
                );
            }
        }
        // f32 agrees.
        let t32 = m2(&tau(&to_t::<f32>(&f), &to_t::<f32>(&g)));
        assert_all_close("f32", entries2(&t32), entries2(&t), Tol::new(1e-4, 0.0));
    }
}

fn check_reversed<T: Real>(f: &Frame<f64>, j: &Vector2<Complex<f64>>) {
    let ft = to_t::<T>(f);
    let r = ft.reversed();
    // Still a valid right-handed frame.
    Frame::new(r.x(), r.y(), r.k()).expect("reversed frame is right-handed");
    assert_eq!(m2(&tau(&ft, &r)), Matrix2::new(1.0, 0.0, 0.0, -1.0));
    let d = Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, -1.0, -1.0));
    assert_eq!(m4(&frame_change_mueller(&ft, &r).matrix()), d);
    // Jones components of the same world field in the reversed frame, by dot products: (E_x, −E_y).
    let rf = f.reversed();
    let e: Vector3<Complex<f64>> =
        f.x().map(|v| c(v, 0.0)) * j[0] + f.y().map(|v| c(v, 0.0)) * j[1];
    let proj = |b: Vector3<f64>| b.x * e.x + b.y * e.y + b.z * e.z;
    let exact = Vector2::new(proj(rf.x()), proj(rf.y()));
    let ours = jv_f64(&jones_vector_to_frame(&jv::<T>(j), &ft, &r));
    common::assert_complex_close(
        "(E_x, −E_y)",
        ours.iter().copied(),
        exact.iter().copied(),
        tol::<T>(),
    );
    let s = stokes_of(&exact);
    let ours_s = stokes_to_frame(&stokes_t::<T>(&stokes_of(j)), &ft, &r)
        .vector()
        .map(|v| v.to_f64());
    assert_all_close(
        "diag(1,1,−1,−1) S",
        ours_s.iter().copied(),
        s.iter().copied(),
        tol::<T>(),
    );
}

proptest! {
    #![proptest_config(common::proptest_config(128))]

    #[test]
    fn reversed_frame_flips_s2_s3(f in frame(), j in jones_vector()) {
        check_reversed::<f64>(&f, &j);
        check_reversed::<f32>(&f, &j);
    }

    /// Specular reflection in s/p frames: ŝ is shared, p̂_r projects onto ±p̂_i, so S2.3's
    /// normalized projections are orthogonal and τ must equal them: diag(1, −1) below 45°
    /// (k̂·k̂′ < 0, a reflection) and I above.
    #[test]
    fn specular_sp_frames_match_literal_projection(n in unit_vector3(), t in unit_vector3(), theta in 0.01..1.55f64) {
        prop_assume!((theta - FRAC_PI_4).abs() > 1e-3);
        let tangent = t - n * t.dot(&n);
        prop_assume!(tangent.norm() > 0.1);
        let tangent = tangent.normalize();
        let d = tangent * theta.sin() - n * theta.cos();
        let r = d - n * (2.0 * d.dot(&n));
        let fi = Frame::sp(d, n).unwrap();
        let fr = Frame::sp(r, n).unwrap();
        assert_all_close("shared ŝ", fi.x().iter().copied(), fr.x().iter().copied(), F64);
        let lit = literal_tau(&fi, &fr);
        let expected = if theta < FRAC_PI_4 { [1.0, 0.0, 0.0, -1.0] } else { [1.0, 0.0, 0.0, 1.0] };
        assert_all_close("literal", entries2(&lit), expected, Tol::new(1e-9, 0.0));
        assert_all_close("τ", entries2(&tau(&fi, &fr)), expected, Tol::new(1e-9, 0.0));
        prop_assert_eq!(reverses_handedness(&fi, &fr), theta < FRAC_PI_4);
    }
}

// ------------------------------------------------------------------ basis changes of operators

fn check_operator_changes<T: Real>(
    frames: &[Frame<f64>; 4],
    jm_: &Matrix2<Complex<f64>>,
    s: &Vector4<f64>,
) {
    let [a, b, c_, d] = frames.map(|f| to_t::<T>(&f));
    let j = jm::<T>(jm_);
    let m = Mueller::from_jones(&j);
    // Mueller of the re-expressed Jones matrix = re-expressed Mueller matrix.
    let lhs = Mueller::from_jones(&jones_matrix_to_frames(&j, &a, &b, &c_, &d)).matrix();
    let rhs = mueller_to_frames(&m, &a, &b, &c_, &d).matrix();
    let scale = jm_.norm_squared().max(1.0);
    let t = Tol::new(tol::<T>().abs * scale, tol::<T>().rel);
    assert_all_close("M(J′) = M′", entries4(&m4(&lhs)), entries4(&m4(&rhs)), t);
    // M′ acting on the re-expressed input = re-expressed output.
    let s_in = stokes_t::<T>(s);
    let out = stokes_to_frame(&(m * s_in), &c_, &d).vector();
    let out2 = (Mueller::from_matrix(rhs).unwrap() * stokes_to_frame(&s_in, &a, &b)).vector();
    assert_all_close(
        "M′ T_in S = T_out M S",
        out.iter().map(|v| v.to_f64()),
        out2.iter().map(|v| v.to_f64()),
        t,
    );
}

proptest! {
    #![proptest_config(common::proptest_config(64))]

    #[test]
    fn operator_basis_changes_agree(
        f in proptest::array::uniform4(frame()),
        j in complex_matrix2(1.0),
        s in common::stokes_vector(),
    ) {
        check_operator_changes::<f64>(&f, &j, &s);
        check_operator_changes::<f32>(&f, &j, &s);
    }
}

// ------------------------------------------------------------------ s/p frames and validation

proptest! {
    #![proptest_config(common::proptest_config(256))]

    #[test]
    fn sp_frame_is_right_handed_and_s_is_normal_to_plane_of_incidence(
        d in unit_vector3(), n in unit_vector3(), scale_d in 0.01..100.0f64, scale_n in 0.01..100.0f64
    ) {
        prop_assume!(d.cross(&n).norm() > 1e-6);
        let f = Frame::sp(d * scale_d, n * scale_n).unwrap();
        Frame::new(f.x(), f.y(), f.k()).expect("valid right-handed frame");
        assert_all_close("k̂ = d̂", f.k().iter().copied(), d.iter().copied(), F64);
        assert_close("ŝ·n̂", f.x().dot(&n), 0.0, F64);
        assert_close("ŝ·d̂", f.x().dot(&d), 0.0, F64);
        // p̂ lies in the plane of incidence, and ŝ has the sign of d̂ × n̂.
        assert_close("p̂·(d̂×n̂)", f.y().dot(&d.cross(&n)), 0.0, Tol::new(1e-9, 0.0));
        prop_assert!(f.x().dot(&d.cross(&n)) > 0.0);
        // A refracted direction in the plane of incidence shares ŝ.
        let t = (d + n * 0.3 * d.dot(&n)).normalize();
        let ft = Frame::sp(t, n).unwrap();
        assert_all_close("refracted ŝ", ft.x().iter().copied(), f.x().iter().copied(), Tol::new(1e-9, 1e-9));
        let f32_ = Frame::sp(d.map(|v| v as f32), n.map(|v| v as f32));
        prop_assert!(f32_.is_ok());
    }

    #[test]
    fn sp_normal_incidence_fallback_same_s_for_both_directions(n in unit_vector3(), sign in prop::bool::ANY) {
        let n = if sign { n } else { -n };
        for (d, label) in [(n, "d = n"), (-n, "d = −n")] {
            let f = Frame::sp(d, n).unwrap();
            Frame::new(f.x(), f.y(), f.k()).expect(label);
        }
        let up = Frame::sp(n, n).unwrap();
        let down = Frame::sp(-n, n).unwrap();
        prop_assert_eq!(up.x(), down.x());
        prop_assert_eq!(down, up.reversed());
        // Within √ε of normal incidence the fallback still applies and stays ⊥ d̂.
        let near = n + Vector3::new(1e-10, -2e-10, 0.5e-10);
        let fnear = Frame::sp(near, n).unwrap();
        let fnear_back = Frame::sp(-near, n).unwrap();
        prop_assert_eq!(fnear.x(), fnear_back.x());
        Frame::new(fnear.x(), fnear.y(), fnear.k()).expect("near-normal frame valid");
        // f32
        let n32 = n.map(|v| v as f32);
        let u32_ = Frame::sp(n32, n32).unwrap();
        let d32 = Frame::sp(-n32, n32).unwrap();
        prop_assert_eq!(u32_.x(), d32.x());
        Frame::new(d32.x(), d32.y(), d32.k()).expect("f32 fallback frame valid");
    }

    #[test]
    fn from_direction_and_x_is_gram_schmidt(k in unit_vector3(), h in unit_vector3(), sk in 0.1..10.0f64) {
        prop_assume!(k.cross(&h).norm() > 1e-3);
        let f = Frame::from_direction_and_x(k * sk, h).unwrap();
        Frame::new(f.x(), f.y(), f.k()).expect("valid");
        let expected = (h - k * h.dot(&k)).normalize();
        assert_all_close("x̂", f.x().iter().copied(), expected.iter().copied(), Tol::new(1e-9, 1e-9));
        let f32_ = Frame::from_direction_and_x(k.map(|v| v as f32), h.map(|v| v as f32)).unwrap();
        Frame::new(f32_.x(), f32_.y(), f32_.k()).expect("valid f32");
    }
}

fn check_rejections<T: Real>() {
    let (x, y, z) = (Vector3::<T>::x(), Vector3::<T>::y(), Vector3::<T>::z());
    let basis = |reason: &'static str| Err(Error::InvalidBasis { reason });
    assert!(Frame::new(x, y, z).is_ok());
    assert_eq!(
        Frame::new(x * T::lit(1.01), y, z),
        basis("basis vector is not of unit length")
    );
    assert_eq!(Frame::new(x, y, Vector3::zeros()), basis("zero vector"));
    let tilted = (y + x * T::lit(0.01)).normalize();
    assert_eq!(
        Frame::new(x, tilted, z),
        basis("basis vectors are not orthogonal")
    );
    assert_eq!(
        Frame::new(x, y, -z),
        basis("basis is left-handed (x̂ × ŷ = −k̂)")
    );
    assert_eq!(
        Frame::new(y, x, z),
        basis("basis is left-handed (x̂ × ŷ = −k̂)")
    );
    let nan = Vector3::new(T::lit(f64::NAN), T::zero(), T::zero());
    assert!(matches!(
        Frame::new(nan, y, z),
        Err(Error::NonFinite { .. })
    ));
    let inf = Vector3::new(T::zero(), T::zero(), T::one() / T::zero());
    assert!(matches!(
        Frame::new(x, y, inf),
        Err(Error::NonFinite { .. })
    ));
    // sp
    assert_eq!(Frame::sp(Vector3::zeros(), z), basis("zero vector"));
    assert_eq!(Frame::sp(x, Vector3::zeros()), basis("zero vector"));
    assert!(matches!(Frame::sp(nan, z), Err(Error::NonFinite { .. })));
    assert!(matches!(Frame::sp(z, nan), Err(Error::NonFinite { .. })));
    assert!(matches!(Frame::sp(inf, z), Err(Error::NonFinite { .. })));
    // from_direction_and_x
    assert_eq!(
        Frame::from_direction_and_x(z, z * T::lit(3.0)),
        basis("x hint is parallel to the direction")
    );
    assert_eq!(
        Frame::from_direction_and_x(z, -z),
        basis("x hint is parallel to the direction")
    );
    assert_eq!(
        Frame::from_direction_and_x(Vector3::zeros(), x),
        basis("zero vector")
    );
    assert_eq!(
        Frame::from_direction_and_x(z, Vector3::zeros()),
        basis("zero vector")
    );
    assert!(matches!(
        Frame::from_direction_and_x(z, nan),
        Err(Error::NonFinite { .. })
    ));
    // Huge and tiny but finite inputs are fine.
    let big = Frame::sp(
        Vector3::new(T::lit(1e30), T::zero(), T::lit(-1e30)),
        z * T::lit(1e-30),
    )
    .unwrap();
    Frame::new(big.x(), big.y(), big.k()).expect("scaled inputs");
}

#[test]
fn constructors_reject_invalid_input() {
    check_rejections::<f64>();
    check_rejections::<f32>();
}

// ------------------------------------------------------------------ external anchor: Mitsuba 3

/// Mitsuba 3.9.1 `rotator(θ)` values (`tests/data/peer_values.json`, kind "rotator"), a rotation
/// of the reference frame by +θ: must equal our `rotation_mueller(−θ)` within the case tolerance.
#[test]
fn mitsuba_rotator_matches_rotation_mueller_of_minus_theta() {
    let mut n = 0;
    for case in common::peer_cases("rotator") {
        assert!(case["source"].as_str().unwrap().contains("Mitsuba 3.9.1"));
        let theta = case["theta"].as_f64().unwrap();
        let case_tol = case["tol"].as_f64().unwrap();
        let rows = common::json_rows(&case["mueller"]);
        let theirs = matrix4_from_rows(&rows);
        let t = Tol::new(case_tol, 0.0);
        assert_all_close(
            "T(−θ) f64",
            entries4(&rotation_mueller(-theta).matrix()),
            entries4(&theirs),
            t,
        );
        assert_all_close(
            "mitsuba_rotator",
            entries4(&convention::mitsuba_rotator(theta).matrix()),
            entries4(&theirs),
            t,
        );
        let ours32 = m4(&rotation_mueller(-(theta as f32)).matrix());
        assert_all_close("T(−θ) f32", entries4(&ours32), entries4(&theirs), t);
        // Mitsuba's frame turned by +θ is our Frame::rotated(θ).
        let f = Frame::from_direction_and_x(Vector3::new(0.0, 0.0, 1.0), Vector3::x()).unwrap();
        assert_all_close(
            "frame turned by θ",
            entries4(&frame_change_mueller(&f, &f.rotated(theta)).matrix()),
            entries4(&theirs),
            t,
        );
        n += 1;
    }
    assert_eq!(n, 4, "expected the four rotator cases");
}

// ------------------------------------------------------------------ convention converters

fn check_converters<T: Real>(
    jm_: &Matrix2<Complex<f64>>,
    j: &Vector2<Complex<f64>>,
    eta: Complex<f64>,
) {
    let jt = jm::<T>(jm_);
    let m = Mueller::from_jones(&jt);
    let scale = jm_.norm_squared().max(1.0);
    let t = Tol::new(tol::<T>().abs * scale, tol::<T>().rel);
    // D M D: an involution, and the Mueller matrix of the conjugated Jones matrix.
    let dmd = convention::flip_time_convention_mueller(&m);
    assert_eq!(convention::flip_time_convention_mueller(&dmd), m);
    let d = Matrix4::from_diagonal(&Vector4::new(1.0, 1.0, 1.0, -1.0));
    assert_all_close(
        "D M D",
        entries4(&m4(&dmd.matrix())),
        entries4(&(d * m4(&m.matrix()) * d)),
        t,
    );
    let conj = Mueller::from_jones(&convention::flip_time_convention_jones_matrix(&jt));
    assert_all_close(
        "M(J*) = D M D",
        entries4(&m4(&conj.matrix())),
        entries4(&m4(&dmd.matrix())),
        t,
    );
    // Stokes: D S from the conjugated field.
    let s = stokes_of(j);
    let sd = convention::flip_time_convention_stokes(&stokes_t::<T>(&s))
        .vector()
        .map(|v| v.to_f64());
    let sconj = stokes_of(&jv_f64(&convention::flip_time_convention_jones_vector(
        &jv::<T>(j),
    )));
    assert_all_close(
        "Stokes(j*) = D S",
        sd.iter().copied(),
        sconj.iter().copied(),
        tol::<T>(),
    );
    // s/p swap: Mueller of the swapped Jones matrix, Stokes of the swapped field.
    let sw = Mueller::from_jones(&convention::swap_sp_jones_matrix(&jt));
    assert_all_close(
        "M(PJP) = E M E",
        entries4(&m4(&sw.matrix())),
        entries4(&m4(&convention::swap_sp_mueller(&m).matrix())),
        t,
    );
    let p = Matrix2::new(c(0.0, 0.0), c(1.0, 0.0), c(1.0, 0.0), c(0.0, 0.0));
    let pjp = p * jm_ * p;
    let ours = convention::swap_sp_jones_matrix(&jt)
        .matrix()
        .map(|z| c(z.re.to_f64(), z.im.to_f64()));
    common::assert_complex_close("P J P", ours.iter().copied(), pjp.iter().copied(), t);
    let swapped_field = stokes_of(&Vector2::new(j[1], j[0]));
    let ours_s = convention::swap_sp_stokes(&stokes_t::<T>(&s))
        .vector()
        .map(|v| v.to_f64());
    assert_all_close(
        "Stokes(Pj) = E S",
        ours_s.iter().copied(),
        swapped_field.iter().copied(),
        tol::<T>(),
    );
    let ours_j = jv_f64(&convention::swap_sp_jones_vector(&jv::<T>(j)));
    common::assert_complex_close("P j", ours_j.iter().copied(), [j[1], j[0]], tol::<T>());
    // Index sign: n + iκ ↔ n − iκ, an involution.
    let e = Complex::new(T::lit(eta.re), T::lit(eta.im));
    let flipped = convention::flip_time_convention_index(e);
    assert_eq!(flipped.re, e.re);
    assert_eq!(flipped.im, -e.im);
    assert_eq!(convention::flip_time_convention_index(flipped), e);
}

proptest! {
    #![proptest_config(common::proptest_config(128))]

    #[test]
    fn converters_are_consistent(j in complex_matrix2(1.0), v in jones_vector(), n in 0.1..4.0f64, k in 0.0..8.0f64) {
        check_converters::<f64>(&j, &v, Complex::new(n, k));
        check_converters::<f32>(&j, &v, Complex::new(n, k));
    }
}

/// Physics check of the S3 flip (the crate's e^{−iωt} convention): a quarter-wave plate with fast axis x̂ on +45° linear
/// light gives S3 = +1 here and −1 in Mitsuba 3 / py-pol / pypolar.
#[test]
fn quarter_wave_plate_s3_sign_flips_with_time_convention() {
    let q = Mueller::from_jones(&JonesMatrix::linear_retarder(0.0, FRAC_PI_2));
    let s = Stokes::new(1.0, 0.0, 1.0, 0.0).unwrap();
    let ours = (q * s).vector();
    assert_close("ours S3", ours[3], 1.0, F64);
    let theirs =
        convention::flip_time_convention_mueller(&q) * convention::flip_time_convention_stokes(&s);
    assert_close("theirs S3", theirs.vector()[3], -1.0, F64);
    // Converting their result back gives ours.
    assert_all_close(
        "round trip",
        convention::flip_time_convention_stokes(&theirs)
            .vector()
            .iter()
            .copied(),
        ours.iter().copied(),
        F64,
    );
}
