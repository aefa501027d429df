//! A short, narrated tour of the crate: what a polarizer, a quarter-wave plate, a gold mirror and
//! a frame rotation do to light.
//!
//! Run with `cargo run --release --example quickstart`.

use core::f64::consts::{FRAC_PI_2, FRAC_PI_4};

use gmueller::frame::rotation_mueller;
use gmueller::fresnel;
use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::stokes::Stokes;
use num_complex::Complex;

fn show(label: &str, s: &Stokes<f64>) {
    // Print rounding noise (−1e-17) as +0.0000 rather than −0.0000.
    let v = s.vector().map(|x| if x.abs() < 5e-5 { 0.0 } else { x });
    println!(
        "  {label:<44} S = ({:+.4}, {:+.4}, {:+.4}, {:+.4})   DoP = {:.3}",
        v[0],
        v[1],
        v[2],
        v[3],
        s.degree_of_polarization()
    );
}

fn main() -> Result<(), gmueller::Error> {
    println!(
        "gmueller quick start: Stokes vectors (S0, S1, S2, S3), e^(-iωt), S3 = 2 Im(Ex* Ey)\n"
    );

    let light = Stokes::unpolarized(1.0)?;
    println!("1. Unpolarized light of unit intensity:");
    show("incident", &light);

    println!("\n2. A linear polarizer at +45° keeps half of it, polarized along +45° (S2 > 0):");
    let polarizer = Mueller::from_jones(&JonesMatrix::linear_polarizer(FRAC_PI_4));
    let linear45 = polarizer * light;
    show("after the polarizer", &linear45);

    println!("\n3. A quarter-wave plate with its fast axis along x̂ turns +45° light circular.");
    println!("   In this crate's convention that is S3 = +1 (Mitsuba 3 and py-pol print -1):");
    let qwp = Mueller::from_jones(&JonesMatrix::linear_retarder(0.0, FRAC_PI_2));
    let circular = qwp * linear45;
    show("after the quarter-wave plate", &circular);

    println!("\n4. A gold mirror (η ≈ 0.18 + 3.07i near 633 nm) at 45° incidence, Stokes x̂ = s:");
    let gold = Complex::new(0.18, 3.07);
    let mirror = Mueller::from_jones(&fresnel::reflection(FRAC_PI_4.cos(), gold));
    let m = mirror.matrix();
    println!(
        "   reflectance of unpolarized light M00 = {:.4}, of s-light M00 + M01 = {:.4}, of p-light M00 − M01 = {:.4}",
        m[(0, 0)],
        m[(0, 0)] + m[(0, 1)],
        m[(0, 0)] - m[(0, 1)]
    );
    show("circular light after the mirror", &(mirror * circular));
    show("+45° light after the mirror", &(mirror * linear45));

    println!("\n5. A frame rotation changes the description, not the light: turning the basis by");
    println!(
        "   ψ = 45° about the beam (S2.4 with φ = −ψ) maps +45° linear light to S1 = +intensity:"
    );
    let rotated = rotation_mueller(-FRAC_PI_4) * linear45;
    show("+45° light in the rotated frame", &rotated);
    Ok(())
}
