//! The scene: geometry (scene units: metres), materials (micro-geometry in µm) and the lights.
//!
//! - Ground `y = 0`: polished black glass (η = 1.5, Gaussian PSD σ = 8 nm, ℓ = 3 µm); what it
//!   transmits is absorbed below, so it is the interface's reflection alone (an opaque
//!   material of real index).
//! - A rough glass sphere (η of Schott N-BK7, `gmueller::spectral::Glass::NBk7`, σ = 10 nm,
//!   ℓ = 2 µm): reflection and transmission at both of its surfaces, from outside and inside.
//! - A rough gold sphere (σ = 12 nm, ℓ = 1.5 µm; n + iκ of gold, `spectral::Metal::Au`); with
//!   `--rough-gold σ` a much rougher one (σ in µm, same ℓ, the tangent-plane scatterer),
//!   rendered beyond first order by the Kirchhoff series.
//! - A two-sided aluminium plate (n + iκ of aluminium, same source) carrying a sinusoidal **height**
//!   grating (amplitude 25 nm, period 2 µm), tilted so that the sun's first diffraction order
//!   reaches the camera across the plate.
//! - The sun (a disk of Ω = 6.8·10⁻⁵ sr, irradiance 1 across the beam, equal-energy spectrum)
//!   and a Rayleigh-like sky (radiance ∝ λ⁻⁴ (1 + cos²γ), linearly polarized perpendicular to
//!   the scattering plane with degree 0.75 sin²γ/(1 + cos²γ), γ the angle to the sun): both
//!   illustrative, not measured.

use nalgebra::Vector3;

use crate::Rng;

pub(crate) type V3 = Vector3<f32>;

/// The sun's solid angle, sr.
pub(crate) const SUN_SOLID_ANGLE: f32 = 6.8e-5;

/// What a ray hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Material {
    Ground,
    Glass,
    Gold,
    Grating,
}

/// A ray–surface intersection.
pub(crate) struct Hit {
    pub(crate) t: f32,
    pub(crate) point: V3,
    /// The outward normal of the object (out of the glass for the glass sphere).
    pub(crate) normal: V3,
    pub(crate) material: Material,
}

struct Sphere {
    centre: V3,
    radius: f32,
    material: Material,
}

/// A rectangle: centre, unit normal, half-extents along `u` and `v`.
struct Plate {
    centre: V3,
    normal: V3,
    u: V3,
    v: V3,
    half: [f32; 2],
}

pub(crate) struct Scene {
    spheres: [Sphere; 2],
    plate: Plate,
    /// Unit direction toward the sun.
    pub(crate) sun: V3,
    pub(crate) camera: Camera,
}

pub(crate) struct Camera {
    pub(crate) origin: V3,
    pub(crate) forward: V3,
    pub(crate) right: V3,
    pub(crate) up: V3,
    pub(crate) tan_half_fov: f32,
}

impl Camera {
    /// The unit direction through image point `(x, y)` ∈ [0, 1]² (y down).
    pub(crate) fn direction(&self, x: f32, y: f32, aspect: f32) -> V3 {
        let sx = (2.0 * x - 1.0) * self.tan_half_fov * aspect;
        let sy = (1.0 - 2.0 * y) * self.tan_half_fov;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }
}

impl Scene {
    pub(crate) fn new() -> Self {
        let sun = V3::new(-0.45, 0.55, -0.70).normalize();
        let origin = V3::new(0.0, 1.0, 4.2);
        let target = V3::new(0.0, 0.45, 0.0);
        let forward = (target - origin).normalize();
        let right = forward.cross(&V3::y()).normalize();
        let up = right.cross(&forward);
        let camera = Camera {
            origin,
            forward,
            right,
            up,
            tan_half_fov: (20f32).to_radians().tan(),
        };
        // The plate: its normal tilted from the bisector of sun and camera so that the mirror
        // condition misses by the first order's offset at 0.55 µm, (r̂ + ŝ)_t = λ/Λ d̂.
        let centre = V3::new(1.15, 0.55, -0.3);
        let to_cam = (origin - centre).normalize();
        let bisector = (to_cam + sun).normalize();
        let axis = bisector.cross(&V3::y()).normalize(); // horizontal, ⟂ bisector
        let half_sum = (to_cam + sun).norm();
        let delta = (0.55f32 / 2.0 / half_sum).asin();
        let normal = rotate(bisector, axis, delta);
        let u = normal.cross(&axis).normalize(); // the grating vector's direction
        let v = normal.cross(&u);
        Self {
            spheres: [
                Sphere {
                    centre: V3::new(-1.05, 0.5, -0.2),
                    radius: 0.5,
                    material: Material::Gold,
                },
                Sphere {
                    centre: V3::new(0.05, 0.5, 0.55),
                    radius: 0.5,
                    material: Material::Glass,
                },
            ],
            plate: Plate {
                centre,
                normal,
                u,
                v,
                half: [0.42, 0.34],
            },
            sun,
            camera,
        }
    }

    /// The nearest hit along `origin + t dir`, `t > 0`.
    pub(crate) fn intersect(&self, origin: &V3, dir: &V3) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut keep = |h: Hit| {
            if best.as_ref().is_none_or(|b| h.t < b.t) {
                best = Some(h);
            }
        };
        if dir.y < 0.0 && origin.y > 0.0 {
            let t = -origin.y / dir.y;
            keep(Hit {
                t,
                point: origin + dir * t,
                normal: V3::y(),
                material: Material::Ground,
            });
        }
        for s in &self.spheres {
            let oc = origin - s.centre;
            let b = oc.dot(dir);
            let c = oc.norm_squared() - s.radius * s.radius;
            let disc = b * b - c;
            if disc > 0.0 {
                let r = disc.sqrt();
                let t = if -b - r > 1e-5 { -b - r } else { -b + r };
                if t > 1e-5 {
                    let point = origin + dir * t;
                    keep(Hit {
                        t,
                        point,
                        normal: (point - s.centre) / s.radius,
                        material: s.material,
                    });
                }
            }
        }
        let p = &self.plate;
        let denom = dir.dot(&p.normal);
        if denom.abs() > 1e-8 {
            let t = (p.centre - origin).dot(&p.normal) / denom;
            let q = origin + dir * t - p.centre;
            if t > 1e-5 && q.dot(&p.u).abs() <= p.half[0] && q.dot(&p.v).abs() <= p.half[1] {
                // The plate is metal on both faces: the normal faces the ray's origin.
                let normal = if denom < 0.0 { p.normal } else { -p.normal };
                keep(Hit {
                    t,
                    point: origin + dir * t,
                    normal,
                    material: Material::Grating,
                });
            }
        }
        best
    }

    /// `true` when nothing blocks the ray toward the sun (the glass sphere casts a shadow:
    /// caustics through it are not traced).
    pub(crate) fn sees_sun(&self, point: &V3, normal: &V3) -> bool {
        let o = point + normal * (1e-4 * normal.dot(&self.sun).signum());
        self.intersect(&o, &self.sun).is_none()
    }

    /// The grating direction of the plate (the shading frame's `t̂₁`, the PSD's x axis);
    /// `None` for the isotropic materials.
    pub(crate) fn grating_axis(&self, hit: &Hit) -> Option<V3> {
        (hit.material == Material::Grating).then_some(self.plate.u)
    }

    /// The `k`-th part of the sun for a vertex that splits it into `k` packets: the disk's
    /// centre and whole solid angle `Ω` for `k = 1`, else a direction uniform in the disk and
    /// `Ω/k`.
    pub(crate) fn sun_sample(&self, k: usize, solid_angle: f32, rng: &mut Rng) -> (V3, f32) {
        if k == 1 {
            return (self.sun, solid_angle);
        }
        let cos_max = 1.0 - solid_angle / std::f32::consts::TAU;
        let z = 1.0 - rng.f() * (1.0 - cos_max);
        let rho = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * rng.f();
        // Any axis not along the sun spans the disk's plane with it.
        let axis = if self.sun.x.abs() < 0.9 {
            V3::x()
        } else {
            V3::y()
        };
        let x = self.sun.cross(&axis).normalize();
        let y = self.sun.cross(&x);
        let dir = x * (rho * phi.cos()) + y * (rho * phi.sin()) + self.sun * z;
        (dir, solid_angle / k as f32)
    }

    /// The sky's radiance arriving from direction `d` (toward the sky) at wavelength `lambda`
    /// (µm) and its degree of linear polarization, along the axis it returns (`x̂`,
    /// perpendicular to the plane of `d` and the sun; the light travels along `−d`).
    pub(crate) fn sky(&self, d: &V3, lambda: f32) -> ([f32; 2], V3) {
        let cos_g = d.dot(&self.sun).clamp(-1.0, 1.0);
        let sin2 = 1.0 - cos_g * cos_g;
        let elevation = d.y.max(0.0);
        let l = 0.10
            * (0.55 / lambda).powi(4)
            * 0.75
            * (1.0 + cos_g * cos_g)
            * (0.35 + 0.65 * (1.0 - elevation).powi(3) + 0.3 * elevation);
        let dop = 0.75 * sin2 / (1.0 + cos_g * cos_g);
        let perp = d.cross(&self.sun);
        let x = if perp.norm() > 1e-4 {
            perp
        } else {
            d.cross(&V3::x())
        };
        ([l, dop], x)
    }
}

/// `v` rotated by `angle` about the unit `axis` (Rodrigues).
fn rotate(v: V3, axis: V3, angle: f32) -> V3 {
    let (s, c) = angle.sin_cos();
    v * c + axis.cross(&v) * s + axis * (axis.dot(&v) * (1.0 - c))
}
