//! Joint friction (docs/model-format.md, "Joint friction") against independent solutions: the
//! inverse analysis of a slider-crank against its free-body diagrams solved by hand, and the
//! dynamics of a block on an incline against its closed forms.

mod common;

use common::{col, example, example_text, patch};
use linkwork::{Error, Model, Results};

/// The example's friction: pins of radius 10 mm at `mu = 0.1`, a 50 mm block at `mu = 0.15`, the
/// default transition velocity; the pump's damping, N s/m.
const PIN: (f64, f64) = (0.1, 0.01);
const GUIDE: (f64, f64) = (0.15, 0.05);
const V_S: f64 = 1e-3;
const PUMP: f64 = 200.0;

/// `a x b`.
fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// A body's pose, velocities and accelerations at output `k`, from the results.
struct Body {
    r: [f64; 2],
    phi: f64,
    v: [f64; 2],
    omega: f64,
    a: [f64; 2],
    alpha: f64,
}

impl Body {
    fn at(r: &Results, name: &str, k: usize) -> Body {
        let c = |q: &str| col(r, &format!("{name}.{q}"))[k];
        Body {
            r: [c("x"), c("y")],
            phi: c("phi"),
            v: [c("vx"), c("vy")],
            omega: c("omega"),
            a: [c("ax"), c("ay")],
            alpha: c("alpha"),
        }
    }
    /// The crank, the rod and the slider at output `k`, from the results.
    fn all_at(r: &Results, k: usize) -> [Body; 3] {
        ["crank", "rod", "slider"].map(|name| Body::at(r, name, k))
    }
    /// The global position of body point `s`.
    fn point(&self, s: [f64; 2]) -> [f64; 2] {
        let (sn, cs) = self.phi.sin_cos();
        [self.r[0] + cs * s[0] - sn * s[1], self.r[1] + sn * s[0] + cs * s[1]]
    }
}

/// What the free-body diagrams give at one output time: the motor torque, the friction of `O`,
/// `A`, `B` (on their first bodies, N m) and of the guide (on ground, N), and the iterations.
struct Hand {
    torque: f64,
    friction: [f64; 4],
    iterations: usize,
}

/// The slider-crank's Newton-Euler equations, body by body, with the friction of each joint, in the
/// order that makes each step explicit (slider along the guide, the rod's moment about `A`, the
/// slider across the guide, the rod's and the crank's forces, the crank's moment), iterated on the
/// friction (which depends on the forces found) until it changes by less than `1e-13` N. An
/// independent formulation: no multipliers, no constraint Jacobian, none of the engine's reaction
/// or friction code. Masses and geometry as examples/slider_crank_friction.yaml; `mu` scales
/// every coefficient (0: no friction), `guide` the guide's once more.
fn free_bodies([crank, rod, slider]: &[Body; 3], mu: f64, guide: f64) -> Hand {
    let (m1, i1, m2, i2, m3, i3) = (1.0, 0.001, 2.0, 0.015, 1.0, 0.001);
    let g = [0.0, -9.81];
    let (r_o, r_a, r_b) = (crank.point([-0.05, 0.0]), crank.point([0.05, 0.0]), rod.point([0.15, 0.0]));
    let (mu_pin, radius) = (mu * PIN.0, PIN.1);
    let (mu_guide, length) = (mu * guide * GUIDE.0, GUIDE.1);
    let pin = |rate: f64, force: [f64; 2]| -mu_pin * (radius * rate / V_S).tanh() * radius * force[0].hypot(force[1]);
    let (mut t_o, mut t_a, mut t_b, mut f_guide) = (0.0, 0.0, 0.0, 0.0);
    // 5000: the iteration contracts by the friction's gain, up to 0.9 in the steep guide's test.
    for iterations in 1..=5000 {
        // The slider: pin B's force on it (fb), the guide's normal force (n) and couple (m_s) about
        // its centre, the guide's friction on it (-f_guide), the pump, gravity.
        let pump = -PUMP * slider.v[0];
        let fb_x = m3 * slider.a[0] + f_guide - pump;
        let m_s = i3 * slider.alpha + t_b;
        // The rod about A: pin B's force on it is -fb, pin A's goes through A.
        let d = [r_b[0] - r_a[0], r_b[1] - r_a[1]];
        let lever = [rod.r[0] - r_a[0], rod.r[1] - r_a[1]];
        let inertia = [m2 * rod.a[0] - m2 * g[0], m2 * rod.a[1] - m2 * g[1]];
        // I2 alpha2 = d x (-fb) + lever x (m2 g) + t_b - t_a, taken about A with the inertia force.
        let rhs = i2 * rod.alpha + cross(lever, inertia) - t_b + t_a;
        let fr_x = -fb_x;
        let fr_y = (rhs + d[1] * fr_x) / d[0];
        let f_rod_b = [fr_x, fr_y];
        let n = m3 * slider.a[1] + fr_y - m3 * g[1];
        let f_rod_a = [inertia[0] - f_rod_b[0], inertia[1] - f_rod_b[1]];
        let f_o = [m1 * crank.a[0] - m1 * g[0] + f_rod_a[0], m1 * crank.a[1] - m1 * g[1] + f_rod_a[1]];
        let arm_a = [r_a[0] - crank.r[0], r_a[1] - crank.r[1]];
        let arm_o = [r_o[0] - crank.r[0], r_o[1] - crank.r[1]];
        let torque = i1 * crank.alpha + cross(arm_a, f_rod_a) - cross(arm_o, f_o) - t_a - t_o;
        let next_o = pin(crank.omega, f_o);
        let next_a = pin(crank.omega - rod.omega, f_rod_a);
        let next_b = pin(rod.omega - slider.omega, f_rod_b);
        let load = n.abs() + m_s.abs() / length;
        let next_guide = mu_guide * (slider.v[0] / V_S).tanh() * load;
        let change =
            [next_o - t_o, next_a - t_a, next_b - t_b, next_guide - f_guide].iter().fold(0.0f64, |a, x| a.max(x.abs()));
        (t_o, t_a, t_b, f_guide) = (next_o, next_a, next_b, next_guide);
        // The torque went with the friction before this update, which moved by under 1e-13.
        if change < 1e-13 {
            return Hand { torque, friction: [t_o, t_a, t_b, f_guide], iterations };
        }
    }
    panic!("the free-body iteration did not converge");
}

/// The example's slider-crank at time `t` in closed form, without the engine: the crank (length
/// `r = 0.1`, pinned at the origin) at `theta = 2 pi t`, `omega_1 = 2 pi`, `alpha_1 = 0`; the rod
/// (`L = 0.3`) from the crank pin `A = r (cos theta, sin theta)` to the slider's pin `B` on the
/// guide `y = 0`, so `L sin phi_2 = -r sin theta`, the branch `cos phi_2 > 0` that the file's
/// guess starts on. Differentiating once and twice:
/// `omega_2 = -r cos theta omega_1 / (L cos phi_2)`,
/// `alpha_2 = (r sin theta omega_1^2 + L sin phi_2 omega_2^2) / (L cos phi_2)`; the slider at
/// `x_B = r cos theta + L cos phi_2` with `v_B = -r sin theta omega_1 - L sin phi_2 omega_2` and
/// `a_B = -r cos theta omega_1^2 - L (cos phi_2 omega_2^2 + sin phi_2 alpha_2)`. Each centre of
/// mass is its link's middle: the crank's at `A / 2`, the rod's at `(A + B) / 2`, their
/// velocities and accelerations the same means.
fn closed_form(t: f64) -> [Body; 3] {
    let (r, l, w1) = (0.1, 0.3, 2.0 * std::f64::consts::PI);
    let (s1, c1) = (w1 * t).sin_cos();
    let phi2 = (-r * s1 / l).asin();
    let (s2, c2) = phi2.sin_cos();
    let w2 = -r * c1 * w1 / (l * c2);
    let alpha2 = (r * s1 * w1 * w1 + l * s2 * w2 * w2) / (l * c2);
    let (a_pos, a_vel, a_acc) = ([r * c1, r * s1], [-r * s1 * w1, r * c1 * w1], [-r * c1 * w1 * w1, -r * s1 * w1 * w1]);
    let b_pos = [r * c1 + l * c2, 0.0];
    let b_vel = [-r * s1 * w1 - l * s2 * w2, 0.0];
    let b_acc = [-r * c1 * w1 * w1 - l * (c2 * w2 * w2 + s2 * alpha2), 0.0];
    let mid = |p: [f64; 2], q: [f64; 2]| [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
    [
        Body {
            r: mid([0.0; 2], a_pos),
            phi: w1 * t,
            v: mid([0.0; 2], a_vel),
            omega: w1,
            a: mid([0.0; 2], a_acc),
            alpha: 0.0,
        },
        Body { r: mid(a_pos, b_pos), phi: phi2, v: mid(a_vel, b_vel), omega: w2, a: mid(a_acc, b_acc), alpha: alpha2 },
        Body { r: b_pos, phi: 0.0, v: b_vel, omega: 0.0, a: b_acc, alpha: 0.0 },
    ]
}

/// The example's efficiency over one turn against the same mechanism computed without the
/// engine: the kinematics in closed form ([`closed_form`]), the motor torque from the free-body
/// diagrams with Coulomb friction ([`free_bodies`]), and
/// `eta = integral(200 v_B^2) / integral(torque omega_1)` over `0 <= t <= 1` by the trapezoidal
/// rule at `0.02` ms (50,000 intervals). The guide's friction reverses within `0.25` ms of each dead
/// centre (`tanh(v_B / v_s)`), a near-step that the engine's 1 ms samples leave to its spline:
/// the summary differs from the finely integrated ratio by about `2e-7` (docs above), and the
/// rule here at `0.02` ms resolves the step to well below that. Tolerance `1e-6`. The friction
/// dissipates several per cent of the motor's work, so a friction term of the wrong sign, lever
/// or size moves `eta` by `1e-3` or more.
#[test]
fn efficiency_matches_the_closed_form_slider_crank() {
    let (_, r) = common::run("slider_crank_friction.yaml", "inverse");
    let eta = summary(&r, "efficiency");
    let intervals = 50_000;
    let times: Vec<f64> = (0..=intervals).map(|k| k as f64 / intervals as f64).collect();
    let (mut pump, mut motor) = (Vec::new(), Vec::new());
    for &t in &times {
        let bodies = closed_form(t);
        pump.push(PUMP * bodies[2].v[0] * bodies[2].v[0]);
        motor.push(free_bodies(&bodies, 1.0, 1.0).torque * bodies[0].omega);
    }
    let eta_closed = integral(&times, |k| pump[k], times.len()) / integral(&times, |k| motor[k], times.len());
    println!("efficiency over one turn: engine {eta:.9}, closed form {eta_closed:.9}");
    assert!((eta - eta_closed).abs() < 1e-6, "{eta} vs {eta_closed}");
}

/// `integral(y dt)` over the first `count` outputs by the trapezoidal rule.
fn integral(t: &[f64], y: impl Fn(usize) -> f64, count: usize) -> f64 {
    (1..count).map(|k| 0.5 * (t[k] - t[k - 1]) * (y(k) + y(k - 1))).sum()
}

/// The inverse analysis's motor torque and joint friction against the free-body diagrams at every
/// output time. Both solve the same equations to `~1e-13` of the loads (the engine's iteration
/// stops at `1e-10` of the largest multiplier, ~130 N here, so `1.3e-8` N at worst); the inputs
/// (positions, velocities, accelerations) are the same result columns. Tolerance `1e-7` N or N m:
/// a lever arm of 0.1 m or more turns `1.3e-8` N into less, with a margin of 5 for the sums; a
/// wrong sign, lever or reference point of a friction term errs by its whole size, `1e-3` N m or
/// more. Measured: the largest difference is printed.
#[test]
fn slider_crank_inverse_matches_free_body_diagrams() {
    let model = Model::load(example("slider_crank_friction.yaml")).unwrap();
    let r = model.run("inverse", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    let names = ["O.friction", "A.friction", "B.friction", "guide.friction"];
    let (mut worst, mut most_iterations) = (0.0f64, 0);
    for k in 0..r.len() {
        let hand = free_bodies(&Body::all_at(&r, k), 1.0, 1.0);
        most_iterations = most_iterations.max(hand.iterations);
        let mut diff = (col(&r, "motor.effort")[k] - hand.torque).abs();
        for (name, f) in names.iter().zip(hand.friction) {
            diff = diff.max((col(&r, name)[k] - f).abs());
        }
        worst = worst.max(diff);
    }
    println!("largest difference from the free-body diagrams: {worst:.3e} (at most {most_iterations} hand iterations)");
    assert!(worst < 1e-7, "{worst:e}");
    // The friction is not negligible: the pins' torques reach 0.01 N m and more, and the guide's
    // force several newtons, so the comparison above tests them.
    let peak = |name: &str| col(&r, name).iter().fold(0.0f64, |a, x| a.max(x.abs()));
    assert!(
        peak("O.friction") > 1e-2 && peak("guide.friction") > 1.0,
        "{} {}",
        peak("O.friction"),
        peak("guide.friction")
    );
}

/// At every output time, the power of the motor, the pump and the friction is the rate of the
/// kinetic and potential energies: `P_motor + P_pump + P_friction = d(T + V)/dt`, with
/// `P_friction` from the friction columns and the joints' relative velocities and
/// `d(T + V)/dt = sum m v . a + I omega alpha - m g . v` from the body columns. A check of each
/// friction's sign and of what it acts on. Tolerance `1e-8` of the motor's peak power (~100 W):
/// the multipliers stop at `1e-10` of the largest (~130 N), and each of the six terms carries that
/// times a velocity of up to 0.6 m/s or 7 rad/s (measured: `1.8e-9` of the peak).
#[test]
fn slider_crank_friction_dissipates_what_the_motor_loses() {
    let (_, r) = common::run("slider_crank_friction.yaml", "inverse");
    let peak = col(&r, "driver_power").iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let bodies = [("crank", 1.0, 0.001), ("rod", 2.0, 0.015), ("slider", 1.0, 0.001)];
    let mut worst = 0.0f64;
    for k in 0..r.len() {
        let b: Vec<Body> = bodies.iter().map(|(n, _, _)| Body::at(&r, n, k)).collect();
        let rate: f64 = bodies
            .iter()
            .zip(&b)
            .map(|((_, m, i), b)| m * (b.v[0] * b.a[0] + b.v[1] * b.a[1]) + i * b.omega * b.alpha + m * 9.81 * b.v[1])
            .sum();
        let f = |name: &str| col(&r, &format!("{name}.friction"))[k];
        // Each pair's power: the friction on body i times the velocity of i relative to j.
        let friction = f("O") * b[0].omega
            + f("A") * (b[0].omega - b[1].omega)
            + f("B") * (b[1].omega - b[2].omega)
            + f("guide") * (0.0 - b[2].v[0]);
        let balance = col(&r, "driver_power")[k] + col(&r, "applied_power")[k] + friction - rate;
        worst = worst.max(balance.abs());
        assert!(friction <= 0.0, "friction gives power {friction} at output {k}");
    }
    assert!(worst < 1e-8 * peak, "{worst:e} of {peak}");
}

/// The summary `name` of a run; panics naming it when there is none.
fn summary(r: &Results, name: &str) -> f64 {
    let summaries = r.summary.summaries.as_ref().expect("the run wrote its summaries");
    *summaries.get(name).unwrap_or_else(|| panic!("no summary {name}"))
}

/// The example's summaries over one turn against its columns.
///
/// `efficiency` (`integral(pump_power) / integral(motor_power)`, each integral through the cubic
/// spline of the samples, docs/model-format.md "Summaries") against the same ratio by the
/// trapezoidal rule over the columns here, and over the free-body diagrams' torque (which agree
/// with the engine's to 1e-7 N m of ~10 N m). On uniform steps the spline's integral is the
/// trapezoidal rule plus `h^2 (m_0 - m_n) / 12` (its end slopes), which cancels for a smooth
/// periodic integrand; but the guide's friction reverses within 0.25 ms of each dead centre
/// (`v_s` over the slider's acceleration there, 4 m/s^2), under the 1 ms step, and the two rules
/// weigh that near-step of the motor's power differently: by 7.6e-8 of eta (measured; printed).
/// Tolerance 1e-6. Finer steps (0.05 ms) take both to 0.9450034, 2e-7 from either
/// ([`efficiency_matches_the_closed_form_slider_crank`] computes it without the engine).
///
/// The work balance over the turn: the kinetic and potential energies return to their start
/// (the motion is periodic), so the motor's work is the pump's and the friction's,
/// `motor_work = pump_work + friction_work + Delta(T + V)`. The summaries integrate the three
/// powers with the same weights, so this is the power balance at each output (within 1e-8 of
/// the peak power, 100 W, test above) integrated over the second: tolerance 1e-6 J (measured
/// 3.5e-9 J). `friction_work` (the summary, from the `<joint>.friction` columns and the relative
/// velocities) against the same integral by the trapezoidal rule here: the near-step again, which
/// neither rule resolves at 1 ms (the summary 2.365158 J, the trapezoidal rule 2.365155 J; both
/// 2.3651683 J at 0.05 ms): tolerance 1e-5 J.
///
/// Without friction (every `mu` 0, the same run otherwise) `efficiency` is 1 to `1e-8`: the
/// integrands are smooth and periodic, so the quadrature is exact to far below that, and what is
/// left is the multipliers' round-off (measured below `5e-10`); so friction's loss is what
/// lowers it.
#[test]
fn slider_crank_efficiency() {
    let (_, r) = common::run("slider_crank_friction.yaml", "inverse");
    let t = &r.time;
    let count = r.len();
    let (motor, pump) = (col(&r, "motor_power"), col(&r, "pump_power"));
    let eta = summary(&r, "efficiency");
    let eta_columns = integral(t, |k| pump[k], count) / integral(t, |k| motor[k], count);
    let omega = col(&r, "crank.omega");
    let hand: Vec<f64> = (0..count).map(|k| free_bodies(&Body::all_at(&r, k), 1.0, 1.0).torque * omega[k]).collect();
    let eta_hand = integral(t, |k| pump[k], count) / integral(t, |k| hand[k], count);
    println!(
        "efficiency over one turn: {eta:.9} (trapezoidal rule: {eta_columns:.9}, free-body diagrams: {eta_hand:.9})"
    );
    assert!((eta - eta_columns).abs() < 1e-6 && (eta - eta_hand).abs() < 1e-6, "{eta} vs {eta_columns}, {eta_hand}");

    let work = |name: &str| summary(&r, name);
    let (e, v) = (col(&r, "kinetic_energy"), col(&r, "potential_energy"));
    let energy_change = e[count - 1] + v[count - 1] - e[0] - v[0];
    let balance = work("motor_work") - work("pump_work") - work("friction_work") - energy_change;
    let f = |name: &str, k: usize| col(&r, &format!("{name}.friction"))[k];
    let b = |name: &str, k: usize| col(&r, name)[k];
    let dissipated = -integral(
        t,
        |k| {
            f("O", k) * b("crank.omega", k)
                + f("A", k) * (b("crank.omega", k) - b("rod.omega", k))
                + f("B", k) * (b("rod.omega", k) - b("slider.omega", k))
                - f("guide", k) * b("slider.vx", k)
        },
        count,
    );
    println!(
        "work over the turn: motor {:.6} J = pump {:.6} + friction {:.6} + energy change {energy_change:.2e}; \
         left over {balance:.2e} J; friction from the columns {dissipated:.6} J",
        work("motor_work"),
        work("pump_work"),
        work("friction_work")
    );
    assert!(balance.abs() < 1e-6, "{balance:e}");
    assert!((work("friction_work") - dissipated).abs() < 1e-5, "{} vs {dissipated}", work("friction_work"));
    assert!(work("friction_work") > 0.01 * work("motor_work"), "the friction takes a share worth testing");
    let peak = col(&r, "motor.effort").iter().fold(0.0f64, |a, x| a.max(x.abs()));
    assert_eq!(work("peak_torque"), peak);

    let text = example_text("slider_crank_friction.yaml");
    // Every pin's coefficient is `mu_pin`, the guide's `mu_guide`.
    assert_eq!(text.matches("{mu: mu_pin, ").count() + text.matches("{mu: mu_guide, ").count(), 4);
    let text = patch(&patch(&text, "mu_pin: 0.1 ", "mu_pin: 0 "), "mu_guide: 0.15", "mu_guide: 0");
    let free =
        Model::from_yaml(&text).unwrap().run("inverse", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    let eta_free = summary(&free, "efficiency");
    println!("without friction: {eta_free:.12}");
    assert!((eta_free - 1.0).abs() < 1e-8, "{eta_free}");
    assert!(eta < eta_free - 0.01, "{eta} vs {eta_free}");
    // The free-body diagrams without friction agree with the run without friction too.
    let worst = (0..count)
        .map(|k| (col(&free, "motor.effort")[k] - free_bodies(&Body::all_at(&free, k), 0.0, 1.0).torque).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-7, "{worst:e}");
}

/// A guide with `mu = 2.5` instead of 0.15: its friction's gain on the reactions, `mu tan(beta)`
/// with the rod at up to `beta = asin(r / L) = 19.5` degrees, reaches 0.88, and the pins' add to
/// it (a fixed point on the reactions would contract by that much per iteration; the engine's
/// Newton does not care). The motor torque and every joint's friction agree with the free-body
/// diagrams (whose own fixed point is given the iterations it needs) to `1e-7` N or N m, for the
/// reasons given at `slider_crank_inverse_matches_free_body_diagrams`; the guide's friction
/// reaches several times the rod's load along it.
#[test]
fn steep_guide_friction_converges_and_matches_free_body_diagrams() {
    let text = patch(&example_text("slider_crank_friction.yaml"), "mu_guide: 0.15", "mu_guide: 2.5");
    let r =
        Model::from_yaml(&text).unwrap().run("inverse", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    let names = ["O.friction", "A.friction", "B.friction", "guide.friction"];
    let (mut worst, mut most_iterations) = (0.0f64, 0);
    for k in 0..r.len() {
        let hand = free_bodies(&Body::all_at(&r, k), 1.0, 2.5 / GUIDE.0);
        most_iterations = most_iterations.max(hand.iterations);
        let mut diff = (col(&r, "motor.effort")[k] - hand.torque).abs();
        for (name, f) in names.iter().zip(hand.friction) {
            diff = diff.max((col(&r, name)[k] - f).abs());
        }
        worst = worst.max(diff);
    }
    let beta = col(&r, "rod.phi").iter().fold(0.0f64, |a, x| a.max(x.abs()));
    println!(
        "largest difference {worst:.3e}; guide gain up to {:.3}; the free-body iteration took up to {most_iterations}",
        2.5 * beta.tan()
    );
    assert!(worst < 1e-7, "{worst:e}");
    assert!(2.5 * beta.tan() > 0.85 && most_iterations > 100, "{beta} {most_iterations}");
}

/// A guide with a coefficient that locks the slider (`mu tan(beta) >= 1` with the rod at an angle
/// `beta` up to `asin(r / L) = 19.5` degrees: `mu = 4` locks from `tan(beta) = 0.25` on, and
/// earlier with the pins' and the block's shares). The run stops with a friction error that names
/// the guide and the time, and keeps the results before it; by then the guide's own gain
/// `mu tan(beta)` is above 0.8 and the motor's effort has grown tenfold in eleven outputs, as an
/// effort does on its way to a lock.
#[test]
fn self_locking_friction_is_named() {
    let text = patch(&example_text("slider_crank_friction.yaml"), "mu_guide: 0.15", "mu_guide: 4");
    let failure = Model::from_yaml(&text).unwrap().run("inverse", &Default::default()).unwrap_err();
    let message = failure.error.to_string();
    assert!(matches!(failure.error, Error::Friction { .. }), "{message}");
    assert!(message.contains("in guide.friction") && message.contains("self-locking"), "{message}");
    let Error::Friction { time, .. } = failure.error else { unreachable!() };
    let rows = failure.results.len();
    assert!(rows > 10 && (failure.results.time[rows - 1] - (time - 0.001)).abs() < 1e-12, "{rows} rows, t = {time}");
    let beta = col(&failure.results, "rod.phi")[rows - 1];
    // Newton stops only where there is no solution: the motor's effort has grown without bound
    // on the way (measured: 26 N m eleven outputs before, 441 N m at the last, 4 tan(beta) =
    // 0.884 at t = 0.113 s; the fixed point it replaced gave up at 0.72, t = 0.09 s).
    let effort = col(&failure.results, "motor.effort");
    println!(
        "stopped at t = {time}, 4 tan(beta) = {}, effort {} then {}",
        4.0 * beta.tan().abs(),
        effort[rows - 12],
        effort[rows - 1]
    );
    assert!(4.0 * beta.tan().abs() > 0.8, "beta {beta} at t = {time}");
    assert!(effort[rows - 1].abs() > 10.0 * effort[rows - 12].abs(), "{} {}", effort[rows - 12], effort[rows - 1]);
}

/// A block of 2 kg on a ground incline at `degrees` below the horizontal (sliding down +s), with
/// friction `mu` in its translational joint (block length 0.1 m, transition velocity `V_S`),
/// released at `v0` m/s down the slope; a dynamic analysis over 1 s with the integrator `kind`
/// (`formulation` for bdf) at `rtol = atol = 1e-9`.
fn incline(degrees: f64, mu: f64, v0: f64, kind: &str, formulation: &str) -> Results {
    let a = degrees.to_radians();
    let (c, s) = (a.cos(), a.sin());
    let text = format!(
        "name: incline
gravity: [0, -9.81]
bodies:
  block: {{mass: 2.0, inertia: 0.01, position: [0, 0], velocity: [{vx}, {vy}]}}
joints:
  slope:
    type: translational
    body_i: ground
    body_j: block
    at: [0, 0]
    axis: [{c}, {ms}]
    friction: {{mu: {mu}, length: 0.1, transition_velocity: {V_S}}}
analyses:
  slide: {{type: dynamic, integrator: {kind}, t_end: 1.0, step: 0.01, solver: {{rtol: 1e-9, atol: 1e-9{form}}}}}
",
        vx = v0 * c,
        vy = -v0 * s,
        ms = -s,
        form = if kind == "bdf" { format!(", formulation: {formulation}") } else { String::new() },
    );
    Model::from_yaml(&text)
        .unwrap()
        .run("slide", &Default::default())
        .unwrap_or_else(|f| panic!("{kind} {formulation}: {}", f.error))
}

/// The integrators, with bdf's two formulations.
const INTEGRATORS: [(&str, &str); 4] = [("bdf", "si2"), ("bdf", "index3"), ("hht", ""), ("abam", "")];

/// `(s, v, a)` along the slope at `degrees` at output `k`: distance from the start, velocity and
/// acceleration down the slope.
fn along(r: &Results, degrees: f64, k: usize) -> [f64; 3] {
    let (c, s) = (degrees.to_radians().cos(), degrees.to_radians().sin());
    let proj = |x: &str, y: &str| col(r, x)[k] * c - col(r, y)[k] * s;
    [proj("block.x", "block.y"), proj("block.vx", "block.vy"), proj("block.ax", "block.ay")]
}

/// Sliding at 30 degrees with `mu = 0.3` (`tan 30 = 0.58 > 0.3`) from 0.5 m/s, 500 times `V_S`
/// (where `tanh` is 1 to round-off): the acceleration is `g (sin a - mu cos a)`, the distance
/// `v0 t + a t^2 / 2`, and the friction on the guide `mu m g cos a` down the slope. The
/// acceleration and friction are computed at each output from the state, and hold to `1e-10`
/// relative (round-off of a few operations on numbers of order 10; measured 4e-16); the distance is
/// the integrator's, held to `1e-7` m over its 1.7 m at `rtol = atol = 1e-9` (index 3 lets its
/// global error reach `1e2` to `1e3` times the tolerance, docs/integrators.md; measured 3.3e-9 m
/// with bdf, 2e-15 with hht and abam, exact on a quadratic). Every integrator.
#[test]
fn block_slides_down_an_incline_at_the_closed_form_acceleration() {
    let (degrees, mu, v0, g, m) = (30.0f64, 0.3, 0.5, 9.81, 2.0);
    let a = degrees.to_radians();
    let acc = g * (a.sin() - mu * a.cos());
    for (kind, formulation) in INTEGRATORS {
        let r = incline(degrees, mu, v0, kind, formulation);
        let mut worst = [0.0f64; 3];
        for k in 0..r.len() {
            let t = r.time[k];
            let [s, _, ak] = along(&r, degrees, k);
            let friction = col(&r, "slope.friction")[k];
            worst[0] = worst[0].max((s - (v0 * t + 0.5 * acc * t * t)).abs());
            worst[1] = worst[1].max((ak - acc).abs() / acc);
            worst[2] = worst[2].max((friction - mu * m * g * a.cos()).abs() / (mu * m * g));
        }
        println!(
            "{kind} {formulation}: distance {:.2e} m, acceleration {:.2e}, friction {:.2e}",
            worst[0], worst[1], worst[2]
        );
        assert!(
            r.len() == 101 && worst[0] < 1e-7 && worst[1] < 1e-10 && worst[2] < 1e-10,
            "{kind} {formulation}: {worst:?}"
        );
    }
}

/// Below the sticking angle (10 degrees, `tan 10 = 0.18 < mu = 0.3`), released at rest, the block
/// stays nearly at rest: the smooth coefficient lets it creep at the velocity where
/// `mu tanh(v / V_S) = tan a`, `v_c = V_S atanh(tan a / mu) = 0.67 V_S`, reached within a time
/// constant `V_S / (mu g cos a sech^2) = 0.5` ms. From 0.05 s on (100 time constants) the velocity
/// is `v_c` to `1e-4` of itself (the integrators' absolute tolerance `1e-9` on velocities of
/// `7e-4` is `1.5e-6` of them, and abam's error test, which sees the positions and the independent
/// velocities, lets it reach `1.5e-5`; bdf si2 2.7e-12, index 3 7e-10, hht 1.2e-6), and over the
/// whole second the block moves less than `V_S` times the time, its creep bound. Every integrator.
#[test]
fn block_below_the_sticking_angle_creeps_at_most_at_the_transition_velocity() {
    let (degrees, mu) = (10.0f64, 0.3);
    let creep = V_S * (degrees.to_radians().tan() / mu).atanh();
    for (kind, formulation) in INTEGRATORS {
        let r = incline(degrees, mu, 0.0, kind, formulation);
        let mut worst = 0.0f64;
        for k in 0..r.len() {
            let [s, v, _] = along(&r, degrees, k);
            let t = r.time[k];
            assert!(s.abs() <= V_S * t + 1e-12, "{kind} {formulation}: moved {s} m by t = {t}");
            if t >= 0.05 {
                worst = worst.max((v - creep).abs() / creep);
            }
        }
        println!("{kind} {formulation}: creep velocity off by {worst:.2e} of {creep:.3e} m/s");
        assert!(worst < 1e-4, "{kind} {formulation}: {worst}");
    }
}
