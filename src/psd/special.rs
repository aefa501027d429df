//! Special functions used at construction time (f64): ln Γ and ln Γ(x)/Γ(x − a).

/// The Lanczos approximation's shift `g` (g = 7, n = 9).
const LANCZOS_G: f64 = 7.0;

/// The Lanczos coefficients for `g = 7`, `n = 9`.
const LANCZOS_C: [f64; 9] = [
    0.99999999999980993,
    676.5203681218851,
    -1259.1392167224028,
    771.32342877765313,
    -176.61502916214059,
    12.507343278686905,
    -0.13857109526572012,
    9.9843695780195716e-6,
    1.5056327351493116e-7,
];

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, n = 9; relative error ≈ 1e-15).
pub(crate) fn ln_gamma(x: f64) -> f64 {
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1 − x) = π / sin(πx).
        let pi = core::f64::consts::PI;
        return (pi / (pi * x).sin()).abs().ln() - ln_gamma(1.0 - x);
    }
    let z = x - 1.0;
    let t = z + LANCZOS_G + 0.5;
    0.5 * core::f64::consts::TAU.ln() + (z + 0.5) * t.ln() - t + lanczos_series(z).ln()
}

/// The Lanczos series `A(z) = c₀ + Σᵢ cᵢ/(z + i)` of [`ln_gamma`] (`z = x − 1`).
fn lanczos_series(z: f64) -> f64 {
    LANCZOS_C
        .iter()
        .enumerate()
        .skip(1)
        .fold(LANCZOS_C[0], |acc, (i, c)| acc + c / (z + i as f64))
}

/// `ln Γ(x) − ln Γ(x − a)` for `x − a > 0`, `a ≥ 0`, without the cancellation of the plain
/// difference (which loses all digits once `ln Γ(x) ≫ 1/ε`, and is `∞ − ∞` above `x ≈ 1e305`).
///
/// # Formula
/// ```text
/// ln Γ(x) = ½ ln 2π + (x − ½) ln t_x − t_x + ln A(x − 1),   t_x = x + g − ½   (Lanczos, g = 7)
/// ln Γ(x) − ln Γ(y) = a ln t_x − (y − ½) ln(1 − a/t_x) − a + ln(A(x − 1)/A(y − 1)),   y = x − a
/// ```
/// (for `y ≥ ½`; below, the plain difference, where both terms are moderate).
pub(crate) fn ln_gamma_ratio(x: f64, a: f64) -> f64 {
    let y = x - a;
    if y < 0.5 {
        return ln_gamma(x) - ln_gamma(y);
    }
    let tx = x + LANCZOS_G - 0.5;
    a * tx.ln() - (y - 0.5) * (-a / tx).ln_1p() - a
        + (lanczos_series(x - 1.0) / lanczos_series(y - 1.0)).ln()
}

#[cfg(test)]
mod tests {
    use super::{ln_gamma, ln_gamma_ratio};

    #[test]
    fn ln_gamma_ratio_known_values() {
        // Γ(x)/Γ(x − 1) = x − 1 and Γ(x)/Γ(x − 2) = (x − 1)(x − 2) exactly; Γ(n + ½)/Γ(n) from
        // Γ(½) = √π and the recurrence; large x: the plain difference has cancelled, the ratio
        // x − 1 is exact.
        for x in [1.5_f64, 2.0, 3.7, 10.0, 1e3, 1e8, 1e15, 1e300, 1e308] {
            let r = ln_gamma_ratio(x, 1.0);
            assert!(
                (r - (x - 1.0).ln()).abs() <= 1e-14 * (x - 1.0).ln().abs().max(1.0),
                "{x}: {r}"
            );
        }
        for x in [2.5_f64, 7.0, 1e6, 1e200] {
            let want = (x - 1.0).ln() + (x - 2.0).ln();
            assert!((ln_gamma_ratio(x, 2.0) - want).abs() <= 1e-14 * want.abs().max(1.0));
        }
        // Γ(5)/Γ(4.5) = 24 / (3.5·2.5·1.5·0.5·√π).
        let g45 = 3.5 * 2.5 * 1.5 * 0.5 * core::f64::consts::PI.sqrt();
        assert!((ln_gamma_ratio(5.0, 0.5) - (24.0 / g45).ln()).abs() < 1e-14);
        // Γ(y + ½)/Γ(y) = √y (1 − 1/(8y) + O(y⁻²)) for large y = x − ½.
        let y = 1e12_f64 - 0.5;
        let x = y + 0.5;
        let want = 0.5 * y.ln() + (-1.0 / (8.0 * y)).ln_1p();
        assert!((ln_gamma_ratio(x, 0.5) - want).abs() < 1e-13);
        // Small y: the plain difference (y < ½).
        assert!((ln_gamma_ratio(1.2, 1.0) - 0.2f64.ln()).abs() < 1e-13);
    }

    #[test]
    fn ln_gamma_known_values() {
        // Γ(n) = (n−1)!, Γ(½) = √π, Γ(x + 1) = x Γ(x) (exact identities).
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-13);
        assert!((ln_gamma(0.5) - core::f64::consts::PI.sqrt().ln()).abs() < 1e-13);
        let g10_5: f64 =
            (0..10).map(|k| k as f64 + 0.5).product::<f64>() * core::f64::consts::PI.sqrt();
        assert!((ln_gamma(10.5) - g10_5.ln()).abs() < 1e-12);
        assert!(ln_gamma(1.0).abs() < 1e-14 && ln_gamma(2.0).abs() < 1e-14);
    }
}
