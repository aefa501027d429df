//! The scene's materials (the part of a scene file that declares them): micro-geometry in µm,
//! indices from `gmueller::spectral`. See `scene.rs` for what each one is.

use gmueller::prelude::{
    GaussianPsd, Glass, Grating, KirchhoffConductor, KirchhoffSeries, Level, Material, Metal,
    RoughConductor, RoughDielectric, Roughness,
};
use nalgebra::Vector2;
use num_complex::Complex;

use crate::adapter::Materials;

/// The materials at `lambda` (µm), indexed by [`crate::scene::Material`]; `rough_gold` the rms
/// height (µm) of a gold sphere rendered beyond first order, or `None` for the first-order one.
pub(crate) fn at(lambda: f32, rough_gold: Option<f32>) -> Materials {
    let psd = |s: f32, l: f32| GaussianPsd::isotropic(s, l).expect("valid PSD");
    let grating = Grating::sinusoidal_height(0.025, 2.0, &Vector2::x()).expect("grating");
    let level = Level::ALL[7]; // Full · Partial
    let (au, al) = (Metal::Au.index(lambda), Metal::Al.index(lambda));
    let gold = match rough_gold {
        Some(sigma) => Material::with_roughness(
            KirchhoffConductor::new(psd(sigma, 1.5), au).expect("rough gold"),
            level,
            Roughness::Series(KirchhoffSeries::new(1e-3).expect("tolerance")),
        ),
        None => Material::new(
            RoughConductor::new(psd(0.012, 1.5), au).expect("gold"),
            level,
        ),
    };
    // Black glass: an interface of index 1.5 whose transmitted light is absorbed, i.e. a
    // "conductor" of real index (Fresnel and Rayleigh–Rice reflection of the dielectric).
    let black = RoughConductor::new(psd(0.008, 3.0), Complex::new(1.5, 0.0)).expect("ground");
    let glass = RoughDielectric::new(psd(0.010, 2.0), Glass::NBk7.index(lambda)).expect("glass");
    let plate = RoughConductor::new(grating, al).expect("aluminium");
    [
        Material::new(black, level),
        Material::new(glass, level),
        gold,
        Material::new(plate, level).two_sided(true),
    ]
}
