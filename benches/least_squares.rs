//! The hand-written Levenberg–Marquardt of `metamer::display::model` against the
//! `levenberg-marquardt` crate on the same problems: the exponential of the module's test,
//! the synthetic GOG and GOGO curves of gog.rs's test (known truth), and the GOG and GOGO
//! fits of each virtual display's ramps (truth unknown: the final costs are compared).
//!
//! Before timing, one table is printed: per problem and solver the final cost Σr², the
//! largest parameter error against the truth where it is known, and whether the bounds
//! held. `cargo bench --bench least_squares` prints it and the time per fit.
//!
//! The crate is unconstrained; the adapter maps each bounded parameter through
//! `p = lo + (hi − lo)(1 + sin u)/2` (the MINUIT transform) so the problem it sees stays
//! smooth. Clamping in `set_params` would make the residual flat outside the box while
//! the crate's trust-region model still predicts a decrease there, so it stalls at a bound.

use criterion::{criterion_group, criterion_main, Criterion};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use metamer::display::model::{levenberg_marquardt, Trc};
use metamer::rig::{Preset, VirtualPanel};
use nalgebra::storage::Owned;
use nalgebra::{DMatrix, DVector, Dyn};

type ResidualFn = dyn Fn(&[f64]) -> Vec<f64>;
type Residual<'a> = &'a ResidualFn;

struct Bounded<'a> {
    residual: Residual<'a>,
    lower: &'a [f64],
    upper: &'a [f64],
    u: DVector<f64>,
}

impl Bounded<'_> {
    fn to_p(&self, u: &DVector<f64>) -> Vec<f64> {
        (0..u.len())
            .map(|i| self.lower[i] + (self.upper[i] - self.lower[i]) * (1.0 + u[i].sin()) / 2.0)
            .collect()
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Bounded<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, u: &DVector<f64>) {
        self.u.copy_from(u);
    }

    fn params(&self) -> DVector<f64> {
        self.u.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let r = (self.residual)(&self.to_p(&self.u));
        r.iter()
            .all(|v| v.is_finite())
            .then(|| DVector::from_vec(r))
    }

    // Forward differences with the same step rule as the hand-written solver, taken in u.
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let r = (self.residual)(&self.to_p(&self.u));
        let (m, n) = (r.len(), self.u.len());
        let mut jac = DMatrix::zeros(m, n);
        for j in 0..n {
            let h = 1e-7 * self.u[j].abs().max(1e-3);
            let mut q = self.u.clone();
            q[j] += h;
            let rq = (self.residual)(&self.to_p(&q));
            for i in 0..m {
                jac[(i, j)] = (rq[i] - r[i]) / h;
            }
        }
        Some(jac)
    }
}

/// The crate behind the hand-written solver's signature.
fn crate_lm(residual: Residual, start: &[f64], lower: &[f64], upper: &[f64]) -> Vec<f64> {
    let u = DVector::from_iterator(
        start.len(),
        (0..start.len()).map(|i| {
            let s = 2.0 * (start[i].clamp(lower[i], upper[i]) - lower[i]) / (upper[i] - lower[i]);
            (s - 1.0).clamp(-1.0, 1.0).asin()
        }),
    );
    let problem = Bounded {
        residual,
        lower,
        upper,
        u,
    };
    let (problem, _report) = LevenbergMarquardt::new().minimize(problem);
    problem.to_p(&problem.u)
}

struct Problem {
    name: String,
    residual: Box<ResidualFn>,
    start: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    truth: Option<Vec<f64>>,
}

fn exponential() -> Problem {
    let xs: Vec<f64> = (0..20).map(|i| i as f64 / 10.0).collect();
    Problem {
        name: "exponential".into(),
        residual: Box::new(move |p: &[f64]| {
            xs.iter()
                .map(|&x| p[0] * (p[1] * x).exp() - 3.0 * (-0.7 * x).exp())
                .collect()
        }),
        start: vec![1.0, 0.0],
        lower: vec![0.0, -5.0],
        upper: vec![10.0, 5.0],
        truth: Some(vec![3.0, -0.7]),
    }
}

/// The problem exactly as `fit_gog_curve` poses it.
fn gog_problem(
    name: String,
    points: Vec<(f64, f64)>,
    flare: bool,
    truth: Option<Vec<f64>>,
) -> Problem {
    let p = metamer::display::model::gog_problem(&points, flare);
    Problem {
        name,
        residual: p.residual,
        start: p.start,
        lower: p.lower,
        upper: p.upper,
        truth,
    }
}

fn synthetic(trc: Trc) -> Vec<(f64, f64)> {
    (0..=16)
        .map(|i| {
            let d = i as f64 / 16.0;
            (d, trc.eval(d))
        })
        .collect()
}

/// A channel's ramp as `metamer fit` sees it from the default characterization plan (9
/// steps: 0, 32, 64, …, 255): black-corrected XYZ projected on the primary's column.
fn ramp(panel: &VirtualPanel, c: usize) -> Vec<(f64, f64)> {
    let black = panel.xyz([0, 0, 0]);
    let drive = |v: u8| {
        let mut rgb = [0u8; 3];
        rgb[c] = v;
        rgb
    };
    let full = panel.xyz(drive(255));
    let col: Vec<f64> = (0..3).map(|k| full[k] - black[k]).collect();
    let norm2: f64 = col.iter().map(|v| v * v).sum();
    let mut pts = vec![(0.0, 0.0)];
    for i in 1..9 {
        let v = (255.0 * i as f64 / 8.0).round() as u8;
        let xyz = panel.xyz(drive(v));
        let dot: f64 = (0..3).map(|k| (xyz[k] - black[k]) * col[k]).sum();
        pts.push((v as f64 / 255.0, dot / norm2));
    }
    pts
}

fn problems() -> Vec<Problem> {
    let mut all = vec![
        exponential(),
        gog_problem(
            "gog synthetic".into(),
            synthetic(Trc::Gog {
                gain: 1.1,
                offset: -0.1,
                gamma: 2.4,
                flare: 0.0,
            }),
            false,
            Some(vec![-0.1, 2.4]),
        ),
        gog_problem(
            "gogo synthetic".into(),
            synthetic(Trc::Gog {
                gain: 0.9,
                offset: 0.05,
                gamma: 2.0,
                flare: 0.02,
            }),
            true,
            Some(vec![0.9, 0.05, 2.0, 0.02]),
        ),
    ];
    for preset in Preset::ALL {
        let panel = VirtualPanel::preset(preset);
        for c in 0..3 {
            for flare in [false, true] {
                let name = format!(
                    "{} {} {}",
                    preset.name(),
                    ["red", "green", "blue"][c],
                    if flare { "gogo" } else { "gog" }
                );
                all.push(gog_problem(name, ramp(&panel, c), flare, None));
            }
        }
    }
    all
}

type Solver = fn(Residual, &[f64], &[f64], &[f64]) -> Vec<f64>;
const SOLVERS: [(&str, Solver); 2] = [("hand", levenberg_marquardt), ("crate", crate_lm)];

fn bench(c: &mut Criterion) {
    let problems = problems();
    println!(
        "{:<28} {:>6} {:>12} {:>12} {:>7}  parameters",
        "problem", "solver", "cost", "max |Δp|", "bounds"
    );
    for p in &problems {
        for (name, solve) in SOLVERS {
            let x = solve(&*p.residual, &p.start, &p.lower, &p.upper);
            let cost: f64 = (p.residual)(&x).iter().map(|v| v * v).sum();
            let err = p.truth.as_ref().map_or("-".to_string(), |t| {
                let e = t
                    .iter()
                    .zip(&x)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                format!("{e:.2e}")
            });
            let inside = (0..x.len()).all(|i| x[i] >= p.lower[i] && x[i] <= p.upper[i]);
            println!(
                "{:<28} {name:>6} {cost:>12.4e} {err:>12} {inside:>7}  {x:.4?}",
                p.name
            );
        }
    }
    let mut group = c.benchmark_group("least squares");
    for p in &problems {
        for (name, solve) in SOLVERS {
            group.bench_function(format!("{} / {name}", p.name), |b| {
                b.iter(|| std::hint::black_box(solve(&*p.residual, &p.start, &p.lower, &p.upper)))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
