//! Small seeded generators for inputs outside proptest, so that every run sees the same inputs:
//! [`SplitMix64`] (Steele, Lea & Flood 2014), and [`Lcg`], which draws the exit sets of the
//! crate's batch property tests from a proptest-drawn seed.
//!
//! The floats are the top 53 bits of the output over 2⁵³ (exact in f64): [`SplitMix64::unit`]
//! in `[0, 1)`, [`SplitMix64::signed`] = `2·unit − 1` in `[−1, 1)`.

/// The generator; its state is the public field, so `SplitMix64(seed)` seeds it.
#[derive(Debug, Clone)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[−1, 1)`.
    pub fn signed(&mut self) -> f64 {
        self.unit() * 2.0 - 1.0
    }

    /// Uniform in `[lo, hi)` (up to rounding).
    pub fn uniform_in(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Log-uniform in `[lo, hi)` (up to rounding), `0 < lo < hi`.
    pub fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.uniform_in(lo.ln(), hi.ln()).exp()
    }
}

/// The 64-bit LCG with Knuth's MMIX constants. The crate's batch property tests draw their exit
/// sets with it from a seed; it stays beside [`SplitMix64`] because their recorded regression
/// cases name seeds of this generator (replayed through another, they would test other exits).
///
/// ```
/// use gmueller::verify::rng::Lcg;
/// let mut a = Lcg(7);
/// let x = a.uniform();
/// assert!((0.0..1.0).contains(&x));
/// assert_eq!(Lcg(7).uniform(), x);
/// ```
#[derive(Debug, Clone)]
pub struct Lcg(pub u64);

impl Lcg {
    /// Uniform in `[0, 1)`: the top 53 bits of the next state over 2⁵³.
    pub fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

impl Lcg {
    /// A renderer's vertex about the normal `+z`: a direction to the light, cosine-weighted
    /// (the next-event estimation of a diffuse environment), and an exit — for even `i` within
    /// ±0.3 rad of the light's mirror direction in polar angle and azimuth (where the lobes
    /// are), for odd `i` uniform in solid angle over the hemisphere; polar angles at most
    /// 1.5 rad. Unit vectors `(to_light, exit)` in the frame's coordinates.
    pub fn light_and_exit(&mut self, i: usize) -> ([f64; 3], [f64; 3]) {
        use std::f64::consts::{PI, TAU};
        let ti = self.uniform().sqrt().asin().min(1.5);
        let pi = TAU * self.uniform();
        let (to, po) = if i.is_multiple_of(2) {
            let to = (ti + (self.uniform() - 0.5) * 0.6).abs().min(1.5);
            (to, pi + PI + (self.uniform() - 0.5) * 0.6)
        } else {
            let to = self.uniform().acos().min(1.5);
            (to, TAU * self.uniform())
        };
        let polar = |t: f64, p: f64| [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()];
        (polar(ti, pi), polar(to, po))
    }
}
