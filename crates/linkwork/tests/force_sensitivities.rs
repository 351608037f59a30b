//! `Dae::add_load_along`, the derivative of the loads along a parameter that the inverse,
//! static, modes and dynamic sensitivities share (gravity through the masses, each force through
//! its coordinates, its numbers and the parameters its expressions read), against central finite
//! differences of `Dae::load` of the model compiled again with the parameter moved (`--set`),
//! with the coordinates and velocities moved along a direction at the same time.

use linkwork::analysis::dynamic::Dae;
use linkwork::Model;

/// `Q(q, qdot, t)` of `model` with every driver and force active.
fn loads(model: &Model, q: &[f64], qdot: &[f64], t: f64) -> Vec<f64> {
    let drivers: Vec<usize> = (0..model.drivers.len()).collect();
    let forces: Vec<usize> = (0..model.forces.len()).collect();
    let mut dae = Dae::new(model, &drivers, &forces).expect("the equations");
    let mut out = vec![0.0; q.len()];
    dae.load(q, qdot, t, &mut out);
    out
}

/// For each parameter `p` of `model`, at the coordinates `q`, velocities `qdot` and time `t`: `add_load_along` with the coordinates and velocities moving along `dq`, `dv`
/// (fixed directions over the parameter's size, so that a step of the parameter moves them by
/// the same fraction, times `states`: 0 holds them) against the central difference of
/// `load(model with p +- h, q +- h dq, qdot +- h dv)`,
/// Richardson-extrapolated from the steps `h = 1e-3` and `h / 2` of the parameter's size
/// (truncation `O(h^4) ~ 1e-12`, round-off `eps / h ~ 1e-13` relative), to 1e-8 of the load's
/// largest derivative (at least 1e-8 absolute). Returns, for each parameter, how many entries
/// of the derivative are not zero, and the largest error relative to that scale.
fn check(model: &Model, name: &str, (q, qdot, t): (&[f64], &[f64], f64), states: f64) -> Vec<(String, usize, f64)> {
    let n = q.len();
    let drivers: Vec<usize> = (0..model.drivers.len()).collect();
    let forces: Vec<usize> = (0..model.forces.len()).collect();
    let dae = Dae::new(model, &drivers, &forces).expect("the equations");
    let mut moving = Vec::new();
    for (p, (param, &value)) in model.parameters.iter().enumerate() {
        let size = value.abs().max(1.0);
        let dq: Vec<f64> = (0..n).map(|k| states * 0.1 * ((k as f64) * 0.7).sin() / size).collect();
        let dv: Vec<f64> = (0..n).map(|k| states * 0.3 * ((k as f64) * 1.3).cos() / size).collect();
        let mut exact = vec![0.0; n];
        dae.add_load_along(q, qdot, t, &dq, &dv, p, &mut exact)
            .unwrap_or_else(|f| panic!("{name}: {f} has no derivatives"));
        let central = |h: f64| {
            let at = |s: f64| {
                let set =
                    model.with_parameters(&[(param.clone(), format!("{:e}", value + s * h))]).expect("the model set");
                let qs: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a + s * h * b).collect();
                let vs: Vec<f64> = qdot.iter().zip(&dv).map(|(a, b)| a + s * h * b).collect();
                loads(&set, &qs, &vs, t)
            };
            let (up, down) = (at(1.0), at(-1.0));
            up.iter().zip(&down).map(|(a, b)| (a - b) / (2.0 * h)).collect::<Vec<f64>>()
        };
        let h = 1e-3 * size;
        let (coarse, fine) = (central(h), central(h / 2.0));
        let fd: Vec<f64> = coarse.iter().zip(&fine).map(|(c, f)| (4.0 * f - c) / 3.0).collect();
        let scale = exact.iter().fold(1.0f64, |a, b| a.max(b.abs()));
        let mut worst = 0.0f64;
        for k in 0..n {
            let err = (exact[k] - fd[k]).abs();
            worst = worst.max(err / scale);
            assert!(
                err <= 1e-8 * scale,
                "{name}: dQ[{k}]/d{param}: {} vs {} (error {err:e}, scale {scale:e})",
                exact[k],
                fd[k]
            );
        }
        moving.push((param.clone(), exact.iter().filter(|e| **e != 0.0).count(), worst));
    }
    eprintln!("{name}: (parameter, entries moved, largest relative error) {moving:?}");
    moving
}

/// Every force type with numbers written with parameters (`tests/models/forces_param.yaml`),
/// the disc 5 mm into the floor and sliding, so that the contact and its friction act. (The
/// quick-return, `quick_return_a`, has forces, but no parameter moves its loads.)
#[test]
fn every_force_type_agrees_with_finite_differences_of_compiles() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/models/forces_param.yaml"))
        .expect("the model");
    let model = Model::from_yaml(&text).expect("the model");
    // The bar turned 0.2 rad from where it starts, so that the spring (at its free length
    // there) pulls; the disc as it starts.
    let mut q = model.q0();
    q[2] += 0.2;
    let qdot = [0.0, 0.1, 0.8, 0.3, -0.05, 0.4];
    assert_eq!(q.len(), qdot.len());
    check(&model, "forces_param", (&q, &qdot, 0.37), 1.0);
    // The parameters alone: each moves some load, so that no check is of zeros against zeros.
    for (param, moved, _) in check(&model, "forces_param", (&q, &qdot, 0.37), 0.0) {
        assert!(moved > 0, "{param} moves no load");
    }
}
