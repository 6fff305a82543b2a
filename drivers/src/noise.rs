//! The one seedable generator of the workspace: simulated instruments draw their noise from
//! it, and the renderer and the characterization plan derive their seeds and random drive
//! values from it, so a seed means the same thing everywhere.
//!
//! SplitMix64 (G. L. Steele, D. Lea, C. H. Flood, "Fast splittable pseudorandom number
//! generators", OOPSLA 2014): one 64-bit state, a Weyl increment and a mixing finalizer;
//! small, fast, and statistically good enough for measurement noise and seeding.

/// The SplitMix64 generator.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator whose first output is `mix(seed)`.
    pub fn new(seed: u64) -> SplitMix64 {
        SplitMix64(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1] with 53 bits (never 0, so its logarithm is finite).
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// Standard normal by the Box–Muller transform.
    pub fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }

    /// The generator's first output for `z`: a bijective 64-bit mix, for deriving
    /// independent seeds from (seed, stream, index).
    pub fn mix(z: u64) -> u64 {
        SplitMix64::new(z).next_u64()
    }
}

/// Where a simulated instrument's noise stands: the reading index a session set last
/// ([`NoiseCursor::seek`]) and how many measurements the device took since. The noise of
/// each measurement is drawn from a stream that depends only on (seed, index, count), not
/// on what the device measured before, so a session resumed in a new process — with a
/// fresh device — reads exactly what an uninterrupted one would.
#[derive(Clone, Debug, Default)]
pub struct NoiseCursor(std::sync::Arc<std::sync::Mutex<(u64, u64)>>);

impl NoiseCursor {
    /// The next measurements belong to reading `index`.
    pub fn seek(&self, index: u64) {
        *self.0.lock().unwrap_or_else(|e| e.into_inner()) = (index, 0);
    }

    /// The generator for the next measurement with noise seed `seed`; advances the count.
    pub fn next_stream(&self, seed: u64) -> SplitMix64 {
        let mut at = self.0.lock().unwrap_or_else(|e| e.into_inner());
        let (index, count) = *at;
        at.1 += 1;
        SplitMix64::new(stream_seed(seed, index, count))
    }
}

/// The state of the stream for measurement `count` of reading `index` under `seed`: each
/// part mixed in turn, so neighbouring indices give unrelated streams.
pub fn stream_seed(seed: u64, index: u64, count: u64) -> u64 {
    let a = SplitMix64::mix(seed);
    let b = SplitMix64::mix(a ^ index);
    SplitMix64::mix(b ^ count)
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_cursor_s_stream_depends_only_on_seed_index_and_count() {
        let a = NoiseCursor::default();
        for _ in 0..5 {
            a.next_stream(9);
        }
        a.seek(42);
        let first = a.next_stream(9).next_u64();
        let second = a.next_stream(9).next_u64();
        // A fresh cursor that never measured before gives the same numbers at index 42.
        let b = NoiseCursor::default();
        b.seek(42);
        assert_eq!(b.next_stream(9).next_u64(), first);
        assert_eq!(b.next_stream(9).next_u64(), second);
        // By the definition: three mixes of seed, index and count.
        let m = SplitMix64::mix;
        // Count 0 for the first (x ^ 0 = x), 1 for the second.
        assert_eq!(first, SplitMix64::new(m(m(m(9) ^ 42))).next_u64());
        assert_eq!(second, SplitMix64::new(m(m(m(9) ^ 42) ^ 1)).next_u64());
        assert_ne!(first, second);
        b.seek(43);
        assert_ne!(b.next_stream(9).next_u64(), first);
    }

    use super::*;

    /// The reference outputs for seed 1234567 published with the algorithm's reference
    /// implementation (Vigna's splitmix64.c test vector, also used by Java's
    /// SplittableRandom tests).
    #[test]
    fn matches_the_reference_sequence() {
        let mut g = SplitMix64::new(1_234_567);
        let want: [u64; 5] = [
            6_457_827_717_110_365_317,
            3_203_168_211_198_807_973,
            9_817_491_932_198_370_423,
            4_593_380_528_125_082_431,
            16_408_922_859_458_223_821,
        ];
        for w in want {
            assert_eq!(g.next_u64(), w);
        }
        assert_eq!(SplitMix64::mix(1_234_567), want[0]);
    }

    #[test]
    fn uniform_is_in_the_half_open_unit_interval_and_normal_has_unit_variance() {
        let mut g = SplitMix64::new(7);
        let n = 20_000;
        let (mut sum, mut sq) = (0.0, 0.0);
        for _ in 0..n {
            let u = g.uniform();
            assert!(u > 0.0 && u <= 1.0);
            let x = g.normal();
            sum += x;
            sq += x * x;
        }
        let mean = sum / n as f64;
        let var = sq / n as f64 - mean * mean;
        // 5σ bounds for n = 20000: mean ± 0.035, variance ± 0.05.
        assert!(mean.abs() < 0.035, "{mean}");
        assert!((var - 1.0).abs() < 0.05, "{var}");
    }
}
