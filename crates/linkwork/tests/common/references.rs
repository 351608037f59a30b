//! Independent reference solutions of the dynamic examples, for the work-precision tests and the
//! work-precision table (`crates/linkwork/examples/work_precision.rs`): each is computed without
//! the engine's integrators.
//!
//! - The unloaded quick-return ([`QuickReturn`]): a one-degree-of-freedom machine coasting with
//!   constant kinetic energy, so its motion is a quadrature, `t(theta) = int sqrt(I(theta) / 2E)`,
//!   with the generalised inertia `I(theta)` from the kinematic analysis (its velocities per unit
//!   crank speed), integrated spectrally: `I` is periodic and analytic in the crank angle.
//! - Andrews' squeezing mechanism ([`ANDREWS_END_CONVERGED`]): the test set's own equations
//!   solved by SciPy's integrators (`benches/andrews_reference.py`); the Bari test set's
//!   published solution ([`ANDREWS_END`]) is good to 9.6 significant digits only.
//! - The IFToMM A02 N-four-bar ([`nfourbar_reference`]): its one-degree-of-freedom equation.
//! - The IFToMM A01 pendulum released at 90 degrees ([`pendulum_a01`]): the exact solution in
//!   Jacobi's elliptic function `sn`.

use linkwork::{Model, Overrides, Results};
use std::f64::consts::PI;

/// The quick-return's initial crank speed, rad/s, as `examples/quick_return_a.yaml` gives it
/// (`omega: 6.283`, held by `given`; not 2 pi).
#[allow(clippy::approx_constant)]
pub const QUICK_RETURN_CRANK_SPEED: f64 = 6.283;

/// Samples of the crank turn for [`QuickReturn::new`]: the reference moves by less than `1e-13`
/// from 256 to 512 samples (`tests/work_precision.rs`), so 512 leaves a wide margin.
pub const SAMPLES: usize = 512;

/// A real trigonometric series `a0 + sum_k (a_k cos k psi + b_k sin k psi)` from equally spaced
/// samples of a periodic function over one period (the discrete Fourier transform; exact for
/// harmonics below `N/2`).
struct Fourier {
    a0: f64,
    a: Vec<f64>,
    b: Vec<f64>,
}

impl Fourier {
    fn new(samples: &[f64]) -> Fourier {
        let n = samples.len();
        let harmonics = n / 2 - 1;
        let a0 = samples.iter().sum::<f64>() / n as f64;
        let (mut a, mut b) = (vec![0.0; harmonics], vec![0.0; harmonics]);
        for k in 1..=harmonics {
            for (j, &f) in samples.iter().enumerate() {
                let (s, c) = (2.0 * PI * (k * j % n) as f64 / n as f64).sin_cos();
                a[k - 1] += 2.0 * f * c / n as f64;
                b[k - 1] += 2.0 * f * s / n as f64;
            }
        }
        Fourier { a0, a, b }
    }

    fn value(&self, psi: f64) -> f64 {
        self.a0
            + (1..=self.a.len())
                .map(|k| {
                    let (s, c) = (k as f64 * psi).sin_cos();
                    self.a[k - 1] * c + self.b[k - 1] * s
                })
                .sum::<f64>()
    }

    /// `int_0^psi` of the series.
    fn integral(&self, psi: f64) -> f64 {
        self.a0 * psi
            + (1..=self.a.len())
                .map(|k| {
                    let (s, c) = (k as f64 * psi).sin_cos();
                    (self.a[k - 1] * s - self.b[k - 1] * (c - 1.0)) / k as f64
                })
                .sum::<f64>()
    }
}

/// The coasting quick-return mechanism of `examples/quick_return_a.yaml` (analysis `dynamics`:
/// no driver, load or gravity; the crank starts at its given angle and speed).
pub struct QuickReturn {
    /// Crank angle at t = 0, rad.
    theta0: f64,
    /// `dt/dtheta = sqrt(I(theta) / 2E)` as a series in `theta - theta0`.
    rate: Fourier,
    /// Each position column's name, its periodic part as a series, and its growth per turn.
    columns: Vec<(String, Fourier, f64)>,
}

impl QuickReturn {
    /// From the model's `kinematics` analysis (the crank driven at 2 pi rad/s from its initial
    /// angle) at `samples` points of one turn, and the crank's given initial speed `omega0`, rad/s.
    pub fn new(model: &Model, omega0: f64, samples: usize) -> QuickReturn {
        let o = Overrides { t_end: Some(1.0), step: Some(1.0 / samples as f64), ..Default::default() };
        let r = model.run("kinematics", &o.clone().into()).unwrap_or_else(|f| panic!("kinematics: {}", f.error));
        assert_eq!(r.len(), samples + 1);
        let col = |name: &str| r.column(name).unwrap_or_else(|| panic!("no column {name}"));
        let crank = col("crank.phi");
        let theta0 = crank[0];
        // Generalised inertia per unit crank speed: sum m v^2 + J omega^2 at crank speed 2 pi.
        let inertia: Vec<f64> = (0..samples)
            .map(|j| {
                model
                    .bodies
                    .iter()
                    .map(|b| {
                        let v = |c: &str| col(&format!("{}.{c}", b.name))[j];
                        b.mass * (v("vx").powi(2) + v("vy").powi(2)) + b.inertia * v("omega").powi(2)
                    })
                    .sum::<f64>()
                    / (2.0 * PI).powi(2)
            })
            .collect();
        let energy = 0.5 * inertia[0] * omega0 * omega0;
        let rate = Fourier::new(&inertia.iter().map(|i| (i / (2.0 * energy)).sqrt()).collect::<Vec<_>>());
        let mut columns = Vec::new();
        for b in &model.bodies {
            for c in ["x", "y", "phi"] {
                let name = format!("{}.{c}", b.name);
                let y = col(&name);
                let growth = y[samples] - y[0];
                let periodic: Vec<f64> = (0..samples).map(|j| y[j] - growth * j as f64 / samples as f64).collect();
                columns.push((name, Fourier::new(&periodic), growth));
            }
        }
        QuickReturn { theta0, rate, columns }
    }

    /// The crank angle at time `t`: Newton on `t(theta) = t`, `dt/dtheta` the series itself.
    pub fn crank_angle(&self, t: f64) -> f64 {
        let mut psi = t / self.rate.a0;
        for _ in 0..50 {
            let d = (self.rate.integral(psi) - t) / self.rate.value(psi);
            psi -= d;
            if d.abs() < 1e-15 * psi.abs().max(1.0) {
                break;
            }
        }
        self.theta0 + psi
    }

    /// The largest error of every body's position columns in `r` (m, rad).
    pub fn error(&self, r: &Results) -> f64 {
        self.names()
            .flat_map(|name| {
                let c = r.column(name).expect("column");
                r.time.iter().zip(c).map(move |(&t, &y)| (y - self.position(name, t)).abs())
            })
            .fold(0.0, f64::max)
    }

    /// The names of the position columns (`<body>.x`, `.y`, `.phi` of every body).
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.columns.iter().map(|c| c.0.as_str())
    }

    /// The value of position column `name` at time `t`.
    pub fn position(&self, name: &str, t: f64) -> f64 {
        let psi = self.crank_angle(t) - self.theta0;
        let (_, series, growth) = self.columns.iter().find(|c| c.0 == name).unwrap_or_else(|| panic!("{name}"));
        series.value(psi) + growth * psi / (2.0 * PI)
    }
}

/// Complete elliptic integral of the first kind `K(k) = pi / (2 AGM(1, sqrt(1 - k^2)))`.
pub fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    // Quadratic convergence: 6 means reach rounding from k = sin 45 deg; 10 leave no doubt.
    for _ in 0..10 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (2.0 * a)
}

/// The largest error of the A01 mass's position (`P1_x`, `P1_y`) in `r` against [`pendulum_a01`], m.
pub fn pendulum_error(r: &Results) -> f64 {
    let (x, y) = (r.column("P1_x").expect("P1_x"), r.column("P1_y").expect("P1_y"));
    (0..r.len())
        .map(|k| {
            let p = pendulum_a01(r.time[k]);
            (x[k] - p[0]).abs().max((y[k] - p[1]).abs())
        })
        .fold(0.0, f64::max)
}

/// A01's period, s: `4 sqrt(L / g) K(sin 45 deg)`.
pub const A01_PERIOD: f64 = 2.3678419;

/// The secular energy change of A01 per period, relative to `m g L = 9.81 J` (positive: a loss):
/// the mean energy over the first period minus that over the last, per period between them
/// (the means remove the energy's oscillation within a swing, `1.6e-4` at 1e-8).
pub fn a01_energy_loss_per_period(r: &Results) -> f64 {
    let (ke, pe) =
        (r.column("kinetic_energy").expect("kinetic_energy"), r.column("potential_energy").expect("potential_energy"));
    let e: Vec<f64> = (0..r.len()).map(|k| ke[k] + pe[k]).collect();
    let per = ((A01_PERIOD / (r.time[1] - r.time[0])).round() as usize).clamp(1, r.len() / 2);
    let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
    let periods = (r.time[r.len() - 1] - A01_PERIOD) / A01_PERIOD;
    (mean(&e[..per]) - mean(&e[e.len() - per..])) / 9.81 / periods
}

/// Jacobi's elliptic `sn(u | k)` by the arithmetic-geometric mean and descending Landen
/// transformation (Abramowitz and Stegun 16.4), with `u` reduced modulo the period `4 K(k)`.
pub fn sn(u: f64, k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    let mut c = vec![k];
    let mut aa = vec![1.0];
    while c.last().is_some_and(|&x| x.abs() > 1e-17) && c.len() < 40 {
        let (an, bn) = (0.5 * (a + b), (a * b).sqrt());
        c.push(0.5 * (a - b));
        aa.push(an);
        (a, b) = (an, bn);
    }
    let quarter = PI / (2.0 * a);
    let u = u.rem_euclid(4.0 * quarter);
    let levels = c.len() - 1;
    let mut phi = 2f64.powi(levels as i32) * a * u;
    for n in (1..=levels).rev() {
        phi = 0.5 * (phi + (c[n] / aa[n] * phi.sin()).asin());
    }
    phi.sin()
}

/// The IFToMM A01 pendulum (length 1 m, g = 9.81 m/s^2, released from rest at (-1, 0)): the
/// exact position `(x, y)` of the mass at time `t`, from `sin(theta / 2) = k sn(K - w t | k)`,
/// `k = sin 45 deg`, `w = sqrt(g / L)`, `theta` the angle from the downward vertical.
pub fn pendulum_a01(t: f64) -> [f64; 2] {
    let k = (PI / 4.0).sin();
    let theta = 2.0 * (k * sn(elliptic_k(k) - 9.81f64.sqrt() * t, k)).asin();
    [-theta.sin(), -theta.cos()]
}

/// The N-four-bar as the one degree of freedom it has: every rocker at the angle `psi` (from
/// +x), every coupler translating with the rockers' tops. Lagrange's equation of that system,
/// `I psi'' = -g c cos psi` with `I = (N + 1)/3 + N` (rockers about their bases, couplers
/// translating at the tops' speed) and `c = (N + 1)/2 + N`, integrated by classical RK4 with
/// step 1e-4 s (error ~1e-13); returns `(psi, psi')` at the times `t`.
pub fn nfourbar_reference(n: usize, times: &[f64]) -> Vec<[f64; 2]> {
    let nf = n as f64;
    let (inertia, c) = ((nf + 1.0) / 3.0 + nf, (nf + 1.0) / 2.0 + nf);
    let f = |y: [f64; 2]| [y[1], -9.81 * c / inertia * y[0].cos()];
    let (mut y, mut t, h) = ([std::f64::consts::FRAC_PI_2, -1.0], 0.0f64, 1e-4f64);
    let mut out = Vec::with_capacity(times.len());
    for &to in times {
        while t < to - 1e-12 {
            let hs = h.min(to - t);
            let k1 = f(y);
            let k2 = f([y[0] + 0.5 * hs * k1[0], y[1] + 0.5 * hs * k1[1]]);
            let k3 = f([y[0] + 0.5 * hs * k2[0], y[1] + 0.5 * hs * k2[1]]);
            let k4 = f([y[0] + hs * k3[0], y[1] + hs * k3[1]]);
            for i in 0..2 {
                y[i] += hs / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            t += hs;
        }
        out.push(y);
    }
    out
}

/// Largest distance, m, of the N-four-bar's point B0 (`B0_x`, `B0_y`) from the `n`-bar
/// reference [`nfourbar_reference`] over the output times.
pub fn nfourbar_error(r: &Results, n: usize) -> f64 {
    let psi = nfourbar_reference(n, &r.time);
    let column = |name: &str| r.column(name).unwrap_or_else(|| panic!("no column {name}"));
    let (bx, by) = (column("B0_x"), column("B0_y"));
    (0..r.len()).map(|k| (bx[k] - psi[k][0].cos()).abs().max((by[k] - psi[k][0].sin()).abs())).fold(0.0, f64::max)
}

/// The test set's coordinates, in the order of its solution vector.
pub const ANDREWS: [&str; 7] = ["beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon"];

/// Initial values of the Test Set for IVP Solvers (Mazzia and Magherini, Bari, release 2.4,
/// andrews.f, subroutine `init`), digits as published.
#[allow(clippy::excessive_precision)]
pub const ANDREWS_START: [f64; 7] = [
    -0.0617138900142764496358948458001,
    0.0,
    0.455279819163070380255912382449,
    0.222668390165885884674473185609,
    0.487364979543842550225598953530,
    -0.222668390165885884674473185609,
    1.23054744454982119249735015568,
];

/// The test set's reference solution at t = 0.03 (andrews.f, subroutine `solut`; computed with
/// PSIDE at tolerances 1e-14 on a Cray C90). It prints 16 digits but is good to 9.57 significant
/// digits (gamma's relative error 2.7e-10, beta's 7.3e-11): see [`ANDREWS_END_CONVERGED`].
pub const ANDREWS_END: [f64; 7] = [
    0.1581077119629904e2,
    -0.1575637105984298e2,
    0.4082224013073101e-1,
    -0.5347301163226948,
    0.5244099658805304,
    0.5347301163226948,
    0.1048080741042263e1,
];

/// Andrews' end state at t = 0.03 from the test set's own equations (relative angles, its mass
/// matrix and forces, the constraints differentiated twice: an ODE), integrated by SciPy's DOP853
/// at rtol 3e-14 (`benches/andrews_reference.py`, which prints these digits). SciPy's Radau and
/// LSODA at their tightest tolerances agree with it to 1.3e-12 and 4.4e-12 relative (gamma; the
/// other angles closer), so it is good to about 11.5 significant digits. Both of Linkwork's
/// formulation-independent integrators converge to it, not to [`ANDREWS_END`]: `bdf` and `abam`
/// at 1e-14 end within 3e-11 relative of it.
pub const ANDREWS_END_CONVERGED: [f64; 7] = [
    15.810771195153082,
    -15.75637105841101,
    0.040822240119633035,
    -0.5347301163421009,
    0.5244099658799518,
    0.5347301163421023,
    1.0480807410419404,
];

/// Significant correct digits of Andrews' end state against `reference`, as the test set counts
/// them (`scd`): `-log10` of the largest relative error of the seven angles at the last output time.
pub fn andrews_digits(r: &Results, reference: &[f64; 7]) -> f64 {
    let n = r.len() - 1;
    let rel = ANDREWS.iter().zip(reference).map(|(name, want)| {
        let got = r.column(name).unwrap_or_else(|| panic!("no column {name}"))[n];
        ((got - want) / want).abs()
    });
    -rel.fold(0.0, f64::max).log10()
}
