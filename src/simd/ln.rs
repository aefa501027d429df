//! The vector natural logarithm `vln`: exponent and mantissa by bit operations, an odd
//! polynomial in `s = f/(2 + f)`, and Cody–Waite `k ln 2`, branch-free, on every lane.

use pulp::Simd;

use super::Lanes;

/// `ln x` on every lane for positive normal finite `x`, within 1 ulp of the standard library's
/// `ln` as measured (so within 2 ulp of the correctly rounded value): every positive normal
/// f32, and 3 · 10⁵ f64 points (log-spaced on `[2⁻⁵³, 1]`, uniform on `(0, 1]`, bit patterns
/// across the whole normal range, powers of two and `√2` with their neighbours), on every
/// back-end (see the tests).
///
/// # Formula
/// ```text
/// x = 2ᵏ m,  m ∈ [√½, √2)   (Lanes::vfrexp, bit operations),  f = m − 1 (exact)
/// s = f / (2 + f),  z = s²,  R = z Σⱼ Lgⱼ zʲ⁻¹ ≈ ln((1 + s)/(1 − s))/s − 2   (|s| ≤ 3 − 2√2)
/// ln m = 2s + s R = f − (f²/2 − s (f²/2 + R))
/// ln x = k LN2_HI − ((f²/2 − (s (f²/2 + R) + k LN2_LO)) − f)   (k LN2_HI exact)
/// ```
/// `Lgⱼ` are fdlibm's seven (f64) or FreeBSD's four single-precision ones (f32), see
/// [`Lanes::LOG_POLY`]. `x = 1` gives exactly 0. Zero, negative, subnormal, infinite and NaN
/// inputs give unspecified values (finite: the bit operations read them as some normal
/// number; NaN is not propagated), never a panic.
#[inline(always)]
pub(crate) fn vln<S: Simd, F: Lanes>(s: S, x: F::V<S>) -> F::V<S> {
    let c = |v: f64| F::vlit(s, v);
    let (k, m) = F::vfrexp(s, x);
    let f = F::vsub(s, m, c(1.0));
    let sf = F::vdiv(s, f, F::vadd(s, c(2.0), f));
    let z = F::vmul(s, sf, sf);
    let mut p = c(F::LOG_POLY[0]);
    for &g in &F::LOG_POLY[1..] {
        p = F::vmul_add(s, p, z, c(g));
    }
    let r = F::vmul(s, p, z);
    let hfsq = F::vmul(s, F::vmul(s, c(0.5), f), f);
    // s (f²/2 + R) + k LN2_LO
    let t = F::vmul_add(s, sf, F::vadd(s, hfsq, r), F::vmul(s, k, c(F::LN2_LO)));
    // f − (f²/2 − t), then + k LN2_HI
    let lm = F::vsub(s, f, F::vsub(s, hfsq, t));
    F::vmul_add(s, k, c(F::LN2_HI), lm)
}

#[cfg(test)]
mod tests {
    use pulp::Simd;

    use super::vln;
    use crate::simd::Lanes;
    use crate::simd::check::{Float, Worst, on_back_ends, track, ulps};
    use crate::simd::driver::LaneMap;

    struct Ln;

    impl<F: Lanes> LaneMap<F, 1, 1> for Ln {
        #[inline(always)]
        fn eval<S: Simd>(&self, s: S, x: [F::V<S>; 1]) -> [F::V<S>; 1] {
            [vln::<S, F>(s, x[0])]
        }
    }

    /// `vln` on every back-end against the standard library's `ln`: the worst case.
    fn worst<F: Float>(xs: &[F]) -> Worst<F> {
        let zero = F::of(0.0);
        let mut worst = (0, zero, zero, zero);
        let want: Vec<F> = xs.iter().map(|x| x.std_ln()).collect();
        on_back_ends(&Ln, xs, |_, [got]| {
            for ((&x, &g), &w) in xs.iter().zip(got).zip(&want) {
                track(&mut worst, ulps(g, w), x, g, w);
            }
        });
        worst
    }

    /// `n + 1` points `2^(lo (i/n))`, the uniform `i/n`, the bit patterns from the smallest
    /// normal number to the largest in `n` odd steps, and `specials` with their 3 neighbours on
    /// either side (those that are normal and finite).
    fn points<F: Float>(
        lo: f64,
        n: usize,
        bits: (u64, u64),
        from_bits: fn(u64) -> F,
        specials: &[F],
        up: fn(F) -> F,
        down: fn(F) -> F,
    ) -> Vec<F> {
        let mut xs: Vec<F> = (0..=n)
            .map(|i| F::of((lo * i as f64 / n as f64).exp2()))
            .collect();
        xs.extend((1..=n).map(|i| F::of(i as f64 / n as f64)));
        let step = ((bits.1 - bits.0) / n as u64) | 1;
        xs.extend((bits.0..=bits.1).step_by(step as usize).map(from_bits));
        xs.push(from_bits(bits.1));
        for &x in specials {
            let (mut u, mut d) = (x, x);
            xs.push(x);
            for _ in 0..3 {
                u = up(u);
                d = down(d);
                xs.extend([u, d]);
            }
        }
        let (min, max) = (from_bits(bits.0), from_bits(bits.1));
        xs.retain(|&x| x >= min && x <= max);
        xs
    }

    #[test]
    fn vln_f64_within_1_ulp() {
        let mut specials = vec![
            1.0,
            2f64.powi(-24),
            2f64.powi(-53),
            core::f64::consts::SQRT_2,
            core::f64::consts::FRAC_1_SQRT_2,
            // m's threshold on the upper word (0x3ff6a09e_00000000) and its neighbour below.
            f64::from_bits(0x3ff6_a09e_0000_0000),
            f64::from_bits(0x3ff6_a09d_ffff_ffff),
            f64::MIN_POSITIVE.next_up(),
            f64::MAX.next_down(),
            core::f64::consts::E,
        ];
        specials.extend((-1021..=1023).map(|e| 2f64.powi(e)));
        let xs = points(
            -53.0,
            100_000,
            (f64::MIN_POSITIVE.to_bits(), f64::MAX.to_bits()),
            f64::from_bits,
            &specials,
            f64::next_up,
            f64::next_down,
        );
        let (u, x, g, w) = worst(&xs);
        println!(
            "vln f64: max {u} ulp at x = {x:e} ({g:e}, std {w:e}), {} points",
            xs.len()
        );
        assert!(u <= 1, "vln({x:e}) = {g:e}, std {w:e}: {u} ulp");
    }

    #[test]
    fn vln_f32_within_1_ulp() {
        let mut specials = vec![
            1.0,
            2f32.powi(-24),
            core::f32::consts::SQRT_2,
            core::f32::consts::FRAC_1_SQRT_2,
            f32::from_bits(0x3fb5_04f3),
            f32::MIN_POSITIVE.next_up(),
            f32::MAX.next_down(),
            core::f32::consts::E,
        ];
        specials.extend((-125..=127).map(|e| 2f32.powi(e)));
        let xs = points(
            -24.0,
            100_000,
            (
                u64::from(f32::MIN_POSITIVE.to_bits()),
                u64::from(f32::MAX.to_bits()),
            ),
            |b| f32::from_bits(b as u32),
            &specials,
            f32::next_up,
            f32::next_down,
        );
        let (u, x, g, w) = worst(&xs);
        println!(
            "vln f32: max {u} ulp at x = {x:e} ({g:e}, std {w:e}), {} points",
            xs.len()
        );
        assert!(u <= 1, "vln({x:e}) = {g:e}, std {w:e}: {u} ulp");
    }

    /// Every f32 of the sampler's range `[2⁻²⁴, 1]` (24 · 2²³ ≈ 2 · 10⁸ inputs), or with
    /// `GMUELLER_VLN_ALL=1` every positive normal f32 (≈ 2.1 · 10⁹); slow, run on demand.
    #[test]
    #[ignore = "exhaustive, slow (2.5 min with GMUELLER_VLN_ALL=1): cargo test --lib simd::ln -- --ignored"]
    fn vln_f32_exhaustive() {
        let all = std::env::var_os("GMUELLER_VLN_ALL").is_some();
        let lo = if all {
            f32::MIN_POSITIVE
        } else {
            2f32.powi(-24)
        }
        .to_bits();
        let hi = if all { f32::MAX } else { 1.0 }.to_bits();
        let mut worst_all = (0, 0.0, 0.0, 0.0);
        let mut start = lo;
        while start <= hi {
            let end = hi.min(start + (1 << 22) - 1);
            let xs: Vec<f32> = (start..=end).map(f32::from_bits).collect();
            let w = worst(&xs);
            if w.0 > worst_all.0 {
                worst_all = w;
            }
            start = end + 1;
        }
        let (u, x, g, w) = worst_all;
        println!(
            "vln f32, every input from {:e} to {:e}: max {u} ulp at x = {x:e} ({g:e}, std {w:e})",
            f32::from_bits(lo),
            f32::from_bits(hi)
        );
        assert!(u <= 1, "vln({x:e}) = {g:e}, std {w:e}: {u} ulp");
    }

    /// Zero, negative, subnormal, infinite and NaN inputs: finite values, no panic.
    #[test]
    fn vln_outside_the_domain_is_finite() {
        let xs = [
            0.0,
            -0.0,
            -1.0,
            -f64::MIN_POSITIVE,
            f64::MIN_POSITIVE / 2.0,
            f64::from_bits(1),
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            -f64::NAN,
            f64::from_bits(u64::MAX),
        ];
        on_back_ends(&Ln, &xs, |what, [got]| {
            assert!(got.iter().all(|g| g.is_finite()), "{what}: {got:?}");
        });
        let xs = xs.map(|x| x as f32);
        on_back_ends(&Ln, &xs, |what, [got]| {
            assert!(got.iter().all(|g| g.is_finite()), "{what}: {got:?}");
        });
        let xs = [f32::from_bits(1), f32::from_bits(u32::MAX)];
        on_back_ends(&Ln, &xs, |what, [got]| {
            assert!(got.iter().all(|g| g.is_finite()), "{what}: {got:?}");
        });
    }
}
