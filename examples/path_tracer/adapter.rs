//! The adapter between the tracer's scene and image code and `gmueller`: frames, material
//! dispatch, the vertex (sun NEE and the next direction), the path state and the spectral and
//! colour conversions. With the material declarations of `materials.rs` (the scene file's
//! part), it is the only code that names the crate; `tests.rs` holds it to 50 lines of code.

use gmueller::prelude::*;
use gmueller::spectral::{D65_WHITE_XYZ, cie1931_normalized, srgb_encode, xyz_to_linear_srgb};

use crate::scene::{Hit, Scene, V3};
use crate::{Options, Rng, Sampling};

/// The materials at one wavelength, indexed by [`crate::scene::Material`].
pub(crate) type Materials = [Material<f32>; 4];

/// A camera path at one wavelength: its state, and what its vertices share.
pub(crate) struct Path<'a> {
    t: PathThroughput<f32>,
    lambda: f32,
    opts: &'a Options,
    coherence: SurfaceCoherence<f32>,
}

impl<'a> Path<'a> {
    /// A path seen along `view`: its Stokes vectors in `x̂` = the image's right, `k̂ = −view`.
    pub(crate) fn new(scene: &Scene, view: &V3, lambda: f32, opts: &'a Options) -> Self {
        let camera = Frame::from_direction_and_x(-view, scene.camera.right).expect("camera");
        let w = opts.sky_coherence;
        let coherence = if opts.horizon_rule {
            SurfaceCoherence::new(w)
        } else {
            SurfaceCoherence::fixed(w)
        };
        let coherence = coherence.expect("coherence width");
        Self {
            t: PathThroughput::new(camera),
            lambda,
            opts,
            coherence,
        }
    }

    /// The sky along `d` (the path's last ray).
    pub(crate) fn sky(&mut self, scene: &Scene, d: &V3) {
        let ([l, dop], x) = scene.sky(d, self.lambda);
        let sky = Stokes::new(l, l * dop, 0.0, 0.0).expect("sky");
        self.t.gather_arriving(
            &Frame::from_direction_and_x(-d, x).expect("sky frame"),
            &sky,
        );
    }

    /// One vertex on `hit` seen from `r̂`: sun NEE, then the direction the light comes from.
    pub(crate) fn vertex(
        &mut self,
        scene: &Scene,
        mats: &Materials,
        hit: &Hit,
        r: V3,
        rng: &mut Rng,
    ) -> Result<Option<V3>, Error> {
        let (m, n, opts) = (&mats[hit.material as usize], hit.normal, self.opts);
        let frame = match scene.grating_axis(hit) {
            Some(u) => Frame::new(u, n.cross(&u), n)?,
            None => Frame::from_normal(n)?,
        };
        let sp = ShadingPoint::new(frame, self.lambda)?;
        let facing = !m.is_opaque() || scene.sun.dot(&n) * r.dot(&n) > 0.0;
        if facing && scene.sees_sun(&hit.point, &n) {
            let k = opts.sun_split.max(1);
            for _ in 0..k {
                let (dir, omega) = scene.sun_sample(k, opts.sun_solid_angle, rng);
                let light =
                    m.distant_packet(&sp, Stokes::unpolarized(1.0 / k as f32)?, omega, dir)?;
                self.t.gather_light(&m.eval(&sp, &light, r)?, &light);
            }
        }
        let u = [rng.f(), rng.f(), rng.f()];
        let s = match opts.sampling {
            Sampling::Lobes => m.sample_incident(&sp, r, &self.coherence, u[0], [u[1], u[2]])?,
            Sampling::Uniform => {
                m.sample_incident_uniform(&sp, r, &self.coherence, [u[1], u[2]])?
            }
        };
        let Some(s) = s else { return Ok(None) };
        self.t
            .advance(&s.weight.scaled(opts.weight_scale), &s.geometry);
        Ok(self.t.roulette(rng.f(), 0.05).then_some(s.sample.direction))
    }

    /// `(X, Y, Z, ȳS0, ȳS1, ȳS2, ȳS3)` of the path, for `λ` drawn uniformly over `span` µm,
    /// and the count of rejected contributions.
    pub(crate) fn xyz_stokes(&self, span: f32) -> ([f32; 7], usize) {
        let [x, y, z] = cie1931_normalized(self.lambda).map(|c| c * span);
        let l = self.t.radiance().vector();
        let v = [
            l[0] * x,
            l[0] * y,
            l[0] * z,
            l[0] * y,
            l[1] * y,
            l[2] * y,
            l[3] * y,
        ];
        (v, self.t.rejected())
    }
}

/// 8-bit sRGB of `xyz` (the equal-energy white at `(1, 1, 1)`, mapped to D65's).
pub(crate) fn srgb8(xyz: [f32; 3]) -> [u8; 3] {
    let w = D65_WHITE_XYZ.map(|c| c as f32);
    let rgb = xyz_to_linear_srgb([xyz[0] * w[0], xyz[1], xyz[2] * w[2]]);
    rgb.map(|c| (srgb_encode(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
}
