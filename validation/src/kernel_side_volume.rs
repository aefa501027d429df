//! The kernel's prediction for a volumetric brute-force scene ([`crate::brute_volume`]): the
//! seed's S2.20 with n = 3 as the crate's random medium computes it,
//! `gmueller::medium::RandomMedium::differential_scattering` (`Dipole` scatterer, `Full ·
//! Partial` with the closed-form blur), re-expressed in the brute force's exit frame — that is
//! [`predict`] for the bulk regions. The thin slab is the surface kernel's coherence term
//! (`surface_coherence_term`, the 2-D result the slab tends to).
//!
//! [`predict_from_primitives`] assembles the same prediction independently of
//! `gmueller::medium`, from the derivation below and the crate's lower-level primitives —
//! `gmueller::interaction::coherence::volume_coherence_term` (the 3-D coherence term `K³_α`),
//! `WavePacket::with_longitudinal_coherence` (`σ_zz`), `GaussianPsd::<_, 3>` (or the 3-D
//! K-correlation's mixture fit), and the Rayleigh dipole's Mueller matrix from its Jones matrix
//! with `Mueller::from_jones` and the crate's frame changes; a unit test holds the medium to it
//! (the two derivations of the absolute constant and of the frames agree).
//!
//! # Formula
//! ```text
//! β(r̂) = (k⁴/16π²) Σ_α K³_α(h) M_dip(ŝ → r̂) S_α,        h = k(r̂ + ŝ),  ŝ = −d̂
//! K³_α(h) = ∫ R(ξ) g^{Θ_α}(Qᵀξ) e^{−ih·ξ} d³ξ = |Θ_α|^{1/2} ∫ p(q) g^{Ξ_α}(h − q) d³q
//! S_x = S_x (1, 1, 0, 0),  S_y = S_y (1, −1, 0, 0),  S_½ = (0, 0, S2, S3)          (packet frame)
//! M_dip = T(scattering-plane out → exit frame) · M(J) · T(packet frame → scattering-plane in)
//! J = diag(1, cos Θ) in the frames (n̂, d̂ × n̂, d̂) → (n̂, r̂ × n̂, r̂),  n̂ = (d̂ × r̂)/|d̂ × r̂|,  cos Θ = d̂·r̂
//! ```
//! β is the radiant intensity per unit volume per unit incident irradiance, in the brute
//! force's exit frame `Frame::sp(r̂, ẑ)` (1/(length·sr)).
//!
//! # The absolute constant, derived
//! The first-Born far field (`crate::brute_volume`, module docs) is
//! `E_s = (k²/4π)(e^{ikr}/r)(I − r̂r̂ᵀ) ∫ δε E_in e^{−ik r̂·r'} d³r'`; per unit irradiance and unit
//! volume of an unbounded stationary medium the average of `r² E_s E_s†` is
//! `(k²/4π)² Σ_αβ C_αβ (I − r̂r̂ᵀ) e_α e_βᵀ (I − r̂r̂ᵀ) ∫ R(ξ) g^{Θ_αβ}(Qᵀξ) e^{−ih·ξ} d³ξ`, and
//! the integral is the crate's `K³` (S2.15 with S2.17's constant corrected to `(2π)^{3/2}`, the
//! unitary transform of DESIGN §1): `∫ R c e^{−ih·ξ} = (2π)^{3/2} F{R c}(h) = (2π)^{3/2} (p * F{c})(h)`
//! and `F{g^{Θ}(Qᵀ·)} = |Θ|^{1/2} g^{Ξ}` (Lemma S2.1, `Ξ = QΘ⁻¹Qᵀ`). The polarization factor
//! `(I − r̂r̂ᵀ)` read in s/p frames of the scattering plane is the Rayleigh dipole's Jones matrix
//! `diag(1, cos Θ)`: n̂ is unchanged, and the incident p̂ = d̂ × n̂ projects on the outgoing
//! `r̂ × n̂` with `(r̂ × n̂)·(d̂ × n̂) = d̂·r̂`. So the constant is `(k²/4π)² = k⁴/(16π²) = π²/λ⁴`. It
//! replaces S2.20's surface prefactor `cos θ_o/λ²` (the Smythe aperture's `cos²θ_o/λ²` over
//! the projected area): a volume radiates as a dipole density and has no aperture.
//!
//! # Thin slab
//! For [`Region::ThinSlab`] (thickness t, δε fully correlated across it, `R₂(ξ_t) = R(ξ_t, 0)`),
//! the brute force's `β` per unit volume `t A` tends to `(k⁴/16π²) t Σ_α K_α(h_t) M_dip S_α`
//! with the surface term `K_α = surface_coherence_term` (the section of the 3-D coherence by
//! the plane, `σ_zz` included, `h_t` the tangential part of h): `∫∫dz₁dz₂ → t²`. In the surface
//! kernel's own form, radiance `L = β t / cos θ_o = (cos θ_o/λ²) M_slab Σ K_α S_α`, this is the
//! surface material `(p₂, M_slab)` with `M_slab = (π t/λ)² M_dip / cos²θ_o`.
//!
//! Non-Gaussian R: the 3-D exponential correlation is `KCorrelation::<_, 3>(σ², ℓ², γ = 3)`
//! (2-D, on a slab: `γ = 2`), blurred through its Gaussian-mixture fit to 1e-7 of `p(0)`.

use gmueller::frame::{Frame, mueller_to_frames, stokes_to_frame};
use gmueller::interaction::coherence::{surface_coherence_term, volume_coherence_term};
use gmueller::interaction::{Full, Kernel, Partial};
use gmueller::jones::JonesMatrix;
use gmueller::medium::{Dipole, RandomMedium};
use gmueller::mueller::Mueller;
use gmueller::packet::{Channel, CoherenceShape, WavePacket};
use gmueller::psd::{ClosedForm, ClosedFormBlur, GaussianPsd, KCorrelation, Psd};
use gmueller::stokes::Stokes;
use nalgebra::{Complex, Matrix2, Vector2, Vector3, Vector4};

use crate::brute_volume::{Permittivity, Region, VolumeScene};

/// The packet of `scene` with the incident Stokes vector `input`, in `Frame::sp(d̂, ẑ)`.
fn packet(scene: &VolumeScene, input: [f64; 4]) -> WavePacket<f64> {
    let light = &scene.light;
    let d = Vector3::from(light.travel());
    let shape = |t: [[f64; 2]; 2]| {
        CoherenceShape::new(Matrix2::new(t[0][0], t[0][1], t[1][0], t[1][1])).expect("shape")
    };
    let stokes = Stokes::new(input[0], input[1], input[2], input[3]).expect("input Stokes");
    let packet = WavePacket::new(
        stokes,
        shape(light.theta_x),
        shape(light.theta_y),
        Frame::sp(d, Vector3::z()).expect("packet frame"),
        light.wavelength,
    )
    .expect("packet");
    if light.sigma_zz.is_finite() {
        packet
            .with_longitudinal_coherence(light.sigma_zz)
            .expect("σ_zz")
    } else {
        packet
    }
}

/// The medium's `dI/dV` for `packet` toward `exit`, in the exit frame `Frame::sp(r̂, ẑ)`.
fn medium_intensity<P: Psd<f64, 3> + ClosedFormBlur<f64, 3>>(
    psd: P,
    packet: &WavePacket<f64>,
    exit: Vector3<f64>,
) -> [f64; 4] {
    let medium = RandomMedium::new(psd, Dipole);
    let kernel = Kernel::<Full, Partial>::default();
    let out = medium
        .differential_scattering(&kernel, packet, exit)
        .expect("medium evaluation");
    let exit_frame = Frame::sp(exit, Vector3::z()).expect("exit frame");
    let s = stokes_to_frame(&out.light, out.geometry.exit_frame(), &exit_frame).vector();
    [s[0], s[1], s[2], s[3]]
}

/// The kernel's β (Stokes vector in the exit frame `Frame::sp(r̂, ẑ)`) for incident Stokes
/// vector `input` (packet frame `Frame::sp(d̂, ẑ)`, `S0 = 1` unit irradiance) and exit `exit`:
/// the crate's random medium for the bulk regions (the 3-D exponential correlation through the
/// K-correlation's mixture fit to 1e-7 of `p(0)`), the surface coherence term for the thin slab.
///
/// # Panics
/// On parameters the crate rejects (invalid shapes, Stokes vectors or packets; an exit along ±ẑ).
#[must_use]
pub fn predict(scene: &VolumeScene, input: [f64; 4], exit: [f64; 3]) -> [f64; 4] {
    let r = Vector3::from(exit);
    match (scene.region, scene.matter) {
        (Region::Bulk { .. }, Permittivity::Gaussian { sigma, ell }) => {
            let psd = GaussianPsd::<f64, 3>::isotropic(sigma, ell).expect("PSD");
            medium_intensity(psd, &packet(scene, input), r)
        }
        (Region::Bulk { .. }, Permittivity::Exponential { sigma, ell }) => {
            let k = KCorrelation::<f64, 3>::new(sigma * sigma, ell * ell, 3.0).expect("PSD");
            let (fit, _, _) = k.mixture_fit_to(1e-7).expect("mixture fit");
            medium_intensity(fit, &packet(scene, input), r)
        }
        (Region::ThinSlab { .. }, _) => predict_from_primitives(scene, input, exit),
    }
}

/// [`predict`] assembled from the derivation in the module docs and the crate's primitives,
/// without `gmueller::medium` (module docs).
///
/// # Panics
/// As [`predict`].
#[must_use]
pub fn predict_from_primitives(scene: &VolumeScene, input: [f64; 4], exit: [f64; 3]) -> [f64; 4] {
    let light = &scene.light;
    let v = |a: [f64; 3]| Vector3::new(a[0], a[1], a[2]);
    let z = Vector3::z();
    let d = v(light.travel());
    let r = v(exit);
    let packet_frame = Frame::sp(d, z).expect("packet frame");
    let exit_frame = Frame::sp(r, z).expect("exit frame");
    let shape = |t: [[f64; 2]; 2]| {
        CoherenceShape::new(Matrix2::new(t[0][0], t[0][1], t[1][0], t[1][1])).expect("shape")
    };
    let stokes = Stokes::new(input[0], input[1], input[2], input[3]).expect("input Stokes");
    let mut packet = WavePacket::new(
        stokes,
        shape(light.theta_x),
        shape(light.theta_y),
        packet_frame,
        light.wavelength,
    )
    .expect("packet");
    if light.sigma_zz.is_finite() {
        packet = packet
            .with_longitudinal_coherence(light.sigma_zz)
            .expect("σ_zz");
    }
    // h = k(r̂ + ŝ), ŝ = −d̂ toward the source.
    let h = (r - d) * packet.wavenumber();
    let channels = [Channel::X, Channel::Y, Channel::Half];
    let weights: [f64; 3] = match (scene.region, scene.matter) {
        (Region::Bulk { .. }, Permittivity::Gaussian { sigma, ell }) => {
            let psd = GaussianPsd::<f64, 3>::isotropic(sigma, ell).expect("PSD");
            channels.map(|c| volume_coherence_term(&psd, &ClosedForm, &packet, c, &h).expect("K³"))
        }
        (Region::Bulk { .. }, Permittivity::Exponential { sigma, ell }) => {
            let k = KCorrelation::<f64, 3>::new(sigma * sigma, ell * ell, 3.0).expect("PSD");
            let (fit, _, _) = k.mixture_fit_to(1e-7).expect("mixture fit");
            channels.map(|c| volume_coherence_term(&fit, &ClosedForm, &packet, c, &h).expect("K³"))
        }
        (Region::ThinSlab { thickness, .. }, matter) => {
            let surface = Frame::new(Vector3::x(), Vector3::y(), z).expect("surface");
            let ht = Vector2::new(h[0], h[1]);
            let k2 = match matter {
                Permittivity::Gaussian { sigma, ell } => {
                    let psd = GaussianPsd::<f64, 2>::isotropic(sigma, ell).expect("PSD");
                    channels.map(|c| {
                        surface_coherence_term(&psd, &ClosedForm, &packet, c, &surface, &ht)
                    })
                }
                Permittivity::Exponential { sigma, ell } => {
                    let k =
                        KCorrelation::<f64, 2>::new(sigma * sigma, ell * ell, 2.0).expect("PSD");
                    let (fit, _, _) = k.mixture_fit_to(1e-7).expect("mixture fit");
                    channels.map(|c| {
                        surface_coherence_term(&fit, &ClosedForm, &packet, c, &surface, &ht)
                    })
                }
            };
            k2.map(|k| k * thickness)
        }
    };
    // The dipole: Jones diag(1, cos Θ) in the scattering plane's s/p frames.
    let cos_t = d.dot(&r);
    let n = d.cross(&r);
    let n = if n.norm() > 1e-9 {
        n.normalize()
    } else {
        packet_frame.x() // forward or backward: any n̂ ⊥ d̂
    };
    let plane_in = Frame::new(n, d.cross(&n), d).expect("scattering-plane frame in");
    let plane_out = Frame::new(n, r.cross(&n), r).expect("scattering-plane frame out");
    let zero = Complex::new(0.0, 0.0);
    let jones = JonesMatrix::from_matrix(Matrix2::new(
        Complex::new(1.0, 0.0),
        zero,
        zero,
        Complex::new(cos_t, 0.0),
    ))
    .expect("dipole Jones matrix");
    let m = mueller_to_frames(
        &Mueller::from_jones(&jones),
        &plane_in,
        &packet_frame,
        &plane_out,
        &exit_frame,
    )
    .matrix();
    let (sx, sy) = (packet.sx(), packet.sy());
    let parts = [
        Vector4::new(sx, sx, 0.0, 0.0),
        Vector4::new(sy, -sy, 0.0, 0.0),
        Vector4::new(0.0, 0.0, input[2], input[3]),
    ];
    let lambda = light.wavelength;
    let constant = std::f64::consts::PI.powi(2) / lambda.powi(4);
    let mut out = Vector4::zeros();
    for (w, s) in weights.iter().zip(&parts) {
        out += m * s * (*w * constant);
    }
    [out[0], out[1], out[2], out[3]]
}

#[cfg(test)]
mod tests {
    use super::{predict, predict_from_primitives};
    use crate::volume_cases::{Size, cases};

    /// The medium (`gmueller::medium`) equals the assembly from the crate's primitives and this
    /// module's derivation, at every exit and input polarization of every bulk configuration.
    #[test]
    fn the_medium_equals_the_assembly_from_primitives() {
        let mut compared = 0;
        for case in cases(Size::Full) {
            for (_, exit) in &case.exits {
                for (_, input) in &case.inputs {
                    let a = predict(&case.scene, *input, *exit);
                    let b = predict_from_primitives(&case.scene, *input, *exit);
                    // On the scale of the unpolarized light at this exit (a polarized input
                    // can be extinguished there: p light at 90°, where the two computations
                    // round cos Θ differently).
                    let scale =
                        predict_from_primitives(&case.scene, [1.0, 0.0, 0.0, 0.0], *exit)[0];
                    for (x, y) in a.iter().zip(&b) {
                        assert!(
                            (x - y).abs() <= 1e-11 * scale,
                            "{}: {a:?} vs {b:?} at {exit:?}",
                            case.name
                        );
                    }
                    compared += 1;
                }
            }
        }
        assert!(compared > 100, "{compared} comparisons");
    }
}
