//! `examples/motion_laws.yaml`: five sliders driven along their guides by the standard motion
//! laws (a rise of 0.1 m in 0.4 s from t = 0, and the return from 0.6 s). Every output
//! point's position and acceleration against the laws written out here independently (the
//! modified trapezoid by its acceleration's definition, as cam design books give it), and the
//! inverse analysis's drive force against `m x''`.

use linkwork::Model;
use std::f64::consts::PI;

const RISE: f64 = 0.1;
const MASS: f64 = 2.0;
const DURATION: f64 = 0.4;

/// The normalized rise and its second derivative of each law, `0 < u < 1`; `None` for a rise
/// not written out here (the modified trapezoid's, checked by its acceleration).
fn law(name: &str, u: f64) -> (Option<f64>, f64) {
    match name {
        "step" => (Some(3.0 * u * u - 2.0 * u.powi(3)), 6.0 - 12.0 * u),
        "step5" => {
            (Some(10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5)), 60.0 * u - 180.0 * u * u + 120.0 * u.powi(3))
        }
        "cycloidal" => (Some(u - (2.0 * PI * u).sin() / (2.0 * PI)), 2.0 * PI * (2.0 * PI * u).sin()),
        "harmonic" => (Some((1.0 - (PI * u).cos()) / 2.0), PI * PI / 2.0 * (PI * u).cos()),
        "modified_trapezoid" => {
            let a = 8.0 * PI / (2.0 + PI);
            let accel = match u {
                u if u <= 0.125 => a * (4.0 * PI * u).sin(),
                u if u <= 0.375 => a,
                u if u <= 0.625 => a * (4.0 * PI * (u - 0.375)).cos(),
                u if u <= 0.875 => -a,
                u => -a * (4.0 * PI * (u - 0.875)).cos(),
            };
            (None, accel)
        }
        other => panic!("no law {other}"),
    }
}

/// `(x, x'')` of a slider at `t`: the rise from 0 minus the return from 0.6 s; a dwell is at
/// the end value of the part before it, with no acceleration (the laws' ends take the dwell's
/// side).
fn motion(name: &str, t: f64) -> (Option<f64>, f64) {
    let (mut x, mut a) = (Some(0.0), 0.0);
    for (start, sign) in [(0.0, 1.0), (0.6, -1.0)] {
        let u = (t - start) / DURATION;
        if u >= 1.0 {
            x = x.map(|x| x + sign * RISE);
        } else if u > 0.0 {
            let (s, s2) = law(name, u);
            x = x.zip(s).map(|(x, s)| x + sign * RISE * s);
            a += sign * RISE / (DURATION * DURATION) * s2;
        }
    }
    (x, a)
}

#[test]
fn sliders_follow_their_laws_and_need_m_times_their_acceleration() {
    let path = format!("{}/../../examples/motion_laws.yaml", env!("CARGO_MANIFEST_DIR"));
    let model = Model::load(path).unwrap();
    let r = model.run("drive", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    assert_eq!(r.len(), 121);
    let column = |name: String| r.column(&name).unwrap_or_else(|| panic!("no column {name}")).to_vec();
    for name in ["step", "step5", "cycloidal", "harmonic", "modified_trapezoid"] {
        let (x, ax, effort) =
            (column(format!("{name}.x")), column(format!("{name}.ax")), column(format!("{name}_drive.effort")));
        for (k, &t) in r.time.iter().enumerate() {
            let (want_x, want_a) = motion(name, t);
            // Positions: the kinematic solver's tolerance is 1e-12 m on the driver's equation.
            if let Some(want_x) = want_x {
                assert!((x[k] - want_x).abs() < 1e-12, "{name} at t = {t}: x = {} vs {want_x}", x[k]);
            }
            // Accelerations (peak 3.1 m/s^2): exact derivatives, solved linearly: rounding only.
            assert!((ax[k] - want_a).abs() < 1e-11, "{name} at t = {t}: x'' = {} vs {want_a}", ax[k]);
            // The drive force balances the slider's inertia alone (the guide holds its weight).
            assert!(
                (effort[k] - MASS * want_a).abs() < 1e-10,
                "{name} at t = {t}: force {} vs {}",
                effort[k],
                MASS * want_a
            );
        }
    }
}
