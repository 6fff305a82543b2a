//! Spectral path tracing of the scene: radiance along a ray at a few wavelengths at once.
//!
//! Next-event estimation picks an emitter tile with probability proportional to its power
//! along the normal (gain × area × Σ spectrum) and a uniform point on it; the tile's own
//! spectrum and the directional factor f(C, γ) in the emitter's frame weight the sample;
//! BRDF sampling is cosine-weighted, so a Lambertian bounce multiplies the throughput by
//! the reflectance alone. The two are combined with the power heuristic (Veach 1997,
//! §9.2.2). Russian roulette on the largest throughput ends paths without bias.
//! Geometry does not depend on wavelength here, so the hero wavelengths share every vertex
//! and their estimates are exact per-wavelength path-tracing estimates.

use super::geometry::{Vec3, VecOps};
use super::scene::Scene;
use super::spectral::{Rng, WavelengthSampler, N_BINS};
use crate::color::K_M;

/// Most wavelengths one path carries (every bin).
pub const MAX_HERO: usize = N_BINS;

/// Which wavelengths a path carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wavelengths {
    /// `n` hero wavelengths drawn from the wavelength distribution.
    Hero(usize),
    /// Every 1 nm bin where the light and the observer are non-zero: no wavelength noise,
    /// at the cost of one multiply per bin and bounce (the spot meter's default).
    Full,
}

/// How paths are sampled (the convergence chart compares these).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Strategy {
    /// Wavelengths per path.
    pub wavelengths: Wavelengths,
    /// Wavelengths drawn ∝ light spectrum × (x̄+ȳ+z̄) instead of uniformly.
    pub wavelength_is: bool,
    /// Next-event estimation with MIS; otherwise BRDF sampling only.
    pub nee_mis: bool,
}

impl Default for Strategy {
    fn default() -> Self {
        Strategy {
            wavelengths: Wavelengths::Full,
            wavelength_is: true,
            nee_mis: true,
        }
    }
}

/// Per-scene data the inner loop needs.
pub struct Tracer<'a> {
    pub scene: &'a Scene,
    pub strategy: Strategy,
    sampler: WavelengthSampler,
    /// (emitter, tile) and cumulative probability.
    tiles: Vec<(usize, usize, f64)>,
    tile_pmf: Vec<Vec<f64>>,
    /// Largest number of bounces (None: Russian roulette only).
    pub max_depth: Option<usize>,
    /// Bins that can carry light to the observer.
    active: Vec<usize>,
}

enum Target {
    None,
    Surface(usize),
    Emitter(usize, f64, f64),
}

impl<'a> Tracer<'a> {
    pub fn new(scene: &'a Scene, strategy: Strategy) -> Tracer<'a> {
        let strategy = Strategy {
            wavelengths: match strategy.wavelengths {
                Wavelengths::Hero(n) => Wavelengths::Hero(n.clamp(1, MAX_HERO)),
                Wavelengths::Full => Wavelengths::Full,
            },
            ..strategy
        };
        let active: Vec<usize> = (0..N_BINS)
            .filter(|&i| {
                scene
                    .emitters
                    .iter()
                    .any(|e| e.spectra.iter().any(|s| s[i] > 0.0))
                    && scene.cmf.iter().any(|c| c[i] > 0.0)
            })
            .collect();
        // Per emitter and spectrum: Σ gain × tile area of the tiles that radiate it.
        let weight: Vec<Vec<f64>> = scene
            .emitters
            .iter()
            .map(|e| {
                let area = e.rect.area_m2 / e.gains.len() as f64;
                let mut w = vec![0.0; e.spectra.len()];
                for (g, k) in e.gains.iter().zip(&e.tile_spectrum) {
                    w[*k as usize] += g * area;
                }
                w
            })
            .collect();
        let sampler = if strategy.wavelength_is {
            let w: Vec<f64> = (0..scene.cmf[0].len())
                .map(|i| {
                    let s: f64 = scene
                        .emitters
                        .iter()
                        .zip(&weight)
                        .map(|(e, w)| e.spectra.iter().zip(w).map(|(s, w)| w * s[i]).sum::<f64>())
                        .sum();
                    s * (scene.cmf[0][i] + scene.cmf[1][i] + scene.cmf[2][i])
                })
                .collect();
            WavelengthSampler::new(&w)
        } else {
            WavelengthSampler::uniform()
        };
        let mut power = Vec::new();
        for (ei, e) in scene.emitters.iter().enumerate() {
            let sums: Vec<f64> = e.spectra.iter().map(|s| s.iter().sum()).collect();
            for (ti, g) in e.gains.iter().enumerate() {
                let lum = sums[e.tile_spectrum[ti] as usize];
                power.push((ei, ti, g * lum * e.rect.area_m2 / e.gains.len() as f64));
            }
        }
        let total: f64 = power.iter().map(|p| p.2).sum();
        let mut tile_pmf: Vec<Vec<f64>> = scene
            .emitters
            .iter()
            .map(|e| vec![0.0; e.gains.len()])
            .collect();
        let mut acc = 0.0;
        let mut tiles = Vec::new();
        for (ei, ti, p) in power {
            let p = p / total;
            tile_pmf[ei][ti] = p;
            acc += p;
            tiles.push((ei, ti, acc));
        }
        Tracer {
            scene,
            strategy,
            sampler,
            tiles,
            tile_pmf,
            max_depth: None,
            active,
        }
    }

    fn nearest(&self, o: Vec3, d: Vec3, t_max: f64) -> (f64, Target, bool) {
        let mut best = t_max;
        let mut target = Target::None;
        let mut front = false;
        for (i, s) in self.scene.surfaces.iter().enumerate() {
            if let Some(h) = s.rect.intersect(o, d, 1e-9, best) {
                best = h.t;
                target = Target::Surface(i);
                front = h.front;
            }
        }
        for (i, e) in self.scene.emitters.iter().enumerate() {
            if let Some(h) = e.rect.intersect(o, d, 1e-9, best) {
                best = h.t;
                target = Target::Emitter(i, h.a, h.b);
                front = h.front;
            }
        }
        (best, target, front)
    }

    fn occluded(&self, o: Vec3, d: Vec3, t_max: f64) -> bool {
        let t = t_max * (1.0 - 1e-9);
        self.scene
            .surfaces
            .iter()
            .any(|s| s.rect.intersect(o, d, 1e-9, t).is_some())
            || self
                .scene
                .emitters
                .iter()
                .any(|e| e.rect.intersect(o, d, 1e-9, t).is_some())
    }

    /// Solid-angle pdf of NEE choosing the point `a, b` on emitter `ei` from distance² and
    /// cosine at the emitter.
    fn light_pdf_sa(&self, ei: usize, a: f64, b: f64, dist2: f64, cos_l: f64) -> f64 {
        let e = &self.scene.emitters[ei];
        let tile = e.tile_at(a, b);
        let area = e.rect.area_m2 / e.gains.len() as f64;
        self.tile_pmf[ei][tile] / area * dist2 / cos_l
    }

    /// XYZ (cd/m²) estimate of the radiance arriving at `origin` from direction `-dir`
    /// (i.e. along the ray `origin + t·dir`), one path.
    pub fn xyz_sample(&self, origin: Vec3, dir: Vec3, rng: &mut Rng) -> [f64; 3] {
        let mut radiance = [0.0f64; MAX_HERO];
        let mut xyz = [0.0; 3];
        let cmf = &self.scene.cmf;
        let mut hero = [0usize; MAX_HERO];
        let (lambda, n): (&[usize], usize) = match self.strategy.wavelengths {
            Wavelengths::Hero(n) => {
                self.sampler.sample_hero(rng.next_f64(), n, &mut hero);
                (&hero[..n], n)
            }
            Wavelengths::Full => (&self.active, self.active.len()),
        };
        self.trace(origin, dir, lambda, &mut radiance[..n], rng);
        let full = self.strategy.wavelengths == Wavelengths::Full;
        for j in 0..n {
            let w = if full {
                K_M * radiance[j]
            } else {
                K_M * radiance[j] / (n as f64 * self.sampler.pmf(lambda[j]))
            };
            for k in 0..3 {
                xyz[k] += w * cmf[k][lambda[j]];
            }
        }
        xyz
    }

    /// Radiance along a ray at the given wavelength bins.
    pub fn trace(
        &self,
        mut o: Vec3,
        mut d: Vec3,
        lambda: &[usize],
        out: &mut [f64],
        rng: &mut Rng,
    ) {
        let n = lambda.len();
        let mut beta = [1.0f64; MAX_HERO];
        let mut buf = [0.0f64; MAX_HERO];
        let bins = Bins::new(lambda);
        // Solid-angle pdf of the BRDF sample that produced `d` (None for camera rays).
        let mut prev_brdf_pdf: Option<f64> = None;
        let mut depth = 0;
        // Throughput after the first surface: Russian roulette is judged relative to it, so
        // a dark patch seen by the meter does not cut its own indirect light short (its
        // reflectance scales every continuation alike and would only add variance).
        let mut first_beta = 1.0f64;
        loop {
            let (t, target, front) = self.nearest(o, d, f64::INFINITY);
            if !front {
                return;
            }
            let p = o.plus(d.times(t));
            let (normal, refl) = match target {
                Target::None => return,
                Target::Emitter(ei, a, b) => {
                    let e = &self.scene.emitters[ei];
                    let cos_l = -d.dot(e.rect.normal);
                    let tile = e.tile_at(a, b);
                    let f = e.gains[tile] * e.directional(-d);
                    let w = match prev_brdf_pdf {
                        Some(pb) if self.strategy.nee_mis => {
                            let pl = self.light_pdf_sa(ei, a, b, t * t, cos_l);
                            pb * pb / (pb * pb + pl * pl)
                        }
                        _ => 1.0,
                    };
                    let le = bins.of(e.tile_spectrum(tile), &mut buf);
                    let k = w * f;
                    for ((o, b), l) in out.iter_mut().zip(&beta[..n]).zip(le) {
                        *o += b * k * l;
                    }
                    (e.rect.normal, &e.reflectance)
                }
                Target::Surface(si) => {
                    let s = &self.scene.surfaces[si];
                    (s.rect.normal, &s.reflectance)
                }
            };
            if let Some(m) = self.max_depth {
                if depth >= m {
                    return;
                }
            }
            depth += 1;
            for (b, r) in beta[..n].iter_mut().zip(bins.of(refl, &mut buf)) {
                *b *= r;
            }
            if depth == 1 {
                first_beta = beta[..n].iter().cloned().fold(0.0, f64::max);
            }
            if self.strategy.nee_mis {
                self.next_event(p, normal, &bins, &beta, out, rng);
            }
            // Russian roulette after two bounces, on the largest throughput.
            if depth > 2 {
                let q = (beta[..n].iter().cloned().fold(0.0, f64::max) / first_beta).min(0.95);
                if rng.next_f64() >= q {
                    return;
                }
                for b in beta[..n].iter_mut() {
                    *b /= q;
                }
            } else if beta[..n].iter().all(|b| *b == 0.0) {
                return;
            }
            // Cosine-weighted hemisphere (Malley's method): f·cos/pdf = ρ, applied above.
            let r = rng.next_f64().sqrt();
            let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
            let z = (1.0 - r * r).max(0.0).sqrt();
            let (s, tt) = normal.basis();
            d = s
                .times(r * phi.cos())
                .plus(tt.times(r * phi.sin()))
                .plus(normal.times(z))
                .normalized();
            prev_brdf_pdf = Some(z / std::f64::consts::PI);
            o = p;
        }
    }

    /// Direct light at `p` (already multiplied by ρ in `beta`) with its MIS weight.
    fn next_event(
        &self,
        p: Vec3,
        normal: Vec3,
        bins: &Bins,
        beta: &[f64; MAX_HERO],
        out: &mut [f64],
        rng: &mut Rng,
    ) {
        let u = rng.next_f64();
        let k = self
            .tiles
            .partition_point(|t| t.2 <= u)
            .min(self.tiles.len() - 1);
        let (ei, ti, _) = self.tiles[k];
        let e = &self.scene.emitters[ei];
        let (row, col) = (ti / e.cols, ti % e.cols);
        let a = (col as f64 + rng.next_f64()) / e.cols as f64;
        let b = (row as f64 + rng.next_f64()) / e.rows as f64;
        let q = e.rect.point(a, b);
        let to = q.minus(p);
        let dist2 = to.dot(to);
        let dist = dist2.sqrt();
        let wi = to.times(1.0 / dist);
        let cos_x = wi.dot(normal);
        let cos_l = -wi.dot(e.rect.normal);
        if cos_x <= 0.0 || cos_l <= 0.0 || self.occluded(p, wi, dist) {
            return;
        }
        let pl = self.tile_pmf[ei][ti] / (e.rect.area_m2 / e.gains.len() as f64) * dist2 / cos_l;
        let pb = cos_x / std::f64::consts::PI;
        let w = pl * pl / (pl * pl + pb * pb);
        // ρ/π · L · cos_x / pl (beta already holds ρ).
        let g =
            e.gains[ti] * e.directional(wi.times(-1.0)) * w * cos_x / (std::f64::consts::PI * pl);
        let mut buf = [0.0; MAX_HERO];
        let le = bins.of(e.tile_spectrum(ti), &mut buf);
        for ((o, b), l) in out.iter_mut().zip(&beta[..bins.idx.len()]).zip(le) {
            *o += b * g * l;
        }
    }
}

/// The wavelength bins a path carries. The full-spectrum mode carries a consecutive run of
/// bins, read as plain slices so the per-bin loops vectorise; hero wavelengths are gathered.
struct Bins<'l> {
    idx: &'l [usize],
    run: bool,
}

impl<'l> Bins<'l> {
    fn new(idx: &'l [usize]) -> Bins<'l> {
        Bins {
            idx,
            run: !idx.is_empty() && idx.windows(2).all(|w| w[1] == w[0] + 1),
        }
    }

    /// `src` at these bins.
    #[inline]
    fn of<'b>(&self, src: &'b [f64], buf: &'b mut [f64; MAX_HERO]) -> &'b [f64] {
        if self.run {
            &src[self.idx[0]..self.idx[0] + self.idx.len()]
        } else {
            for (b, &l) in buf.iter_mut().zip(self.idx) {
                *b = src[l];
            }
            &buf[..self.idx.len()]
        }
    }
}
