//! A short tour: what a polarizer and a quarter-wave plate do to light.
//!
//! Run with `cargo run --release --example quickstart`.

use gmueller::jones::JonesMatrix;
use gmueller::mueller::Mueller;
use gmueller::stokes::Stokes;

fn main() -> Result<(), gmueller::Error> {
    let unpolarized = Stokes::<f64>::unpolarized(1.0)?;
    let polarizer =
        Mueller::from_jones(&JonesMatrix::linear_polarizer(core::f64::consts::FRAC_PI_4));
    let after = polarizer * unpolarized;
    println!(
        "unpolarized light through a +45° polarizer: {:?}",
        after.vector().as_slice()
    );
    let qwp = Mueller::from_jones(&JonesMatrix::linear_retarder(
        0.0,
        core::f64::consts::FRAC_PI_2,
    ));
    println!(
        "…then a quarter-wave plate, fast axis x̂:    {:?}",
        (qwp * after).vector().as_slice()
    );
    Ok(())
}
