//! Dynamics against independent references: conservation of energy, closed-form accelerations,
//! Newton-Euler balances of the reported reactions, and a second formulation of a mechanism.

mod common;

use common::run;

fn col<'a>(r: &'a linkwork::Results, name: &str) -> &'a [f64] {
    r.column(name).unwrap_or_else(|| panic!("no column {name}"))
}

/// Largest change of the total mechanical energy `T + V - W` over the run.
fn energy_drift(r: &linkwork::Results) -> f64 {
    let (t, v, w) = (col(r, "kinetic_energy"), col(r, "potential_energy"), col(r, "nonconservative_work"));
    let e0 = t[0] + v[0] - w[0];
    (0..r.len()).map(|k| (t[k] + v[k] - w[k] - e0).abs()).fold(0.0, f64::max)
}

#[test]
fn double_pendulum_energy_hht() {
    let (_, r) = run("double_pendulum.yaml", "dynamics_hht");
    let drift = energy_drift(&r);
    eprintln!("hht drift {drift:e} steps {:?}", r.summary["statistics"]);
    assert!(drift < 5e-2, "drift {drift}");
}

/// A four-bar under gravity with a motor torque, a spring-damper between the coupler and ground,
/// a rotational spring on the rocker and a follower force on the coupler; one variant drives the
/// crank so that a driver effort appears, and one flips the first joint to ground-first.
fn loaded_fourbar(driven: bool) -> String {
    let base = std::fs::read_to_string(common::example("fourbar.yaml")).unwrap();
    let base = base.split("drivers:").next().unwrap().to_string();
    let base = base.replace(
        "  O4: {type: revolute, body_i: rocker, point_i: O4, body_j: ground, point_j: O4}",
        "  O4: {type: revolute, body_i: ground, point_i: O4, body_j: rocker, point_j: O4}",
    );
    let analysis = if driven {
        "  dynamics: {type: dynamic, integrator: hht, drivers: [motor], t_end: 0.5, step: 0.05}"
    } else {
        "  dynamics: {type: dynamic, integrator: hht, drivers: [], t_end: 0.5, step: 0.05}"
    };
    format!(
        "{base}gravity: [0, -9.81]
drivers:
  motor: {{type: angle, body: crank, function: \"2*t + 0.3*sin(3*t)\"}}
forces:
  motor_torque: {{type: torque, body: crank, torque: \"0.4 - 0.05*crank.omega\"}}
  spring: {{type: spring_damper, body_i: coupler, point_i: [0.05, 0.02], body_j: ground, point_j: [0.1, 0.4], stiffness: 40, damping: 0.3, free_length: 0.2}}
  torsion: {{type: rotational_spring_damper, body_i: rocker, body_j: ground, stiffness: 0.5, damping: 0.01}}
  push: {{type: force, body: coupler, point: B, frame: body, fx: 0.7, fy: \"-0.2*t\"}}
analyses:
{analysis}
"
    )
}

/// Reactions from the multipliers against a Newton-Euler balance of every body: at each output
/// time, `m a = sum of joint forces + applied forces + m g` and `J alpha = sum of moments about
/// the centre of mass`, with each joint's force on its second body the opposite of the reported
/// force on its first body. The applied loads come from the force elements, the joint forces from
/// the `<joint>.fx, .fy, .torque` columns (moments about the joint's point, moved to each centre of
/// mass here). Tolerance `1e-8` relative to the largest force: both sides come from one linear
/// solve at the output state, so only rounding separates them.
#[test]
fn reactions_balance_every_body() {
    for driven in [false, true] {
        let model = linkwork::Model::from_yaml(&loaded_fourbar(driven)).unwrap();
        let r = model.run("dynamics").unwrap_or_else(|f| panic!("{}", f.error));
        let g = model.gravity;
        for k in 0..r.len() {
            let at = |name: &str| col(&r, name)[k];
            let q: Vec<f64> =
                model.bodies.iter().flat_map(|b| ["x", "y", "phi"].map(|c| at(&format!("{}.{c}", b.name)))).collect();
            let v: Vec<f64> = model
                .bodies
                .iter()
                .flat_map(|b| ["vx", "vy", "omega"].map(|c| at(&format!("{}.{c}", b.name))))
                .collect();
            let t = r.time[k];
            // Residual per body: m a - (applied + joint forces), J alpha - moments.
            let mut res: Vec<f64> = model
                .bodies
                .iter()
                .flat_map(|b| {
                    let a = ["ax", "ay", "alpha"].map(|c| at(&format!("{}.{c}", b.name)));
                    [b.mass * a[0] - b.mass * g[0], b.mass * a[1] - b.mass * g[1], b.inertia * a[2]]
                })
                .collect();
            let mut scale = 1.0f64;
            for f in &model.forces {
                let cols = f.force.columns();
                let x: Vec<f64> = cols.iter().map(|&c| q[c]).collect();
                let xv: Vec<f64> = cols.iter().map(|&c| v[c]).collect();
                let mut out = vec![0.0; cols.len()];
                f.force.load(&x, &xv, t, &mut out);
                for (&c, &val) in cols.iter().zip(&out) {
                    res[c] -= val;
                    scale = scale.max(val.abs());
                }
            }
            for j in &model.joints {
                let anchor = j.constraint.anchor();
                let f = [at(&format!("{}.fx", j.name)), at(&format!("{}.fy", j.name))];
                let torque = at(&format!("{}.torque", j.name));
                scale = scale.max(f[0].abs()).max(f[1].abs());
                // The joint's point in the global frame.
                let p = match anchor.i.0 {
                    Some(b) => {
                        let (s, c) = q[b + 2].sin_cos();
                        let sp = anchor.point;
                        [q[b] + c * sp[0] - s * sp[1], q[b + 1] + s * sp[0] + c * sp[1]]
                    }
                    None => anchor.point,
                };
                // Force-moment systems: (f, torque about p) on i, the opposite on j.
                for (body, sign) in [(anchor.i, 1.0), (anchor.j, -1.0)] {
                    let Some(b) = body.0 else { continue };
                    let d = [p[0] - q[b], p[1] - q[b + 1]];
                    let (fx, fy) = (sign * f[0], sign * f[1]);
                    res[b] -= fx;
                    res[b + 1] -= fy;
                    res[b + 2] -= sign * torque + d[0] * fy - d[1] * fx;
                }
            }
            if driven {
                // The angle driver's effort is a torque on the crank (body 0).
                res[2] -= at("motor.effort");
            }
            let worst = res.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            assert!(worst < 1e-8 * scale, "driven {driven}, t = {t}: Newton-Euler residual {worst:e} (scale {scale})");
        }
        if driven {
            assert!(col(&r, "motor.effort").iter().any(|e| e.abs() > 1e-3), "the motor works");
        }
    }
}
