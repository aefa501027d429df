//! `--render`: a small spectral ray-traced scene shaded with gmueller's scalar S2.20 kernel
//! (`Kernel<Intensity, Partial>`), rendered twice — under the sun (Ω = 6.8·10⁻⁵ sr,
//! coherence width w ≈ 34 µm at 0.5 µm) and under an equally bright but far less coherent disk
//! source of Ω = 0.1 sr in the same direction (w = λ/√(πΩ) ≈ 0.9 µm, like a bright patch of
//! overcast sky) — and written side by side into one PNG.
//!
//! Scene (scene units are metres; micro-geometry is in µm): a rough ground plane (Gaussian PSD
//! σ = 0.015 µm, ℓ = 3 µm, grey phase screen), a rough glass-like sphere (Gaussian PSD
//! σ = 0.009 µm, ℓ = 1.5 µm, Fresnel/Rayleigh–Rice with n = 1.5) and a tilted metal plate carrying
//! a first-order sinusoidal height grating (amplitude 0.02 µm, period 5 µm, built as in
//! `kernel_side::height_grating`), oriented so that its first diffraction order reaches the
//! camera. Pixel radiance per unit source irradiance is `response.total().s0()` per wavelength,
//! plus a small spectral ambient term (sky light × a diffuse albedo, not from the kernel) so the
//! shapes stay visible; the sphere and the plate cast hard shadows of the source.
//!
//! Spectral: `--wavelengths N` (default 48) stratified samples over 0.40–0.70 µm, jittered per
//! pixel so that the sharp diffraction orders give a continuous rainbow rather than N spots;
//! XYZ from the CIE 1931 2° matching functions (multi-lobe fit of Wyman, Sloan & Shirley 2013),
//! white-balanced for the equal-energy source, → linear sRGB (D65 matrix), exposure so that the
//! 99th percentile of luminance over both images maps to 1, then sRGB gamma and 8 bits.
//!
//! What to look for: under the sun the grating's first order is a sharp, saturated rainbow band
//! across the plate, the ground shows the sun's small mirror image inside its glossy (blue-core,
//! red-fringed: the lobe width grows with λ/ℓ) halo, and the sphere a small highlight. Under the
//! low-coherence source each wavelength's order is blurred over several degrees, wider than the
//! grating's dispersion, so the rainbow washes out into a pastel gradient; the ground glint and
//! the sphere highlight widen into large glows. (Part of the plate's brightness there is the tail
//! of its own mirror reflection of the extended source, only ≈ 3 lobe widths away: for a
//! grating the order's offset from specular, λ/Λ, is about twice its dispersion 0.3 µm/Λ.)
//! The first-order model is kept valid: vσ ≤ 0.3 at 0.40 µm for the ground glint, the plate
//! and the sphere's highlight. Default run: 480×300 per panel, 48 wavelengths, a few seconds.

use std::error::Error;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, Once};
use std::time::Instant;

use gmueller::frame::Frame;
use gmueller::interaction::{
    ConstantMueller, FresnelReflection, Geometry, Intensity, Kernel, Partial, Pbsdf, PhaseScreen,
    RayleighRice, RoughSurface,
};
use gmueller::mueller::Mueller;
use gmueller::packet::WavePacket;
use gmueller::psd::{ClosedForm, GaussianPsd, Grating, Psd};
use gmueller::stokes::Stokes;
use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::{Matrix4, Vector3};
use num_complex::Complex;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use gmueller_validation::kernel_side::height_grating;

type V3 = Vector3<f64>;

/// Options of the render mode.
pub struct RenderArgs {
    /// Image width of one panel, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Number of wavelength strata over 0.40–0.70 µm.
    pub wavelengths: usize,
    /// Worker threads.
    pub threads: usize,
    /// Output directory.
    pub out: PathBuf,
}

/// Solid angle of the sun, sr.
const SUN_OMEGA: f64 = 6.8e-5;
/// Solid angle of the low-coherence comparison source, sr.
const SKY_OMEGA: f64 = 0.1;
const LAMBDA_MIN: f64 = 0.40;
/// Period of the plate's height grating, µm.
const GRATING_PERIOD: f64 = 5.0;
const LAMBDA_MAX: f64 = 0.70;

/// CIE 1931 2° colour matching functions, multi-lobe piecewise-Gaussian fit of
/// C. Wyman, P.-P. Sloan, P. Shirley, "Simple Analytic Approximations to the CIE XYZ Color
/// Matching Functions", JCGT 2(2), 2013 (eqs. 2–4); `lambda_nm` in nm.
fn cie_xyz(lambda_nm: f64) -> [f64; 3] {
    let g = |x: f64, mu: f64, s1: f64, s2: f64| {
        let t = (x - mu) / if x < mu { s1 } else { s2 };
        (-0.5 * t * t).exp()
    };
    let l = lambda_nm;
    [
        1.056 * g(l, 599.8, 37.9, 31.0) + 0.362 * g(l, 442.0, 16.0, 26.7)
            - 0.065 * g(l, 501.1, 20.4, 26.2),
        0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1),
        1.217 * g(l, 437.0, 11.8, 36.0) + 0.681 * g(l, 459.0, 26.0, 13.8),
    ]
}

/// CIE XYZ → linear sRGB (IEC 61966-2-1, D65).
fn xyz_to_linear_srgb(c: [f64; 3]) -> [f64; 3] {
    [
        3.2406 * c[0] - 1.5372 * c[1] - 0.4986 * c[2],
        -0.9689 * c[0] + 1.8758 * c[1] + 0.0415 * c[2],
        0.0557 * c[0] - 0.2040 * c[1] + 1.0570 * c[2],
    ]
}

/// The sRGB transfer function (linear → encoded), clamped to [0, 1].
fn srgb_gamma(v: f64) -> f64 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Relative luminance of linear sRGB.
fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Deterministic hash of a pixel to [0, 1) (for the wavelength jitter).
fn hash01(x: usize, y: usize) -> f64 {
    let mut h = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    h ^= h >> 33;
    h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h ^= h >> 33;
    h = h.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    h ^= h >> 33;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Object {
    Ground,
    Sphere,
    Plate,
}

struct Hit {
    t: f64,
    object: Object,
    point: V3,
    normal: V3,
}

/// The scene geometry (world: y up; camera looks towards −z).
struct SceneGeo {
    sphere_center: V3,
    sphere_radius: f64,
    plate_center: V3,
    /// Plate frame: `u` = grating vector direction, `v` = along the grooves, `n` = normal.
    plate_u: V3,
    plate_v: V3,
    plate_n: V3,
    plate_half: [f64; 2],
}

impl SceneGeo {
    fn new(camera: V3, to_sun: V3) -> Self {
        let plate_center = V3::new(1.3, 0.9, -0.6);
        // Tilt the plate normal from the sun–camera bisector b towards the camera, in the plane
        // of incidence, by δ with |(r̂ + ŝ)_t| = 2 cos θ_h sin δ = λ_mid/Λ: the first order at
        // λ_mid then reaches the camera (δ < 90° − θ_h keeps both directions above the plate).
        let r0 = (camera - plate_center).normalize();
        let b = (r0 + to_sun).normalize();
        let axis = r0.cross(&to_sun).normalize();
        let in_plane = (r0 - b * b.dot(&r0)).normalize();
        let cos_h = b.dot(&to_sun);
        let sin_delta = (0.55 / GRATING_PERIOD / (2.0 * cos_h)).min(0.99);
        let delta = sin_delta.asin();
        let n = (b * delta.cos() + in_plane * delta.sin()).normalize();
        let u = axis.cross(&n).normalize();
        let v = n.cross(&u);
        Self {
            sphere_center: V3::new(-1.8, 0.6, 1.2),
            sphere_radius: 0.6,
            plate_center,
            plate_u: u,
            plate_v: v,
            plate_n: n,
            plate_half: [0.7, 0.5],
        }
    }

    fn intersect(&self, o: &V3, d: &V3, t_max: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut take = |h: Hit| {
            if h.t > 1e-6 && h.t < t_max && best.as_ref().is_none_or(|b| h.t < b.t) {
                best = Some(h);
            }
        };
        // Ground y = 0.
        if d.y < 0.0 {
            let t = -o.y / d.y;
            take(Hit {
                t,
                object: Object::Ground,
                point: o + d * t,
                normal: V3::y(),
            });
        }
        // Sphere.
        let oc = o - self.sphere_center;
        let bq = oc.dot(d);
        let disc = bq * bq - (oc.norm_squared() - self.sphere_radius * self.sphere_radius);
        if disc > 0.0 {
            let t = -bq - disc.sqrt();
            let p = o + d * t;
            take(Hit {
                t,
                object: Object::Sphere,
                point: p,
                normal: (p - self.sphere_center) / self.sphere_radius,
            });
        }
        // Plate (two-sided geometry; only its front carries the grating).
        let dn = d.dot(&self.plate_n);
        if dn.abs() > 1e-12 {
            let t = (self.plate_center - o).dot(&self.plate_n) / dn;
            let p = o + d * t;
            let q = p - self.plate_center;
            if q.dot(&self.plate_u).abs() <= self.plate_half[0]
                && q.dot(&self.plate_v).abs() <= self.plate_half[1]
            {
                take(Hit {
                    t,
                    object: Object::Plate,
                    point: p,
                    normal: self.plate_n,
                });
            }
        }
        best
    }
}

/// The materials (the micro-geometry in µm).
struct Materials {
    ground: RoughSurface<GaussianPsd<f64, 2>, ConstantMueller<f64>, PhaseScreen<f64>>,
    sphere: RoughSurface<GaussianPsd<f64, 2>, FresnelReflection<f64>, RayleighRice<f64>>,
    plate: RoughSurface<Grating<f64, 2>, ConstantMueller<f64>, PhaseScreen<f64>>,
}

impl Materials {
    fn new() -> Result<Self, Box<dyn Error>> {
        let grey = 0.35;
        let glass = Complex::new(1.5, 0.0);
        Ok(Self {
            ground: RoughSurface {
                psd: GaussianPsd::isotropic(0.015, 3.0)?,
                specular: ConstantMueller(Mueller::from_matrix(Matrix4::identity() * grey)?),
                scatter: PhaseScreen::new(grey)?,
            },
            sphere: RoughSurface {
                psd: GaussianPsd::isotropic(0.009, 1.5)?,
                specular: FresnelReflection::new(glass)?,
                scatter: RayleighRice::new(glass)?,
            },
            plate: RoughSurface {
                psd: height_grating(0.02, GRATING_PERIOD),
                specular: ConstantMueller(Mueller::identity()),
                scatter: PhaseScreen::new(1.0)?,
            },
        })
    }
}

/// `response.total().s0()` of `material` for a source of solid angle `omega` travelling along
/// `travel`, seen at a surface with frame `surface` along `exit`; 0 if either is below it.
fn shade<P: Psd<f64, 2>, Sp: Pbsdf<f64>, Sc: Pbsdf<f64>>(
    material: &RoughSurface<P, Sp, Sc>,
    omega: f64,
    travel: &V3,
    surface: &Frame<f64>,
    exit: &V3,
    lambda: f64,
) -> f64
where
    ClosedForm: gmueller::psd::BlurMethod<f64, 2, P>,
{
    let Ok(frame) = Frame::sp(*travel, surface.k()) else {
        return 0.0;
    };
    let Ok(packet) = WavePacket::from_distant_disk_source(
        Stokes::unpolarized(1.0).expect("stokes"),
        omega,
        frame,
        lambda,
    ) else {
        return 0.0;
    };
    let Ok(g) = Geometry::for_packet(&packet, surface, *exit) else {
        return 0.0;
    };
    let kernel = Kernel::<Intensity, Partial>::default();
    let l = kernel.evaluate(material, &packet, &g).total();
    if l.is_finite() { l.max(0.0) } else { 0.0 }
}

/// Diffuse ambient albedo per object (not from the kernel; keeps the shapes visible).
fn ambient_albedo(object: Object, lambda: f64) -> f64 {
    let x = (lambda - LAMBDA_MIN) / (LAMBDA_MAX - LAMBDA_MIN);
    match object {
        Object::Ground => 0.25 + 0.1 * (1.0 - (2.0 * x - 1.0).powi(2)),
        Object::Sphere => 0.1 + 0.5 * x * x,
        Object::Plate => 0.08,
    }
}

/// Sky radiance seen directly (bluish, Rayleigh-like), per unit source irradiance.
fn sky_radiance(lambda: f64, d: &V3) -> f64 {
    0.5 * (0.45 / lambda).powi(4) * (0.6 + 0.4 * d.y.max(0.0))
}

/// Ambient irradiance of the surfaces (relative to the source's unit irradiance).
const AMBIENT: f64 = 0.15;

/// Renders both panels and writes `render.png` into `args.out`.
///
/// # Errors
/// If the materials cannot be built or the PNG cannot be written.
pub fn run(args: &RenderArgs) -> Result<(), Box<dyn Error>> {
    let start = Instant::now();
    let (w, h, nl) = (args.width, args.height, args.wavelengths.max(1));
    let camera = V3::new(0.0, 3.0, 5.0);
    let target = V3::new(0.0, 0.4, 0.0);
    let to_sun = V3::new(-0.2, 0.7, -1.0).normalize();
    let travel = -to_sun;
    let geo = SceneGeo::new(camera, to_sun);
    let mats = Materials::new()?;
    let fov_y = 38f64.to_radians();
    let fwd = (target - camera).normalize();
    let right = fwd.cross(&V3::y()).normalize();
    let up = right.cross(&fwd);
    let tan_half = (0.5 * fov_y).tan();
    let aspect = w as f64 / h as f64;
    let omegas = [SUN_OMEGA, SKY_OMEGA];

    // XYZ per pixel per panel.
    let image = Mutex::new(vec![[[0.0f64; 3]; 2]; w * h]);
    let next = AtomicUsize::new(0);
    let bar = ProgressBar::new(h as u64);
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} rows")
            .expect("progress template"),
    );
    let dl = (LAMBDA_MAX - LAMBDA_MIN) / nl as f64;
    std::thread::scope(|s| {
        for _ in 0..args.threads.max(1) {
            s.spawn(|| {
                let mut row = vec![[[0.0f64; 3]; 2]; w];
                loop {
                    let y = next.fetch_add(1, Ordering::Relaxed);
                    if y >= h {
                        break;
                    }
                    for (x, px) in row.iter_mut().enumerate() {
                        let sx = (2.0 * (x as f64 + 0.5) / w as f64 - 1.0) * tan_half * aspect;
                        let sy = (1.0 - 2.0 * (y as f64 + 0.5) / h as f64) * tan_half;
                        let d = (fwd + right * sx + up * sy).normalize();
                        let jitter = hash01(x, y);
                        *px = [[0.0; 3]; 2];
                        let hit = geo.intersect(&camera, &d, f64::INFINITY);
                        let lit = hit.as_ref().is_some_and(|hit| {
                            let o = hit.point + hit.normal * 1e-6;
                            geo.intersect(&o, &to_sun, f64::INFINITY).is_none()
                        });
                        let surface = hit.as_ref().map(|hit| {
                            let hint = if hit.object == Object::Plate {
                                geo.plate_u
                            } else if hit.normal.x.abs() < 0.9 {
                                V3::x()
                            } else {
                                V3::z()
                            };
                            Frame::from_direction_and_x(hit.normal, hint).expect("surface frame")
                        });
                        for i in 0..nl {
                            let lambda = LAMBDA_MIN + (i as f64 + jitter) * dl;
                            let cmf = cie_xyz(lambda * 1000.0);
                            for (panel, &omega) in omegas.iter().enumerate() {
                                let l = match (&hit, &surface) {
                                    (Some(hit), Some(frame)) => {
                                        let exit = -d;
                                        let direct = if lit {
                                            match hit.object {
                                                Object::Ground => shade(
                                                    &mats.ground,
                                                    omega,
                                                    &travel,
                                                    frame,
                                                    &exit,
                                                    lambda,
                                                ),
                                                Object::Sphere => shade(
                                                    &mats.sphere,
                                                    omega,
                                                    &travel,
                                                    frame,
                                                    &exit,
                                                    lambda,
                                                ),
                                                Object::Plate => shade(
                                                    &mats.plate,
                                                    omega,
                                                    &travel,
                                                    frame,
                                                    &exit,
                                                    lambda,
                                                ),
                                            }
                                        } else {
                                            0.0
                                        };
                                        direct
                                            + AMBIENT * ambient_albedo(hit.object, lambda)
                                                / std::f64::consts::PI
                                    }
                                    _ => sky_radiance(lambda, &d),
                                };
                                for c in 0..3 {
                                    px[panel][c] += l * cmf[c] * dl;
                                }
                            }
                        }
                    }
                    image.lock().expect("image lock")[y * w..(y + 1) * w].copy_from_slice(&row);
                    bar.inc(1);
                }
            });
        }
    });
    bar.finish_and_clear();
    let image = image.into_inner().expect("image lock");

    // White balance for the equal-energy source: divide by the RGB of a flat unit spectrum.
    let white = {
        let n = 300;
        let mut xyz = [0.0; 3];
        for i in 0..n {
            let l = LAMBDA_MIN + (i as f64 + 0.5) * (LAMBDA_MAX - LAMBDA_MIN) / n as f64;
            let c = cie_xyz(l * 1000.0);
            for k in 0..3 {
                xyz[k] += c[k] * (LAMBDA_MAX - LAMBDA_MIN) / n as f64;
            }
        }
        xyz_to_linear_srgb(xyz)
    };
    let rgb: Vec<[[f64; 3]; 2]> = image
        .iter()
        .map(|p| {
            let f = |c: [f64; 3]| {
                let v = xyz_to_linear_srgb(c);
                [v[0] / white[0], v[1] / white[1], v[2] / white[2]]
            };
            [f(p[0]), f(p[1])]
        })
        .collect();
    // Exposure: the 90th percentile of luminance over both panels maps to 0.5; then the
    // extended Reinhard curve on luminance (hue kept) with the 99.9th percentile as white, so
    // that the highlights (up to ~1/Ω) compress instead of clipping the whole image.
    let mut lum: Vec<f64> = rgb
        .iter()
        .flat_map(|p| p.iter().map(|&c| luminance(c)))
        .collect();
    lum.sort_by(f64::total_cmp);
    let pct = |q: f64| lum[((lum.len() as f64 * q) as usize).min(lum.len() - 1)].max(1e-30);
    let exposure = 0.5 / pct(0.90);
    let white2 = (exposure * pct(0.999)).max(1.0).powi(2);
    let tone = |c: [f64; 3]| -> [f64; 3] {
        let l = exposure * luminance(c);
        if l <= 0.0 {
            return [0.0; 3];
        }
        let f = exposure * (1.0 + l / white2) / (1.0 + l);
        [c[0] * f, c[1] * f, c[2] * f]
    };

    // Write the PNG: two panels side by side with a label band on top.
    ensure_font();
    std::fs::create_dir_all(&args.out)?;
    let path = args.out.join("render.png");
    let gap = 8usize;
    let band = 48usize;
    let (tw, th) = (2 * w + gap, h + band);
    {
        let root = BitMapBackend::new(&path, (tw as u32, th as u32)).into_drawing_area();
        root.fill(&BLACK)?;
        for y in 0..h {
            for x in 0..w {
                for (panel, &lin) in rgb[y * w + x].iter().enumerate() {
                    let c = tone(lin);
                    let to8 = |v: f64| (srgb_gamma(v) * 255.0).round() as u8;
                    let px = (panel * (w + gap) + x) as i32;
                    root.draw_pixel(
                        (px, (band + y) as i32),
                        &RGBColor(to8(c[0]), to8(c[1]), to8(c[2])),
                    )?;
                }
            }
        }
        let font = ("sans-serif", 15).into_font().color(&WHITE);
        let small = ("sans-serif", 12).into_font().color(&WHITE);
        let labels = [
            format!("sunlight: Ω = {SUN_OMEGA:.1e} sr, coherence width w ≈ 34 µm"),
            format!("low coherence: Ω = {SKY_OMEGA} sr, w ≈ 0.9 µm, same irradiance"),
        ];
        for (panel, label) in labels.iter().enumerate() {
            let x0 = (panel * (w + gap) + 6) as i32;
            root.draw(&Text::new(label.clone(), (x0, 6), font.clone()))?;
            root.draw(&Text::new(
                format!(
                    "gmueller S2.20 Intensity/Partial/ClosedForm · {nl} λ, 0.40–0.70 µm · w at 0.5 µm"
                ),
                (x0, 27),
                small.clone(),
            ))?;
        }
        root.present()?;
    }
    println!(
        "render: {}×{} per panel, {nl} wavelengths, {} threads — wrote {} in {:.1} s",
        w,
        h,
        args.threads,
        path.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

static FONT: Once = Once::new();

fn ensure_font() {
    FONT.call_once(|| {
        // DejaVu Sans (Bitstream Vera licence), shipped by the `dejavu` crate.
        let _ = register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    });
}
