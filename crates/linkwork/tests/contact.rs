//! Contact (docs/model-format.md, "Contact") against independent solutions: the bouncing disc
//! of `examples/bouncing_disc.yaml` against the same force law integrated here as a 1-DOF ODE by
//! RK4 with tiny steps, its coefficient of restitution against Hunt and Crossley's relation,
//! energy conservation without damping, and a block sliding to rest against `v0^2 / (2 mu g)`.

mod common;

use common::{col, example_text, patch, run};
use linkwork::{Model, Results};

const G: f64 = 9.81;
const R: f64 = 0.05;
const K: f64 = 1e6;
const N: f64 = 1.5;

/// The contact force of the example on the disc at height `y`, velocity `v` (damping `c`).
fn normal(y: f64, v: f64, c: f64) -> f64 {
    let delta = R - y;
    if delta <= 0.0 {
        return 0.0;
    }
    (K * delta.powf(N) * (1.0 - c * v)).max(0.0)
}

/// `(y, vy)` of the 1 kg disc dropped from `y0` at rest, by RK4 with step `DT`, at `times`
/// (multiples of the step's multiple `1e-3`).
fn reference(y0: f64, c: f64, times: &[f64]) -> Vec<(f64, f64)> {
    const DT: f64 = 2e-7;
    let f = |y: f64, v: f64| (v, -G + normal(y, v, c));
    let (mut y, mut v, mut t) = (y0, 0.0, 0.0);
    let mut out = Vec::with_capacity(times.len());
    for &to in times {
        let steps = ((to - t) / DT).round() as usize;
        for _ in 0..steps {
            let (k1y, k1v) = f(y, v);
            let (k2y, k2v) = f(y + 0.5 * DT * k1y, v + 0.5 * DT * k1v);
            let (k3y, k3v) = f(y + 0.5 * DT * k2y, v + 0.5 * DT * k2v);
            let (k4y, k4v) = f(y + DT * k3y, v + DT * k3v);
            y += DT / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y);
            v += DT / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        t += steps as f64 * DT;
        out.push((y, v));
    }
    out
}

/// The output rows in free flight (no penetration in the results, nor within 2 mm of the floor,
/// so that an impact a step earlier or later in the reference is not compared mid-contact).
fn free_flight(r: &Results) -> Vec<usize> {
    let (y, p) = (col(r, "disc.y"), col(r, "bounce.penetration"));
    (0..r.len()).filter(|&k| p[k] == 0.0 && y[k] > R + 2e-3).collect()
}

/// The speed at the floor `sqrt(vy^2 + 2 g (y - r))` at a free-flight row: exact in free flight,
/// so it measures the rebound speed without locating the end of the contact.
fn floor_speed(r: &Results, k: usize) -> f64 {
    let (y, v) = (col(r, "disc.y")[k], col(r, "disc.vy")[k]);
    (v * v + 2.0 * G * (y - R)).sqrt()
}

/// Hunt and Crossley's exit speed for entry speed `v_in` and damping factor `c`, gravity
/// neglected during the contact: `m v dv / (1 + c v) = -k delta^n d delta` integrates to
/// `c (v_in + v_out) = ln((1 + c v_in) / (1 - c v_out))`, solved by bisection.
fn hunt_crossley_exit(v_in: f64, c: f64) -> f64 {
    let g = |v: f64| c * (v_in + v) - ((1.0 + c * v_in) / (1.0 - c * v)).ln();
    let (mut lo, mut hi) = (0.0, v_in.min(1.0 / c * (1.0 - 1e-15)));
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The example, with each integrator, against the RK4 solution of the same law: positions and
/// velocities at every free-flight output over the first three bounces (1.2 s). RK4 at 2e-7 s
/// resolves the 1.5 ms contact in 7500 steps (error below 1e-10 of the velocity); the engine runs
/// at rtol = atol = 1e-8, and its error per bounce accumulates through the impact's sensitivity
/// (the exit speed depends on the entry speed). bdf's error test covers velocities: 1e-5 m and
/// m/s (measured 9e-7 m, 4e-6 m/s). hht's tests positions only and is second order, so its
/// velocities carry more: 1e-4 (measured 4e-6 m, 2.4e-5 m/s). abam's error test covers both, as
/// bdf's: 1e-5 (measured 3.5e-9 m, 8.7e-9 m/s). The flat floor's normal is
/// vertical, so the friction, which spins the disc, leaves the vertical motion a 1-DOF drop.
#[test]
fn bouncing_disc_matches_an_independent_solution() {
    for analysis in ["dynamics", "dynamics_hht", "dynamics_abam"] {
        let (_, r) = run("bouncing_disc.yaml", analysis);
        let rows: Vec<usize> = free_flight(&r).into_iter().filter(|&k| r.time[k] <= 1.2).collect();
        let times: Vec<f64> = rows.iter().map(|&k| r.time[k]).collect();
        let want = reference(0.5, 0.05, &times);
        let (y, vy) = (col(&r, "disc.y"), col(&r, "disc.vy"));
        let mut worst = (0.0f64, 0.0f64);
        for (&k, &(wy, wv)) in rows.iter().zip(&want) {
            worst = (worst.0.max((y[k] - wy).abs()), worst.1.max((vy[k] - wv).abs()));
        }
        println!("{analysis}: largest differences y {:.2e} m, vy {:.2e} m/s", worst.0, worst.1);
        let tol = if analysis == "dynamics_hht" { 1e-4 } else { 1e-5 };
        assert!(
            worst.0 < tol && worst.1 < tol,
            "{analysis}: largest differences y {:.2e} m, vy {:.2e} m/s",
            worst.0,
            worst.1
        );
        // Friction at the first impact slows the rim's slip `vx + omega r` on the floor (0.2 m/s
        // before) and spins the disc.
        let (vx, omega) = (col(&r, "disc.vx"), col(&r, "disc.omega"));
        let k = rows.iter().copied().find(|&k| r.time[k] > 0.31).unwrap();
        let slip = vx[k] + omega[k] * R;
        assert!(
            slip.abs() < 0.1 && omega[k] < -1.0,
            "{analysis}: slip {slip} m/s, omega {} after the impact",
            omega[k]
        );
        // Both impacts before 1.2 s (at 0.30 s and 0.85 s) seen.
        let p = col(&r, "bounce.penetration");
        let impacts = (1..r.len()).filter(|&k| p[k] > 0.0 && p[k - 1] == 0.0 && r.time[k] <= 1.2).count();
        assert_eq!(impacts, 2, "{analysis}: impacts before 1.2 s");
    }
}

/// The first impact's coefficient of restitution, `v_out / v_in` from the free-flight speeds at
/// the floor before and after it, against the RK4 solution's (the same measure, 1e-5: the
/// integrator's error through one impact) and Hunt and Crossley's relation at
/// `v_in = 2.97` m/s. The relation neglects gravity during the 11 ms contact, whose impulse is 3.6%
/// of `v_in` and acts alike on compression and restitution, cancelling to first order: 5e-3 on
/// `e` (measured 2.5e-3).
#[test]
fn restitution_follows_hunt_crossley() {
    let (_, r) = run("bouncing_disc.yaml", "dynamics");
    let rows = free_flight(&r);
    let before = *rows.iter().rfind(|&&k| r.time[k] < 0.3).unwrap();
    let after = *rows.iter().find(|&&k| r.time[k] > 0.31).unwrap();
    let (v_in, v_out) = (floor_speed(&r, before), floor_speed(&r, after));
    let e = v_out / v_in;
    let (t_in, t_out) = (r.time[before], r.time[after]);
    let rk = reference(0.5, 0.05, &[t_in, t_out]);
    let speed = |(y, v): (f64, f64)| (v * v + 2.0 * G * (y - R)).sqrt();
    let e_rk4 = speed(rk[1]) / speed(rk[0]);
    let want = hunt_crossley_exit(v_in, 0.05) / v_in;
    println!("e {e}, RK4 {e_rk4}, Hunt-Crossley {want}");
    assert!((v_in - (2.0 * G * 0.45f64).sqrt()).abs() < 1e-6, "v_in {v_in}");
    assert!((e - e_rk4).abs() < 1e-5, "e {e} vs RK4 {e_rk4}");
    assert!((e - want).abs() < 5e-3, "e {e} vs Hunt-Crossley {want}");
    // The peak normal force: the disc stops at `delta_max`, where `F_n` is many times its weight.
    let fmax = col(&r, "bounce.fn").iter().fold(0.0f64, |a, &b| a.max(b));
    assert!(fmax > 100.0, "peak normal force {fmax}");
}

/// Without damping (nor friction) the contact is conservative: kinetic plus potential energy (gravity's and the
/// contact's `k delta^2.5 / 2.5`) stays at its initial value across the impacts of 2 s to 1e-3 J
/// of 4.9 J: the integrators' own dissipation at rtol 1e-8 over the few hundred steps of each
/// impact (measured 5.9e-4 J with bdf, 1.1e-4 J with hht, 1.5e-5 J with abam), where a damping of 0.05 s/m would take 0.9 J at the first.
#[test]
fn elastic_impacts_conserve_energy() {
    for analysis in ["dynamics", "dynamics_hht", "dynamics_abam"] {
        let text = patch(&example_text("bouncing_disc.yaml"), "damping: 0.05", "damping: 0");
        let text = patch(&text, "friction: {mu: 0.3}", "friction: {mu: 0}");
        let r = Model::from_yaml(&text)
            .unwrap()
            .run(analysis, &Default::default())
            .unwrap_or_else(|f| panic!("{}", f.error));
        let (t, v) = (col(&r, "kinetic_energy"), col(&r, "potential_energy"));
        let drift = (0..r.len()).map(|k| (t[k] + v[k] - t[0] - v[0]).abs()).fold(0.0, f64::max);
        let p = col(&r, "bounce.penetration");
        let impacts = (1..r.len()).filter(|&k| p[k] > 0.0 && p[k - 1] == 0.0).count();
        assert!(impacts >= 3, "{analysis}: {impacts} impacts");
        println!("{analysis}: energy drift {drift:.3e} J, {impacts} impacts");
        assert!(drift < 1e-3, "{analysis}: energy drift {drift:.3e} J");
    }
}

/// A disc held at a constant angle (so that it slides, not rolls) starts at 1 m/s resting on the
/// floor at its static penetration `(m g / k)^(1/n)`; friction `mu = 0.3` stops it after
/// `v0^2 / (2 mu g) = 0.16989` m. The tanh transition leaves the last `v_s` of speed to decay over
/// `v_s / (mu g)`, adding about `v_s^2 / (mu g) = 3.4e-7` m; the run's error is of order rtol:
/// 1e-6 m.
#[test]
fn sliding_block_stops_at_the_coulomb_distance() {
    let delta = (G / K).powf(1.0 / N);
    let text = format!(
        "name: slide
gravity: [0, -9.81]
bodies:
  block: {{mass: 1, inertia: 0.00125, position: [0, {y}], velocity: [1, 0]}}
joints:
  level: {{type: absolute_angle, body: block}}
forces:
  floor:
    type: contact
    body_i: block
    shape_i: {{circle: {{radius: 0.05}}}}
    body_j: ground
    shape_j: {{polyline: [[-1, 0], [0.5, 0], [1, 0]]}}
    stiffness: 1.0e6
    damping: 0.05
    friction: {{mu: 0.3}}
analyses:
  slide: {{type: dynamic, t_end: 0.5, step: 0.01, solver: {{rtol: 1.0e-8, atol: 1.0e-8}}}}
  slide_hht: {{type: dynamic, integrator: hht, t_end: 0.5, step: 0.01, solver: {{rtol: 1.0e-8, atol: 1.0e-8}}}}
  slide_abam: {{type: dynamic, integrator: abam, t_end: 0.5, step: 0.01, solver: {{rtol: 1.0e-8, atol: 1.0e-8}}}}
",
        y = R - delta
    );
    let want = 1.0 / (2.0 * 0.3 * G);
    for analysis in ["slide", "slide_hht", "slide_abam"] {
        let r = Model::from_yaml(&text)
            .unwrap()
            .run(analysis, &Default::default())
            .unwrap_or_else(|f| panic!("{}", f.error));
        let x = col(&r, "block.x");
        let stop = x[r.len() - 1];
        println!("{analysis}: stopped at {stop} m, want {want}");
        assert!((stop - want).abs() < 1e-6, "{analysis}: stopped at {stop} m, want {want}");
        let fnl = col(&r, "floor.fn");
        assert!((fnl[5] - G).abs() < 1e-6, "{analysis}: normal force {} while sliding", fnl[5]);
        let ft = col(&r, "floor.ft")[5];
        assert!((ft.abs() - 0.3 * G).abs() < 1e-6, "{analysis}: friction {ft} while sliding");
    }
}

/// Bad input names its field.
#[test]
fn bad_contacts_name_their_fields() {
    let base = example_text("bouncing_disc.yaml");
    let cases = [
        ("stiffness: 1.0e6", "stiffness: -1", "forces.bounce.stiffness"),
        ("radius: 0.05", "radius: 0", "forces.bounce.shape_j.circle.radius"),
        ("body_j: disc", "body_j: wheel", "forces.bounce.body_j"),
        ("exponent: 1.5", "exponent: 0.5", "forces.bounce.exponent"),
        ("damping: 0.05", "damping: -1", "forces.bounce.damping"),
        (
            "friction: {mu: 0.3}",
            "friction: {mu: 0.3, transition_velocity: 0}",
            "forces.bounce.friction.transition_velocity",
        ),
        ("{circle: {centre: [0, 0], radius: 0.05}}", "{segment: [[0, 0], [1, 0]]}", "forces.bounce.shape_j"),
        ("{segment: [[-1, 0], [1, 0]]}", "{polyline: [[-1, 0], [-1, 0], [1, 0]]}", "forces.bounce.shape_i.polyline[1]"),
        ("{segment: [[-1, 0], [1, 0]]}", "{polyline: [[-1, 0]]}", "forces.bounce.shape_i.polyline"),
        ("body_j: disc", "body_j: ground", "forces.bounce.body_j"),
    ];
    for (from, to, path) in cases {
        let text = patch(&base, from, to);
        let message = match Model::from_yaml(&text) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("{to}: accepted"),
        };
        assert!(message.contains(path), "{to}: {message}");
    }
}
