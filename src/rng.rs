//! Seeded pseudo-random numbers, one copy of each generator: synthetic
//! marker noise, the report's random trials and the grasp table's
//! placements (SplitMix64 and normal draws on it), and the seeded inputs
//! of the unit tests (the 64-bit linear congruential generator of Knuth's
//! MMIX). Not for cryptography; the streams are part of the
//! library's reproducible outputs (a seed gives the same noise on every
//! machine), so they must not change.

/// `2⁵³`: the uniform draws take the top 53 bits of a 64-bit word.
const TWO_53: f64 = (1u64 << 53) as f64;

/// SplitMix64 (Steele, Lea and Flood 2014; the seeding generator of
/// `xoshiro`): a Weyl sequence of step `0x9E37_79B9_7F4A_7C15` through a
/// bijective 64-bit mix.
#[derive(Debug, Clone)]
pub(crate) struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// The generator whose first draw advances `state` once.
    pub(crate) const fn new(state: u64) -> Self {
        SplitMix64 { state }
    }

    /// The next 64-bit word.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`: the top 53 bits over `2⁵³`.
    #[cfg_attr(not(feature = "report"), allow(dead_code))] // the experiments' draws
    pub(crate) fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / TWO_53
    }

    /// Uniform in `(0, 1)`: the top 53 bits plus one half over `2⁵³`
    /// (never 0, so its logarithm is finite).
    pub(crate) fn open_uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / TWO_53
    }

    /// Uniform in `[−1, 1)`.
    #[cfg_attr(not(feature = "report"), allow(dead_code))] // the experiments' draws
    pub(crate) fn symmetric(&mut self) -> f64 {
        2.0 * self.uniform() - 1.0
    }

    /// Uniform in `[a, b)`.
    #[cfg_attr(not(feature = "report"), allow(dead_code))] // the experiments' draws
    pub(crate) fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }

    /// Log-uniform in `[a, b)` (`0 < a < b`).
    #[cfg_attr(not(feature = "report"), allow(dead_code))] // the experiments' draws
    pub(crate) fn log_range(&mut self, a: f64, b: f64) -> f64 {
        (a.ln() + (b.ln() - a.ln()) * self.uniform()).exp()
    }
}

/// Standard normal samples by the Box–Muller transform of two
/// [`SplitMix64::open_uniform`] draws (both outputs used, the sine one
/// kept for the next call): synthetic observations and the simulated
/// experiments' noise.
#[derive(Debug, Clone)]
pub(crate) struct Gaussian {
    uniform: SplitMix64,
    spare: Option<f64>,
}

impl Gaussian {
    /// The generator of `seed` (its SplitMix64 state `seed ^ 0x9E37_79B9_7F4A_7C15`).
    pub(crate) fn new(seed: u64) -> Self {
        Gaussian {
            uniform: SplitMix64::new(seed ^ 0x9E37_79B9_7F4A_7C15),
            spare: None,
        }
    }

    /// One standard normal sample.
    pub(crate) fn sample(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (u, v) = (self.uniform.open_uniform(), self.uniform.open_uniform());
        let r = (-2.0 * u.ln()).sqrt();
        let t = 2.0 * std::f64::consts::PI * v;
        self.spare = Some(r * t.sin());
        r * t.cos()
    }
}

/// The 64-bit linear congruential generator of Knuth's MMIX
/// (`x ← 6364136223846793005 x + 1442695040888963407`): the seeded
/// matrices and configurations of the unit tests. (The statics' start
/// vector of inverse iteration, `statics/stability.rs`, draws the same
/// stream inline.)
#[cfg(test)]
#[derive(Debug, Clone)]
pub(crate) struct Lcg {
    state: u64,
}

#[cfg(test)]
impl Lcg {
    /// The generator whose first draw advances `state` once.
    pub(crate) const fn new(state: u64) -> Self {
        Lcg { state }
    }

    /// The next state.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.state = self
            .state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        self.state
    }

    /// Uniform in `[0, 1)`: the top 53 bits over `2⁵³`.
    #[cfg_attr(not(feature = "report"), allow(dead_code))] // the experiments' draws
    pub(crate) fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / TWO_53
    }

    /// Uniform in `[−0.5, 0.5)`.
    pub(crate) fn centered(&mut self) -> f64 {
        self.uniform() - 0.5
    }

    /// Uniform in `[−1, 1)`.
    #[cfg_attr(not(feature = "report"), allow(dead_code))] // the experiments' draws
    pub(crate) fn symmetric(&mut self) -> f64 {
        2.0 * self.uniform() - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The streams are outputs of the library (seeded noise, trial
    /// draws): the first draws of each generator, written out from the
    /// definitions (SplitMix64's first output of state 0 is the published
    /// 0xE220A8397B1DCDAF).
    #[test]
    fn the_streams_are_the_published_generators() {
        assert_eq!(SplitMix64::new(0).next_u64(), 0xE220_A839_7B1D_CDAF);
        let mut l = Lcg::new(1);
        assert_eq!(
            l.next_u64(),
            6_364_136_223_846_793_005u64.wrapping_add(1_442_695_040_888_963_407)
        );
        let mut a = SplitMix64::new(7);
        let mut b = SplitMix64::new(7);
        let word = b.next_u64();
        assert_eq!(a.uniform(), (word >> 11) as f64 / TWO_53);
        let mut g = Gaussian::new(3);
        let (x, y) = (g.sample(), g.sample());
        let mut u = SplitMix64::new(3 ^ 0x9E37_79B9_7F4A_7C15);
        let (p, q) = (u.open_uniform(), u.open_uniform());
        let r = (-2.0 * p.ln()).sqrt();
        assert_eq!(
            (x, y),
            (
                r * (std::f64::consts::TAU * q).cos(),
                r * (std::f64::consts::TAU * q).sin()
            )
        );
    }

    /// Every uniform draw lies in its interval; the normal samples have
    /// mean 0 and variance 1 to their sampling error.
    #[test]
    fn draws_lie_in_their_intervals_and_normals_are_standard() {
        let (mut s, mut l) = (SplitMix64::new(11), Lcg::new(11));
        for _ in 0..10_000 {
            assert!((0.0..1.0).contains(&s.uniform()));
            let o = s.open_uniform();
            assert!(o > 0.0 && o < 1.0);
            assert!((-1.0..1.0).contains(&s.symmetric()));
            assert!((-0.5..0.5).contains(&l.centered()));
            assert!((-1.0..1.0).contains(&l.symmetric()));
            let r = s.log_range(1e-3, 1.0);
            assert!((1e-3..1.0 + 1e-12).contains(&r));
        }
        let mut g = Gaussian::new(5);
        let n = 100_000;
        let x: Vec<f64> = (0..n).map(|_| g.sample()).collect();
        let mean = x.iter().sum::<f64>() / n as f64;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
        // standard errors 0.0032 and 0.0045
        assert!(
            mean.abs() < 0.02 && (var - 1.0).abs() < 0.03,
            "{mean} {var}"
        );
    }
}
