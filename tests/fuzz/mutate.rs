//! Input generation: mutations of valid seed files (bit flips, byte insertion and deletion,
//! splices of two seeds, numbers replaced by interesting ones, duplicated chunks that make
//! huge counts) and plain random bytes, all from one seeded SplitMix64 so a run repeats.

use metamer_drivers::noise::SplitMix64;

/// Numbers that break parsers and numerics: zero, signs, extremes, non-finite spellings,
/// counts that overflow a size computation.
const INTERESTING: &[&str] = &[
    "0",
    "-1",
    "1e308",
    "-1e308",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e-320",
    "4294967296",
    "18446744073709551615",
    "99999999999999999999",
    "-0",
    "0.0000001",
    "65535",
    "2147483648",
];

pub struct Mutator {
    rng: SplitMix64,
}

impl Mutator {
    pub fn new(seed: u64) -> Mutator {
        Mutator {
            rng: SplitMix64::new(seed),
        }
    }

    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.rng.next_u64() % n as u64) as usize
        }
    }

    /// One input: a mutated seed (nine times in ten) or random bytes.
    pub fn next(&mut self, seeds: &[Vec<u8>]) -> Vec<u8> {
        if self.below(10) == 0 {
            let n = self.below(256);
            return (0..n).map(|_| self.rng.next_u64() as u8).collect();
        }
        let mut data = seeds[self.below(seeds.len())].clone();
        let rounds = 1 + self.below(4);
        for _ in 0..rounds {
            self.mutate(&mut data, seeds);
        }
        data
    }

    fn mutate(&mut self, data: &mut Vec<u8>, seeds: &[Vec<u8>]) {
        let len = data.len();
        match self.below(7) {
            0 if len > 0 => {
                let i = self.below(len);
                data[i] ^= 1 << self.below(8);
            }
            1 => {
                let i = self.below(len + 1);
                let b = self.rng.next_u64() as u8;
                data.insert(i, b);
            }
            2 if len > 0 => {
                let i = self.below(len);
                let n = 1 + self.below(16.min(len - i));
                data.drain(i..i + n);
            }
            3 => {
                let other = &seeds[self.below(seeds.len())];
                let cut = self.below(len + 1);
                let from = self.below(other.len() + 1);
                data.truncate(cut);
                data.extend_from_slice(&other[from..]);
            }
            4 => self.replace_number(data),
            5 if len > 0 => {
                // A chunk repeated: many rows, fields or items.
                let i = self.below(len);
                let n = 1 + self.below(64.min(len - i));
                let chunk = data[i..i + n].to_vec();
                let times = 1 + self.below(64);
                for _ in 0..times {
                    data.splice(i..i, chunk.iter().copied());
                }
            }
            _ if len > 0 => {
                let i = self.below(len);
                data[i] = self.rng.next_u64() as u8;
            }
            _ => data.push(self.rng.next_u64() as u8),
        }
    }

    /// Replaces one run of digits (with sign, point and exponent) by an interesting number.
    fn replace_number(&mut self, data: &mut Vec<u8>) {
        let starts: Vec<usize> = (0..data.len())
            .filter(|&i| data[i].is_ascii_digit() && (i == 0 || !data[i - 1].is_ascii_digit()))
            .collect();
        let word = INTERESTING[self.below(INTERESTING.len())].as_bytes();
        if starts.is_empty() {
            let i = self.below(data.len() + 1);
            data.splice(i..i, word.iter().copied());
            return;
        }
        let start = starts[self.below(starts.len())];
        let end = (start..data.len())
            .find(|&i| !matches!(data[i], b'0'..=b'9' | b'.' | b'e' | b'E' | b'-' | b'+'))
            .unwrap_or(data.len());
        data.splice(start..end, word.iter().copied());
    }
}
