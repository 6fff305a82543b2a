//! Illuminance probes by path tracing: cosine-weighted directions from the point, each
//! traced with the full spectrum; E_v = π·mean(luminance). The direct part is the same
//! directions stopped at their first hit (only an emitter seen directly counts).

use rayon::prelude::*;

use super::geometry::VecOps;
use super::integrator::{Strategy, Tracer};
use super::radiosity::probes::{Illuminance, Probe};
use super::scene::Scene;
use super::spectral::Rng;

/// Illuminance at every probe from `samples` paths each (95 % half-width as the bound).
pub fn probe_illuminance_path(
    scene: &Scene,
    probes: &[Probe],
    samples: u64,
    seed: u64,
) -> Vec<Illuminance> {
    let total = Tracer::new(scene, Strategy::default());
    let mut first = Tracer::new(scene, Strategy::default());
    first.max_depth = Some(0);
    probes
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let n = p.normal.normalized();
            let (s, t) = n.basis();
            let sums = (0..samples)
                .into_par_iter()
                .map(|i| {
                    let mut rng = Rng::new(seed, 5000 + k as u64, i);
                    let r = rng.next_f64().sqrt();
                    let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
                    let z = (1.0 - r * r).max(0.0).sqrt();
                    let d = s
                        .times(r * phi.cos())
                        .plus(t.times(r * phi.sin()))
                        .plus(n.times(z))
                        .normalized();
                    let mut r2 = rng.clone();
                    let y_all = total.xyz_sample(p.position, d, &mut rng)[1];
                    let y_dir = first.xyz_sample(p.position, d, &mut r2)[1];
                    (y_all, y_all * y_all, y_dir)
                })
                .reduce(|| (0.0, 0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
            let m = samples.max(1) as f64;
            let pi = std::f64::consts::PI;
            let mean = sums.0 / m;
            let var = (sums.1 / m - mean * mean).max(0.0) / (m - 1.0).max(1.0);
            let direct = pi * sums.2 / m;
            Illuminance {
                direct_lux: direct,
                indirect_lux: pi * mean - direct,
                total_lux: pi * mean,
                bound_lux: 1.96 * pi * var.sqrt(),
            }
        })
        .collect()
}
