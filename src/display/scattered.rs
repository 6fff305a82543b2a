//! Seeded space-filling patch sets for scattered-data characterization: the eight corners
//! of the drive cube (black, primaries, secondaries, white) and a Halton sequence in bases
//! 2, 3, 5 under a seeded Cranley–Patterson rotation (each axis shifted by a random offset
//! modulo 1), quantised to 8-bit codes. Such sets resemble what ArgyllCMS's `targen`
//! spreads through the cube, without its optimisation.

/// `n` drive codes (n ≥ 8 includes all corners first), reproducible from `seed`.
pub fn scattered_patches(n: usize, seed: u64) -> Vec<[u8; 3]> {
    let mut out: Vec<[u8; 3]> = Vec::with_capacity(n);
    for corner in 0..8u8 {
        if out.len() == n {
            return out;
        }
        out.push(std::array::from_fn(|c| {
            if corner >> c & 1 == 1 {
                255
            } else {
                0
            }
        }));
    }
    let shift: [f64; 3] = std::array::from_fn(|c| unit(splitmix(seed ^ ((c as u64 + 1) * 0x51ED))));
    let mut i = 1;
    while out.len() < n {
        let code: [u8; 3] = std::array::from_fn(|c| {
            let v = (radical_inverse(i, [2, 3, 5][c]) + shift[c]).fract();
            (v * 255.0).round() as u8
        });
        out.push(code);
        i += 1;
    }
    out
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

fn unit(z: u64) -> f64 {
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// The van der Corput radical inverse of `i` in `base`.
fn radical_inverse(mut i: usize, base: usize) -> f64 {
    let (mut f, mut x) = (1.0, 0.0);
    while i > 0 {
        f /= base as f64;
        x += f * (i % base) as f64;
        i /= base;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radical_inverse_matches_hand_values() {
        // 6 = 110₂ → 0.011₂ = 0.375; 5 = 12₃ → 0.21₃ = 2/9 + 1/3·… = 7/9.
        assert_eq!(radical_inverse(6, 2), 0.375);
        assert!((radical_inverse(5, 3) - 7.0 / 9.0).abs() < 1e-15);
    }

    #[test]
    fn corners_first_then_spread_through_every_octant() {
        let p = scattered_patches(200, 1);
        assert_eq!(p.len(), 200);
        assert_eq!(p[0], [0, 0, 0]);
        assert_eq!(p[7], [255, 255, 255]);
        let mut octants = [0usize; 8];
        for c in &p[8..] {
            octants[(0..3).map(|k| usize::from(c[k] >= 128) << k).sum::<usize>()] += 1;
        }
        // A low-discrepancy set puts 192/8 = 24 in each octant, give or take a few.
        assert!(
            octants.iter().all(|&n| (18..=30).contains(&n)),
            "{octants:?}"
        );
        assert_eq!(p, scattered_patches(200, 1));
        assert_ne!(p, scattered_patches(200, 2));
    }
}
