//! The n = 3 kernel (S2.20 with the 3-D coherence term `K³`, `σ_zz`, the Rayleigh dipole's Mueller
//! matrix; `gmueller_validation::kernel_side_volume`) against the brute-force 3-D first-Born
//! vector field sum (`gmueller_validation::brute_volume`: a random permittivity field, GSM
//! light, far field summed over voxels, matter averaged over realizations with a fixed seed):
//! reduced versions of the wave tracer's three volumetric configurations
//! (`gmueller_validation::volume_cases`, `Size::Test`), each asserting the tracer's verdict —
//! S0, S1–S3 and the degree of polarization within max(3 s.e., 2 %) for every exit and input
//! polarization — and that the wrong predictions are rejected where they should be:
//! - `volume_cube` (`θ_x ≠ θ_y`, five inputs): the opposite circular handedness (S3 negated) for
//!   circular input and a mirrored frame (S2 negated) for +45° input, at every exit where that
//!   component keeps 10 % of S0;
//! - `volume_backscatter`: the prediction with `σ_zz → ∞` (10³ µm) at the backscatter
//!   direction itself and around it;
//! - `volume_exponential` (a second R: exponential, the 3-D K-correlation with γ = 3, blurred
//!   through its Gaussian-mixture fit): a Gaussian R of the same σ and ℓ;
//! - `volume_thin_slab` (the 2-D `surface_coherence_term` × t as the thin-slab limit): the
//!   section of the coherence without `σ_zz`.
//!
//! The fixed seed is not a lucky one: with seeds 1–12 instead, all 48 reduced comparisons
//! passed (`ok()`: every check, every rejection). About 5–11 s on 2 cores.

use crate::volume_cases::{self, Case, Comparison, Row, Size, Wrong};

const SEED: u64 = 20220801;

fn case(name: &str) -> Case {
    volume_cases::cases(Size::Test)
        .into_iter()
        .find(|c| c.name == name)
        .expect("configuration")
}

/// Runs `case` and prints the comparison of every row.
fn run(case: &Case) -> Comparison {
    let est = volume_cases::run(case, SEED, 2, &|| {});
    let cmp = volume_cases::compare(case, &est);
    for r in &cmp.rows {
        let (angles, _) = case.exits[r.exit];
        let b = &r.brute;
        println!(
            "{} {:>11} ψ = {:>5.1}°, a = {:>6.1}°: brute S0 {:.4e} ± {:.2} %, kernel {:+.2} %, \
             DoP {:.4} ± {:.4} vs {:.4}, failed {}{}",
            case.name,
            case.inputs[r.input].0,
            angles[0],
            angles[1],
            b.mean[0],
            100.0 * b.se[0] / b.mean[0],
            100.0 * (r.kernel[0] / b.mean[0] - 1.0),
            b.dop,
            b.dop_se,
            crate::brute_volume::dop(&r.kernel),
            cmp.failures(r),
            r.wrong
                .iter()
                .zip(&case.wrong)
                .map(|(w, name)| format!(
                    "; {} S0 {:+.1} %, failed {}",
                    name.name(),
                    100.0 * (w[0] / b.mean[0] - 1.0),
                    volume_cases::failures(b, w, cmp.floor)
                ))
                .collect::<String>()
        );
    }
    println!("{}: {}", case.name, cmp.verdict());
    cmp
}

/// The comparison must be informative: median relative s.e. of S0 below `max`.
fn assert_informative(case: &Case, cmp: &Comparison, max: f64) {
    let se = cmp.median_rel_se();
    assert!(
        se < max,
        "{}: median s.e. {:.2} % too large",
        case.name,
        100.0 * se
    );
}

/// Exits where wrong prediction `w` fails the criterion for input `input`.
fn rejected_at(cmp: &Comparison, w: usize, input: usize) -> Vec<usize> {
    exits_where(cmp, input, |r| {
        volume_cases::failures(&r.brute, &r.wrong[w], cmp.floor) > 0
    })
}

/// Exits of input `input` whose row satisfies `pred`.
fn exits_where(cmp: &Comparison, input: usize, pred: impl Fn(&Row) -> bool) -> Vec<usize> {
    cmp.rows
        .iter()
        .filter(|r| r.input == input && pred(r))
        .map(|r| r.exit)
        .collect()
}

#[test]
fn volume_cube_matches_brute_force_for_every_polarization() {
    let c = case("volume_cube");
    let cmp = run(&c);
    assert_informative(&c, &cmp, 0.04);
    let (ok, all) = cmp.passed();
    assert_eq!(ok, all, "{}", cmp.verdict());
    let input = |name: &str| c.inputs.iter().position(|i| i.0 == name).expect("input");
    let (circ, diag) = (input("circular"), input("+45°"));
    let w = |x: Wrong| {
        c.wrong
            .iter()
            .position(|&v| v == x)
            .expect("wrong prediction")
    };
    // Where the scattered light keeps a circular (or diagonal) part of 10 % of S0 or more, the
    // sign errors must be caught; such exits must exist (the dipole turns circular light
    // linear at 90°, so not every exit has one).
    for (input, comp, wrong) in [(circ, 3, Wrong::FlipS3), (diag, 2, Wrong::FlipS2)] {
        let strong = exits_where(&cmp, input, |r| r.kernel[comp].abs() > 0.1 * r.kernel[0]);
        let rejected = rejected_at(&cmp, w(wrong), input);
        println!(
            "{}: {} rejected at exits {rejected:?}, S{comp} ≥ 10 % at {strong:?}",
            c.inputs[input].0,
            wrong.name()
        );
        assert!(strong.len() >= 3, "too few exits with S{comp}");
        assert!(
            strong.iter().all(|e| rejected.contains(e)),
            "{} not rejected everywhere S{comp} is large",
            wrong.name()
        );
    }
}

#[test]
fn volume_backscatter_sees_the_longitudinal_coherence() {
    let c = case("volume_backscatter");
    let cmp = run(&c);
    assert_informative(&c, &cmp, 0.04);
    assert!(cmp.ok(), "{}", cmp.verdict());
    // The backscatter direction itself (ψ = 180°) and its neighbours reject σ_zz → ∞ for every
    // input; the exit list starts with them.
    assert_eq!(c.exits[0].0[0], 180.0);
    for input in 0..c.inputs.len() {
        let at = rejected_at(&cmp, 0, input);
        for exit in 0..3 {
            assert!(
                at.contains(&exit),
                "input {}: σ_zz → ∞ not rejected at ψ = {}°",
                c.inputs[input].0,
                c.exits[exit].0[0]
            );
        }
    }
}

#[test]
fn volume_exponential_matches_through_the_mixture_fit() {
    let c = case("volume_exponential");
    let cmp = run(&c);
    assert_informative(&c, &cmp, 0.04);
    assert!(cmp.ok(), "{}", cmp.verdict());
}

#[test]
fn volume_thin_slab_is_the_surface_kernel() {
    let c = case("volume_thin_slab");
    let cmp = run(&c);
    assert_informative(&c, &cmp, 0.04);
    assert!(cmp.ok(), "{}", cmp.verdict());
}
