//! Cam joints (`type: cam`): `examples/cam_roller.yaml`, a disc cam given by its pitch curve
//! lifting a radial roller follower, against the motion law the curve was made from, the closed
//! form of the pressure angle, and virtual work; `examples/cam_profile.yaml`, an eccentric disc
//! given by its working surface (expressions and a point table), against the closed form of the
//! lift and virtual work; cam_roller.yaml's cam given by its surface instead; bad cams.

mod common;

use common::problems;
use linkwork::expr::{HyperDual, Scalar};
use linkwork::Model;
use std::f64::consts::PI;

/// The example's lift in the cam angle `theta`: a cycloidal rise of 20 mm over 120 deg, a dwell
/// to 180, a cycloidal return over 90 deg, a dwell to 360. `(s, s', s'')` in `theta`.
fn lift(theta: f64) -> (f64, f64, f64) {
    common::cycloidal_cam_lift(theta, 0.02, 2.0 * PI / 3.0, PI / 2.0)
}

const BASE: f64 = 0.05;

#[test]
fn the_follower_moves_by_the_law_and_the_pressure_angle_is_its_closed_form() {
    // The cam turns on past 360 deg, across the pitch curve's seam (psi = +-pi, at theta =
    // 270 deg) twice.
    let (r, [y, vy, ay]) = common::cam_motion("cam_roller.yaml");
    let pressure = common::col(&r, "pressure_angle");
    let omega = 2.0 * PI;
    let mut worst = [0.0f64; 4];
    let (mut low, mut high) = (0.0f64, 0.0f64);
    for (k, &t) in r.time.iter().enumerate() {
        let (s, d1, d2) = lift(omega * t);
        worst[0] = worst[0].max((y[k] - BASE - s).abs());
        worst[1] = worst[1].max((vy[k] - d1 * omega).abs());
        worst[2] = worst[2].max((ay[k] - d2 * omega * omega).abs());
        worst[3] = worst[3].max((pressure[k] - (d1 / (BASE + s)).atan()).abs());
        (low, high) = (low.min(pressure[k]), high.max(pressure[k]));
    }
    // The pitch curve is the law itself (no interpolation): the lift is exact to the position
    // solver's tolerance, 1e-10 on the constraint, and velocity and acceleration come from
    // linear solves with the exact Jacobian and gamma, rounding on values of 0.1 m/s and
    // 2 m/s^2. The pressure angle is the law's slope over the radius at the solved position.
    // Measured: 2e-17 m, 1e-16 m/s, 3e-13 m/s^2 and 2e-16 rad.
    assert!(worst[0] < 1e-9, "lift error {:e}", worst[0]);
    assert!(worst[1] < 1e-9, "velocity error {:e}", worst[1]);
    assert!(worst[2] < 1e-8, "acceleration error {:e}", worst[2]);
    assert!(worst[3] < 1e-9, "pressure angle error {:e}", worst[3]);
    // The extremes lie near the law's steepest points (mid-rise 2H/beta = 0.019 m/rad over a
    // radius of 0.06 m, mid-return 0.025 m/rad): atan(0.318) = 0.308 rad on the rise (the
    // quotient peaks a little earlier, at 0.311) and -0.405 rad on the steeper return, whose sign
    // says the cam lets the follower in.
    assert!((0.305..0.315).contains(&high) && (-0.41..-0.40).contains(&low), "pressure angle in [{low}, {high}]");
}

#[test]
fn the_motor_torque_pays_the_followers_work() {
    let (_, r) = common::run("cam_roller.yaml", "drive");
    let (ay, torque) = (common::col(&r, "follower.ay"), common::col(&r, "motor.effort"));
    // Virtual work: the cam turns steadily about its centre of mass and the guide is frictionless,
    // so T omega = F v_y with F = m (a_y + g) the force the follower needs and v_y = s' omega:
    // T = F ds/dtheta.
    let (m, g, omega) = (0.3, 9.81, 2.0 * PI);
    let peak = torque.iter().fold(0.0f64, |p, t| p.max(t.abs()));
    let mut worst = 0.0f64;
    for k in 0..r.len() {
        let (_, d1, _) = lift(omega * r.time[k]);
        let want = m * (ay[k] + g) * d1;
        worst = worst.max((torque[k] - want).abs());
    }
    // The multipliers come from one well-conditioned linear solve: 1e-10 N m against a peak of
    // 0.08 N m is rounding with room (measured 7e-15 N m).
    assert!(worst < 1e-10, "torque error {worst:e}");
    assert!(peak > 0.01, "the follower's lift needs torque: peak {peak}");
}

#[test]
fn bad_cams_are_problems_at_their_fields() {
    let model = |joint: &str, measure: &str| {
        format!(
            "parameters:\n  r0: 0.05\n\
             bodies:\n  cam: {{mass: 1, inertia: 0.1, position: [0, 0]}}\n  \
             follower: {{mass: 1, inertia: 0.1, position: [0, 0.05]}}\n\
             joints:\n  pin: {{type: revolute, body_i: ground, body_j: cam, at: [0, 0]}}\n  \
             contact: {{type: cam, {joint}}}\n\
             measures:\n  p: {{type: pressure_angle, joint: {measure}}}\n"
        )
    };
    let good = "body_i: cam, body_j: follower, point_j: [0, 0]";
    let cases = [
        (
            "body_i: cma, body_j: follower, point_j: [0, 0], radius: r0",
            "contact",
            "joints.contact.body_i: unknown body 'cma'",
        ),
        (&format!("{good}, radius: 'r0 +'"), "contact", "joints.contact.radius: cannot read the expression 'r0 +'"),
        (
            &format!("{good}, radius: 'r0 + cam.phi'"),
            "contact",
            "joints.contact.radius: cannot read the expression 'r0 + cam.phi'",
        ),
        (&format!("{good}, radius: 'r0 + t'"), "contact", "expected psi (the polar angle"),
        (
            &format!("{good}, radius: r0, roller_radius: -1"),
            "contact",
            "joints.contact.roller_radius: expected a number >= 0",
        ),
        (&format!("{good}, radius: r0"), "pin", "measures.p.joint: 'pin' is a revolute joint; expected a cam joint"),
        (&format!("{good}, radius: r0"), "cams", "measures.p.joint: unknown joint 'cams'"),
    ];
    let centred = model(&format!("{good}, radius: r0"), "contact").replace("position: [0, 0.05]", "position: [0, 0]");
    let list = problems(&centred);
    assert!(
        list.iter().any(|p| p.starts_with("joints.contact: the follower's point is at the cam's centre")),
        "{list:#?}"
    );
    for (joint, measure, want) in cases {
        let list = problems(&model(joint, measure));
        assert!(list.iter().any(|p| p.contains(want)), "no '{want}' in {list:#?}");
    }
}

// --- The cam given by its working surface: examples/cam_profile.yaml -----------------------------

const RC: f64 = 0.04;
const ECC: f64 = 0.01;
const ROLLER: f64 = 0.01;

/// The roller centre's distance from the pivot along a radial follower's line, for the eccentric
/// disc: `s = e cos(a) + sqrt((Rc + r)^2 - e^2 sin(a)^2)`, `a` the angle from the follower's line
/// to the eccentricity (law of cosines in the triangle pivot, disc centre, roller centre).
fn eccentric_lift<S: Scalar>(a: S) -> S {
    let k = S::constant;
    k(ECC) * a.cos() + (k((RC + ROLLER) * (RC + ROLLER)) - k(ECC * ECC) * a.sin() * a.sin()).sqrt()
}

#[test]
fn a_roller_on_an_eccentric_disc_lifts_by_the_closed_form() {
    let (_, r) = common::run("cam_profile.yaml", "motion");
    assert_eq!(r.len(), 541);
    let omega = 2.0 * PI;
    // The cam's angle is theta = omega t; the upper follower's line points at pi/2, the lower's
    // at -pi/2, so a = theta - pi/2 and theta + pi/2, and the lower follower is at y = -s.
    let upper = |t: HyperDual| eccentric_lift(t * HyperDual::constant(omega) - HyperDual::constant(PI / 2.0));
    let lower = |t: HyperDual| -eccentric_lift(t * HyperDual::constant(omega) + HyperDual::constant(PI / 2.0));
    let worst = |body: &str, f: &dyn Fn(HyperDual) -> HyperDual| {
        let cols: Vec<&[f64]> = ["y", "vy", "ay"].iter().map(|q| common::col(&r, &format!("{body}.{q}"))).collect();
        let mut worst = [0.0f64; 3];
        for (k, &t) in r.time.iter().enumerate() {
            let want = common::derivatives(f, t);
            for d in 0..3 {
                worst[d] = worst[d].max((cols[d][k] - want[d]).abs());
            }
        }
        eprintln!(
            "{body}: largest differences (position, velocity, acceleration) {:.2e} {:.2e} {:.2e}",
            worst[0], worst[1], worst[2]
        );
        worst
    };
    // The expressions are the disc itself: the lift is exact to the position solver's tolerance
    // (1e-10 on the constraint), velocity and acceleration to the rounding of linear solves with
    // the exact Jacobian and gamma (values of 0.06 m/s and 0.4 m/s^2).
    // Measured: 9.5e-13 m, 6.9e-14 m/s, 1.5e-12 m/s^2.
    let [p, v, a] = worst("upper", &upper);
    assert!(p < 1e-9 && v < 1e-9 && a < 1e-8, "upper: {p:e} {v:e} {a:e}");
    // The table: 360 points of the disc joined by a periodic cubic spline over their chord
    // length. A cubic spline's value, slope and curvature miss the curve's by about h^4 / 384,
    // h^3 / 24 and 3 h^2 / 8 times |p''''| = 1 / Rc^3 (in arc length; de Boor, ch. V), with
    // h = 2 pi Rc / 360 = 0.7 mm: 9.7e-12 m (the spline's unit test measures this constant on a
    // circle), 2.2e-7 rad of the tangent and 2.9e-3 1/m of the curvature (25 1/m). The lift is
    // off by the first over the cosine of the pressure angle (at most 0.2 rad): 1e-11 m; the
    // velocity by the tangent's error times the contact's sliding speed (some 0.3 m/s): 7e-8
    // m/s; the acceleration by the curvature's error times that speed squared: 3e-4 m/s^2.
    // Measured: 1.06e-11 m, 1.3e-8 m/s, 5.8e-5 m/s^2.
    let [p, v, a] = worst("lower", &lower);
    assert!(p < 2e-11 && v < 1e-7 && a < 3e-4, "lower: {p:e} {v:e} {a:e}");
    // The pressure angle: the contact normal runs through the disc's centre, so by the law of
    // sines it makes asin(e sin(a) / (Rc + r)) with the follower's line, positive (pushing out)
    // where the lift rises, sin(a) < 0. It is read at the solved position, so it carries the
    // lift's error over the lever Rc + r. Measured: 3.7e-12 rad.
    let pressure = common::col(&r, "pressure_angle");
    let mut worst_angle = 0.0f64;
    for (k, &t) in r.time.iter().enumerate() {
        let a = omega * t - PI / 2.0;
        worst_angle = worst_angle.max((pressure[k] + (ECC * a.sin() / (RC + ROLLER)).asin()).abs());
    }
    eprintln!("pressure angle: largest difference {worst_angle:.2e}");
    assert!(worst_angle < 1e-9, "pressure angle error {worst_angle:e}");
}

#[test]
fn the_motor_torque_pays_both_followers_work() {
    let (_, r) = common::run("cam_profile.yaml", "drive");
    let torque = common::col(&r, "motor.effort");
    let (m, g, omega) = (0.3, 9.81, 2.0 * PI);
    let mut worst = 0.0f64;
    for (k, &t) in torque.iter().enumerate() {
        // Virtual work: T omega = sum of m (a_y + g) v_y over the followers.
        let want: f64 = ["upper", "lower"]
            .iter()
            .map(|b| m * (common::col(&r, &format!("{b}.ay"))[k] + g) * common::col(&r, &format!("{b}.vy"))[k])
            .sum::<f64>()
            / omega;
        worst = worst.max((t - want).abs());
    }
    // One well-conditioned linear solve for the multipliers: rounding on a torque of 0.1 N m.
    // Measured: 5.2e-15 N m.
    eprintln!("torque against virtual work: {worst:.2e}");
    assert!(worst < 1e-10, "torque error {worst:e}");
}

/// examples/cam_roller.yaml's cam, given by its working surface instead of its pitch curve: the
/// pitch curve `R(psi) = base + s(theta)`, `theta = pi/2 - psi` the cam angle, offset inward by
/// the roller's radius. With `u = theta` the curve's parameter (`psi = pi/2 - u`), the pitch
/// point is `R (sin u, cos u)` and its outward normal `(R sin u - s' cos u, R cos u + s' sin u) /
/// sqrt(R^2 + s'^2)` (`dR/dpsi = -s'`), so the surface is the pitch point less `r` times that.
fn roller_surface_point(u: f64) -> [f64; 2] {
    let (s, d1, _) = lift(u);
    let (r, d) = (BASE + s, (BASE + s).hypot(d1));
    let n = [(r * u.sin() - d1 * u.cos()) / d, (r * u.cos() + d1 * u.sin()) / d];
    [r * u.sin() - 0.01 * n[0], r * u.cos() - 0.01 * n[1]]
}

/// The lift law of cam_roller.yaml in `th` as model-file text: `(s, s')`.
fn roller_law_text() -> (String, String) {
    let s = "(cycloidal(th, 0, 0, 2*pi/3, lift) + cycloidal(th, pi, lift, 3*pi/2, 0) - lift)";
    let d1 = "(if(th <= 2*pi/3, 3*lift/(2*pi)*(1 - cos(3*th)), 0) - if(th >= pi, if(th <= 3*pi/2, 2*lift/pi*(1 - cos(4*(th - pi))), 0), 0))";
    (s.replace("th", "u"), d1.replace("th", "u"))
}

/// The worst lift error of cam_roller.yaml's kinematic run with its joint replaced by `joint`.
fn roller_lift_error(joint: &str) -> f64 {
    let from = "    radius: \"base + cycloidal(pi/2 - psi, 0, 0, 2*pi/3, lift) + cycloidal(pi/2 - psi, pi, lift, 3*pi/2, 0) - lift\"\n";
    let text = common::patched_example("cam_roller.yaml", &[(from, joint)]);
    let model = Model::from_yaml(&text).unwrap_or_else(|e| panic!("{e}"));
    let r = model.run("motion", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    let y = common::col(&r, "follower.y");
    r.time.iter().enumerate().map(|(k, &t)| (y[k] - BASE - lift(2.0 * PI * t).0).abs()).fold(0.0, f64::max)
}

#[test]
fn the_roller_cam_given_by_its_surface_lifts_as_by_its_pitch_curve() {
    let (s, d1) = roller_law_text();
    let (r, d) = (format!("(base + {s})"), format!("sqrt((base + {s})^2 + {d1}^2)"));
    let x = format!("{r}*sin(u) - 10 mm*({r}*sin(u) - {d1}*cos(u))/{d}").replace("10 mm", "0.01");
    let y = format!("{r}*cos(u) - 0.01*({r}*cos(u) + {d1}*sin(u))/{d}");
    let expressions = roller_lift_error(&format!("    profile: {{x: \"{x}\", y: \"{y}\"}}\n"));
    // Expressions of the surface: the lift is the law's (which the pitch-curve joint follows to
    // 2e-17 m) to the position solver's tolerance, 1e-10 on the constraint. Measured: 1.1e-12 m.
    eprintln!("surface as expressions: lift error {expressions:.2e}");
    assert!(expressions < 1e-9, "{expressions:e}");
    // 360 points of the surface, a degree of cam angle apart (h = 0.7 to 1.2 mm of chord). The
    // spline misses the surface by about h^4 |p''''| / 384, |p''''| ~ 1 / rho^3 with the radius
    // of curvature rho >= 0.03 m (the law's jerk, which jumps at the ends of the rise and the
    // return, adds a term of order h^3 there of like size): 1e-13 to 1e-12 m, below the position
    // solver's tolerance; so 1e-10 m, the solver's, holds both. Measured: 1.1e-12 m, the solver's
    // tolerance dominating as with the expressions.
    let points: Vec<[f64; 2]> = (0..360).map(|k| roller_surface_point((k as f64).to_radians())).collect();
    let list = |c: usize| points.iter().map(|p| format!("{:?}", p[c])).collect::<Vec<_>>().join(", ");
    let table = roller_lift_error(&format!("    profile: {{x: [{}], y: [{}]}}\n", list(0), list(1)));
    eprintln!("surface as 360 points: lift error {table:.2e}");
    assert!(table < 1e-10, "{table:e}");
}

#[test]
fn bad_profiles_are_problems_at_their_fields() {
    let model = |joint: &str| {
        format!(
            "parameters:\n  r0: 0.05\n\
             bodies:\n  cam: {{mass: 1, inertia: 0.1, position: [0, 0]}}\n  \
             follower: {{mass: 1, inertia: 0.1, position: [0, 0.06]}}\n\
             joints:\n  pin: {{type: revolute, body_i: ground, body_j: cam, at: [0, 0]}}\n  \
             contact: {{type: cam, body_i: cam, body_j: follower, point_j: [0, 0], {joint}}}\n"
        )
    };
    let cases = [
        ("radius: r0, profile: {x: 'cos(u)', y: 'sin(u)'}", "joints.contact: give one of radius"),
        ("", "joints.contact: give one of radius"),
        ("profile: {x: 'r0*cos(u)', y: 'r0*sin(t)'}", "joints.contact.profile.y: cannot read the expression"),
        ("profile: {x: 'r0*cos(u)', y: 'r0*sin(u)', period: 6}", "joints.contact.profile.period: the curve does not close"),
        ("profile: {x: 'r0*cos(u)', y: 'r0*sin(u)', period: -1}", "joints.contact.profile.period: expected a positive"),
        ("profile: {x: 'r0*cos(u)', y: [0, 1, 2]}", "joints.contact.profile: expected x and y both"),
        ("profile: {x: [0, 1, 0], y: [0, 0]}", "joints.contact.profile: x has 3 values and y 2"),
        ("profile: {x: [0, 1, 0], y: [0, 0, 1], period: 1}", "joints.contact.profile.period: points take no period"),
        ("profile: {x: [0, 1, 1, 0], y: [0, 0, 0, 1]}", "joints.contact.profile: points 1 and 2 are equal"),
        ("profile: {file: nowhere.csv, x: x, y: y}", "joints.contact.profile.file: cannot read"),
        ("profile: {file: nowhere.csv, x: [1, 2], y: y}", "joints.contact.profile.x: expected the name of a column"),
        ("surface_radius: 'r0 + psi'", "joints.contact.surface_radius: the curve does not close"),
        ("surface_radius: 'r0 + u'", "joints.contact.surface_radius: cannot read the expression"),
        (
            "surface_radius: '1 + 0.6*cos(psi)', roller_radius: 0.85",
            "joints.contact.roller_radius: the roller (radius 0.85 m) is larger than the working surface's concave radius of curvature",
        ),
    ];
    for (joint, want) in cases {
        let list = problems(&model(joint));
        assert!(list.iter().any(|p| p.starts_with(want)), "no '{want}' in {list:#?}");
    }
    // Every field is read: a bad body and a bad profile are both reported.
    let both = model("profile: {x: 'r0*cos(u)', y: 'r0*sin(t)'}")
        .replace("body_j: follower, point_j", "body_j: folower, point_j");
    let list = problems(&both);
    for want in ["joints.contact.body_j: unknown body 'folower'", "joints.contact.profile.y: cannot read"] {
        assert!(list.iter().any(|p| p.starts_with(want)), "no '{want}' in {list:#?}");
    }
}

#[test]
fn a_roller_with_no_unique_nearest_point_stops_the_analysis_naming_the_joint() {
    // The roller's centre starts at the centre of a circular surface, where every point of it is
    // nearest: the position solver cannot start.
    let text = "bodies:\n  cam: {mass: 1, inertia: 0.1, position: [0, 0]}\n  \
                follower: {mass: 1, inertia: 0.1, position: [0, 0]}\n\
                joints:\n  pin: {type: revolute, body_i: ground, body_j: cam, at: [0, 0]}\n  \
                guide: {type: translational, body_i: ground, body_j: follower, at: [0, 0], axis: [0, 1]}\n  \
                contact: {type: cam, body_i: cam, body_j: follower, point_j: [0, 0], roller_radius: 0.01, \
                profile: {x: '0.04*cos(u)', y: '0.04*sin(u)'}}\n\
                drivers:\n  motor: {type: angle, body: cam, function: 't'}\n\
                analyses:\n  motion: {type: kinematic, drivers: [motor], t_end: 1, step: 0.1}\n";
    let error =
        Model::from_yaml(text).unwrap().run("motion", &Default::default()).map(|_| ()).unwrap_err().error.to_string();
    eprintln!("{error}");
    assert!(error.contains("joints.contact is NaN at t = 0 s"), "{error}");
    assert!(error.contains("no unique, regular nearest point on the working surface"), "{error}");
}
