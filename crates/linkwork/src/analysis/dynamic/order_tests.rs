//! Observed orders of convergence against theory, on a problem with a closed form: a bar
//! pinned to ground at a point off its centre of mass, turned by a linear rotational spring,
//! without gravity. With `J_O = J + m d^2` its angle obeys `J_O phi'' = -k phi` exactly, so
//! `phi(t) = phi_0 cos(omega t)`, `omega = sqrt(k / J_O)`, while the centre of mass moves on a
//! circle and the pin's two constraint rows and multipliers are active throughout.
//!
//! Each method runs at constant steps `h, h/2, h/4` (the crate-internal `fixed_step`, no error
//! test) with tight Newton tolerances, and the observed order `log2(e(h) / e(h/2))` of the
//! largest angle error at the output times must be within 0.25 of the theoretical order. BDF's
//! start-up raises the order one step at a time, so its first steps (orders 1, 2, ...) start
//! at `1e-6 s` and double up to `h`: their errors (`1e-12` for the order-1 step) stay far below
//! the `O(h^k)` error being measured. Newton runs to `1e-12`, so errors stay above `1e-10`.
//!
//! Measured (errors at `h, h/2, h/4`; observed orders): BDF3 `5.6e-4, 7.3e-5, 9.2e-6` (2.9, 3.0);
//! BDF4 `5.0e-5, 3.1e-6, 1.9e-7` (4.0, 4.0); SI2 BDF5 `7.2e-6, 2.0e-7, 5.3e-9` (5.2, 5.2). Index-3
//! BDF5 meets a floor near `3e-7` at `h = 0.025`: in index 3 the velocities are differences of
//! positions, `v = c q + b`, so the start-up's small steps turn position errors into velocity
//! errors `1/h` larger; SI2, whose velocities are unknowns under their own constraints, has no
//! such floor (this is why Adams offers SI2).

use crate::analysis::dynamic::{run_dynamic, Formulation, IntegratorKind};
use crate::Model;

/// `phi_0 = 0.5`, `m = 2`, `J = 0.5`, `d = 0.5`, `k = 4`: `J_O = 1`, `omega = 2`.
const START: f64 = 1e-6;
const MODEL: &str = "
name: pinned bar on a torsion spring
bodies:
  bar:
    mass: 2
    inertia: 0.5
    position: [0.43879128094518, 0.23971276930210]   # 0.5 (cos 0.5, sin 0.5)
    angle: 0.5
    points: {O: [-0.5, 0]}
    given: [phi]
joints:
  O: {type: revolute, body_i: bar, point_i: O, body_j: ground, point_j: [0, 0]}
forces:
  spring: {type: rotational_spring_damper, body_i: bar, body_j: ground, stiffness: 4, free_angle: 0}
analyses:
  dynamics: {type: dynamic, t_end: 2, step: 0.1}
";

/// Largest `|phi - 0.5 cos(2 t)|` at the output times of a constant-step run.
fn error(kind: IntegratorKind, formulation: Formulation, order: usize, h: f64) -> f64 {
    let start = if kind == IntegratorKind::Bdf { Some(START) } else { None };
    let model = Model::from_yaml(MODEL).unwrap();
    let mut analysis = model.analysis("dynamics").unwrap().clone();
    let s = &mut analysis.integrator;
    s.kind = kind;
    s.formulation = formulation;
    s.max_order = Some(order);
    s.rtol = 1e-12;
    s.atol = 1e-12;
    s.fixed_step = Some(h);
    s.initial_step = start;
    let r = run_dynamic(&model, &analysis).unwrap_or_else(|f| panic!("{kind:?} h {h}: {}", f.error));
    let phi = r.column("bar.phi").unwrap();
    r.time.iter().zip(phi).map(|(t, p)| (p - 0.5 * (2.0 * t).cos()).abs()).fold(0.0, f64::max)
}

fn observed_order(kind: IntegratorKind, formulation: Formulation, order: usize, h: f64) -> [f64; 2] {
    let e: Vec<f64> = [h, h / 2.0, h / 4.0].iter().map(|&h| error(kind, formulation, order, h)).collect();
    eprintln!("{kind:?} {formulation:?} order {order}: errors {e:?}");
    [(e[0] / e[1]).log2(), (e[1] / e[2]).log2()]
}

fn check(kind: IntegratorKind, formulation: Formulation, order: usize, h: f64, theory: f64) {
    for p in observed_order(kind, formulation, order, h) {
        assert!((p - theory).abs() < 0.25, "{kind:?} {formulation:?} order {order}: observed {p}, theory {theory}");
    }
}

#[test]
fn bdf1_and_bdf2_converge_at_their_orders() {
    for formulation in [Formulation::Index3, Formulation::Si2] {
        check(IntegratorKind::Bdf, formulation, 1, 0.0025, 1.0);
        check(IntegratorKind::Bdf, formulation, 2, 0.01, 2.0);
    }
}

#[test]
fn bdf3_to_bdf5_converge_at_their_orders() {
    check(IntegratorKind::Bdf, Formulation::Index3, 3, 0.05, 3.0);
    check(IntegratorKind::Bdf, Formulation::Index3, 4, 0.05, 4.0);
    check(IntegratorKind::Bdf, Formulation::Si2, 5, 0.05, 5.0);
}

#[test]
fn hht_converges_at_second_order() {
    check(IntegratorKind::Hht, Formulation::Index3, 2, 0.02, 2.0);
}
