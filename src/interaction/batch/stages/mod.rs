//! The stages of the batch kernels (plane wave and partially coherent lobes), one file each, in the order of the scalar
//! functions they re-implement in lanes; each is an `#[inline(always)]` function on one vector
//! of directions, tested against its scalar twin at every [`pulp`] back-end:
//!
//! - [`validity`]: the fast test that a direction is certainly accepted by `Geometry::new`;
//! - [`geometry`]: r̂ and `cos θ_o` (`geometry::unit`, `Geometry::new`);
//! - [`azimuth`]: the exit s vector and `(cos φ, sin φ)` (`Frame::sp_unit`,
//!   `Geometry::exit_azimuth`);
//! - [`fresnel`]: `q_o = √(ε − sin²θ_o)` (`principal_sqrt`);
//! - [`rayleigh_rice`]: the four factors `ss, ps, sp, pp` (`RayleighRice::factors`), in
//!   reflection and, at a dielectric interface, in transmission (a stage the lane loop does not
//!   run yet);
//! - [`psd`]: the weight `cos θ_o · exp(ln prefactor + ln p(h_t) + ln α)`
//!   (`GaussianPsd::log_value`, the Debye–Waller factor);
//! - [`series`]: the Kirchhoff series' channel weights `ln Σ (w_n/g) K[p_n]` (`Terms::sum`),
//!   for the series kernel in place of `ln α + ln K`;
//! - [`stokes`]: `w · M′ (T S)` from the factors (`Mueller::from_jones`);
//! - [`channels`]: the channel weights `ln K`, the `Full` level's channel mix, the projection
//!   onto the cone and the final scale (`PreparedPacket::channel_mix`, `onto_cone`,
//!   `PreparedPacket::scaled`), for the partially coherent lobe batch;
//! - [`specular`]: the Fresnel Mueller matrix and the frame change to each exit's s/p frame
//!   (`FresnelReflection::mueller`).
//!
//! A new stage is one file here plus its test.

use pulp::Simd;

use crate::real::Real;

pub(crate) mod azimuth;
pub(crate) mod channels;
pub(crate) mod fresnel;
pub(crate) mod geometry;
pub(crate) mod psd;
pub(crate) mod rayleigh_rice;
pub(crate) mod series;
pub(crate) mod specular;
pub(crate) mod stokes;
pub(crate) mod validity;

#[cfg(test)]
mod lobe_tests;

/// `(a · b + c · d) + e · f` without fusing (nalgebra's 3-vector dot product order).
#[inline(always)]
pub(crate) fn dot3<S: Simd, F: Real>(s: S, a: [F::V<S>; 3], b: [F::V<S>; 3]) -> F::V<S> {
    F::vadd(
        s,
        F::vadd(s, F::vmul(s, a[0], b[0]), F::vmul(s, a[1], b[1])),
        F::vmul(s, a[2], b[2]),
    )
}

/// `v / d` component by component (true divisions, as nalgebra's `Vector3 / T`).
#[inline(always)]
pub(crate) fn div3<S: Simd, F: Real>(s: S, v: [F::V<S>; 3], d: F::V<S>) -> [F::V<S>; 3] {
    [
        F::vdiv(s, v[0], d),
        F::vdiv(s, v[1], d),
        F::vdiv(s, v[2], d),
    ]
}

/// A per-packet 3-vector on every lane.
#[inline(always)]
pub(crate) fn splat3<S: Simd, F: Real>(s: S, v: nalgebra::Vector3<F>) -> [F::V<S>; 3] {
    [F::vsplat(s, v.x), F::vsplat(s, v.y), F::vsplat(s, v.z)]
}

#[cfg(test)]
pub(crate) mod fixture {
    //! Scenes, exits and the every-back-end runner of the stage tests.
    use nalgebra::Vector3;
    use num_complex::Complex;
    use pulp::{Simd, WithSimd};

    use super::super::prep::PlaneWavePrep;
    use crate::frame::Frame;
    use crate::interaction::Geometry;
    use crate::interaction::pbsdf::RayleighRice;
    pub(crate) use crate::numerics::same;
    use crate::packet::{CoherenceShape, WavePacket};
    use crate::psd::GaussianPsd;
    use crate::real::Real;
    use crate::stokes::Stokes;

    /// One packet on one surface with its prepared constants and a set of exits.
    pub(crate) struct Scene<F: Real> {
        pub(crate) surface: Frame<F>,
        pub(crate) packet: WavePacket<F>,
        pub(crate) psd: GaussianPsd<F, 2>,
        pub(crate) scatter: RayleighRice<F>,
        pub(crate) prep: PlaneWavePrep<F>,
        pub(crate) exits: Vec<Vector3<F>>,
    }

    impl<F: Real> Scene<F> {
        /// The scalar geometry of exit `i`.
        pub(crate) fn geometry(&self, i: usize) -> Geometry<F> {
            Geometry::for_packet(&self.packet, &self.surface, self.exits[i]).unwrap()
        }
    }

    /// Normal, oblique and grazing incidence on a dielectric and two absorbing substrates, with
    /// exits around the specular direction and near the normal (every band of `Frame::sp`).
    pub(crate) fn scenes<F: Real>() -> Vec<Scene<F>> {
        let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
        let psd = GaussianPsd::<F, 2>::isotropic(F::lit(0.02), F::lit(1.5)).unwrap();
        let mut out = Vec::new();
        for (theta_i, eta) in [
            (0.0_f64, (1.5, 0.0)),
            (0.6, (0.3, 6.0)),
            (1.2, (2.0, 0.5)),
            (1.5, (1.3, 0.0)),
        ] {
            let eta = Complex::new(F::lit(eta.0), F::lit(eta.1));
            let travel = Vector3::new(theta_i.sin(), 0.0, -theta_i.cos()).map(F::lit);
            let frame = Frame::sp(travel, Vector3::z())
                .unwrap()
                .rotated(F::lit(0.7));
            let stokes = Stokes::new(F::one(), F::lit(0.3), F::lit(-0.5), F::lit(0.6)).unwrap();
            let packet = WavePacket::from_stokes(
                stokes,
                CoherenceShape::isotropic(F::lit(5.0)).unwrap(),
                frame,
                F::lit(0.5),
            )
            .unwrap();
            let prep = PlaneWavePrep::new(&psd, eta * eta, &packet, &surface).unwrap();
            let scatter = RayleighRice::new(eta).unwrap();
            out.push(Scene {
                surface,
                packet,
                psd,
                scatter,
                prep,
                exits: exits(theta_i, 97),
            });
        }
        out
    }

    /// Seeded exits around the specular direction and near the normal, some not unit.
    fn exits<F: Real>(theta_i: f64, n: usize) -> Vec<Vector3<F>> {
        seeded_exits(theta_i, n, 1.5)
            .into_iter()
            .enumerate()
            .map(|(i, e)| {
                let scale = [1.0, 3.0, 1e-3][i % 7 % 3];
                e.map(|c| F::lit(c * scale))
            })
            .collect()
    }

    /// `n` seeded unit exit directions (in `f64`, for the caller to round or scale), in three
    /// bands that cover every band of `Frame::sp`: around the specular one (polar angle
    /// `θ_i ± 0.25`, azimuth `± 0.25`), near the normal (polar angle in `[0, near_normal)`,
    /// any azimuth), and at the normal or within `1e-10`, `1e-5` of it. Polar angles are
    /// capped at 1.56. The stage fixture and the batch loop's tests (`batch/tests.rs`) draw
    /// their exits here.
    pub(crate) fn seeded_exits(theta_i: f64, n: usize, near_normal: f64) -> Vec<Vector3<f64>> {
        let mut x = 0x5eed_u64 + n as u64;
        let mut uniform = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|i| {
                let (to, po) = match i % 3 {
                    0 => (theta_i + (uniform() - 0.5) * 0.5, (uniform() - 0.5) * 0.5),
                    1 => (uniform() * near_normal, uniform() * 6.0),
                    _ => ([0.0, 1e-10, 1e-5][i % 9 / 3], uniform() * 6.0),
                };
                let to = to.abs().min(1.56);
                Vector3::new(to.sin() * po.cos(), to.sin() * po.sin(), to.cos())
            })
            .collect()
    }

    /// A stage test, run at one back-end.
    pub(crate) trait PerWidth {
        fn run<S: Simd>(&self, s: S, what: &str);
    }

    struct Run<'a, P>(&'a P, &'static str);

    impl<P: PerWidth> WithSimd for Run<'_, P> {
        type Output = ();
        #[inline(always)]
        fn with_simd<S: Simd>(self, s: S) {
            self.0.run(s, self.1);
        }
    }

    /// Runs `t` at every back-end: pulp's scalar ones of 1, 2, 4 and 8 `f64` lanes, the
    /// dispatched one, and AVX2 + FMA (x86-64-v3) and AVX-512 (x86-64-v4) when the CPU has
    /// them.
    pub(crate) fn every_width<P: PerWidth>(t: &P) {
        Run(t, "Scalar").with_simd(pulp::Scalar);
        Run(t, "Scalar128b").with_simd(pulp::Scalar128b);
        Run(t, "Scalar256b").with_simd(pulp::Scalar256b);
        Run(t, "Scalar512b").with_simd(pulp::Scalar512b);
        crate::simd::dispatch(Run(t, "dispatched"));
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = pulp::x86::V3::try_new() {
            Simd::vectorize(v3, Run(t, "V3"));
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(v4) = pulp::x86::V4::try_new() {
            Simd::vectorize(v4, Run(t, "V4"));
        }
    }

    /// The lanes of `xs` (1 to one vector's width of values; the last repeated on the other
    /// lanes, so every lane holds a valid input).
    #[inline(always)]
    pub(crate) fn load<S: Simd, F: Real>(s: S, xs: &[F]) -> F::V<S> {
        let w = F::width::<S>();
        let mut buf = [xs[xs.len() - 1]; 16];
        buf[..xs.len()].copy_from_slice(xs);
        F::load_partial(s, &buf[..w])
    }

    /// The first `F::width::<S>()` lanes of `v` (at most 16).
    #[inline(always)]
    pub(crate) fn lanes_of<S: Simd, F: Real>(s: S, v: F::V<S>) -> [F; 16] {
        let mut out = [F::zero(); 16];
        F::store_partial(s, &mut out[..F::width::<S>()], v);
        out
    }

    /// Calls `f(first, chunk)` for every chunk of `0..n` of one vector's width.
    pub(crate) fn chunks<S: Simd, F: Real>(n: usize, mut f: impl FnMut(usize, usize)) {
        let w = F::width::<S>();
        let mut i = 0;
        while i < n {
            let len = w.min(n - i);
            f(i, len);
            i += len;
        }
    }
}
