//! The wavelength grid, wavelength sampling and the random numbers of the path tracer.
//!
//! Paper Eq. 8 (X = K_m ∫ L x̄ dλ) is evaluated as the colour core does: a sum over the
//! integer wavelengths 380…780 nm. The tracer estimates that sum by sampling wavelengths
//! from a discrete distribution (uniform, or proportional to the light's spectrum times
//! x̄+ȳ+z̄) and, with hero-wavelength sampling (Wilkie et al. 2014, as in pbrt-v4), carries
//! several wavelengths per path: one uniform offset u, the others at u + j/n (mod 1),
//! each mapped through the inverse CDF so every one is marginally distributed by the pdf.

use crate::color::{observer, ObserverKind, Spectrum, END_NM, START_NM};

/// Number of wavelength bins (380..=780 nm at 1 nm).
pub const N_BINS: usize = (END_NM - START_NM + 1) as usize;

/// A spectrum's values on the integer-nm grid of paper Eq. 8, one per bin: the flat array
/// the tracer indexes in its inner loop.
pub fn bins(spectrum: &Spectrum) -> Vec<f64> {
    spectrum.on_grid(START_NM as f64, 1.0, N_BINS)
}

/// The same value in every bin.
pub fn constant_bins(value: f64) -> Vec<f64> {
    vec![value; N_BINS]
}

/// x̄, ȳ, z̄ on the grid.
pub fn cmf_bins(kind: ObserverKind) -> [Vec<f64>; 3] {
    let o = observer(kind);
    let at = |k: usize| (START_NM..=END_NM).map(|nm| o.at_nm(nm)[k]).collect();
    [at(0), at(1), at(2)]
}

/// A discrete distribution over wavelength bins.
#[derive(Clone, Debug)]
pub struct WavelengthSampler {
    pmf: Vec<f64>,
    cdf: Vec<f64>,
}

impl WavelengthSampler {
    /// Proportional to `weights` (non-negative, not all zero).
    pub fn new(weights: &[f64]) -> WavelengthSampler {
        let total: f64 = weights.iter().sum();
        let pmf: Vec<f64> = weights.iter().map(|w| w / total).collect();
        let mut acc = 0.0;
        let cdf = pmf
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        WavelengthSampler { pmf, cdf }
    }

    pub fn uniform() -> WavelengthSampler {
        WavelengthSampler::new(&[1.0; N_BINS])
    }

    pub fn pmf(&self, bin: usize) -> f64 {
        self.pmf[bin]
    }

    /// The bin whose CDF interval holds `u` ∈ [0, 1); never a zero-probability bin.
    pub fn sample(&self, u: f64) -> usize {
        let i = self.cdf.partition_point(|&c| c <= u);
        let mut i = i.min(N_BINS - 1);
        while self.pmf[i] == 0.0 && i > 0 {
            i -= 1;
        }
        i
    }

    /// `n` hero wavelengths from one uniform number.
    pub fn sample_hero(&self, u: f64, n: usize, out: &mut [usize]) {
        for (j, o) in out.iter_mut().take(n).enumerate() {
            let v = (u + j as f64 / n as f64).fract();
            *o = self.sample(v);
        }
    }
}

/// PCG32 (O'Neill 2014, pcg-random.org): small, fast, and seedable per sample so that a
/// render depends on the seed only, not on the thread that ran it.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

impl Rng {
    /// A stream for (seed, stream id, index) mixed with SplitMix64.
    pub fn new(seed: u64, stream: u64, index: u64) -> Rng {
        let mix = metamer_drivers::noise::SplitMix64::mix;
        let s = mix(seed ^ mix(stream ^ mix(index)));
        let mut r = Rng {
            state: 0,
            inc: (mix(s) << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(s);
        r.next_u32();
        r
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1) with 53 bits.
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        ((hi | lo) as f64) * (1.0 / (1u64 << 53) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hero_wavelengths_follow_the_pmf() {
        let mut w = vec![0.0; N_BINS];
        w[10] = 1.0;
        w[200] = 3.0;
        let s = WavelengthSampler::new(&w);
        let mut out = [0usize; 4];
        let mut count = [0usize; 2];
        let mut rng = Rng::new(1, 2, 3);
        for _ in 0..10_000 {
            s.sample_hero(rng.next_f64(), 4, &mut out);
            for &b in &out {
                assert!(b == 10 || b == 200, "{b}");
                count[(b == 200) as usize] += 1;
            }
        }
        // Stratified: exactly one of four lands on bin 10 each time (pmf 1/4).
        assert_eq!(count[0], 10_000);
    }

    #[test]
    fn bins_hold_the_spectrum_at_each_integer_wavelength() {
        // A ramp of 1 per nm from 0 at 380 nm: bin i holds i, and 780 nm holds 400.
        let ramp = Spectrum::new(vec![380.0, 780.0], vec![0.0, 400.0]).unwrap();
        let b = bins(&ramp);
        assert_eq!(b.len(), 401);
        assert!(b
            .iter()
            .enumerate()
            .all(|(i, &v)| (v - i as f64).abs() < 1e-9));
        let [_, ybar, _] = cmf_bins(ObserverKind::Cie1931);
        // ȳ(555 nm) = 1 in the CIE 1931 table.
        assert_eq!(ybar[555 - 380], 1.0);
    }

    #[test]
    fn rng_is_uniform_enough() {
        let mut r = Rng::new(7, 0, 0);
        let n = 100_000;
        let mean: f64 = (0..n).map(|_| r.next_f64()).sum::<f64>() / n as f64;
        // Standard error of the mean of U(0,1) is 0.289/√n ≈ 0.0009.
        assert!((mean - 0.5).abs() < 0.004, "{mean}");
    }
}
