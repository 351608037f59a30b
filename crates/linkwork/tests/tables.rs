//! Tables (`tables:` and `spline(name, x)`): `examples/cam_table.yaml`, a cam whose follower's
//! lift is a periodic spline through a CSV file's points, against the cycloidal law the points
//! were sampled from and against virtual work; a table given inline in a driver; bad tables.

mod common;

use common::problems;
use linkwork::Model;
use std::f64::consts::PI;

/// The lift the table was sampled from (examples/data/cam_lift.csv): a cycloidal rise of 20 mm
/// over 120 deg, a dwell to 180, a cycloidal return over 120 deg, a dwell to 360. `(y, y', y'')`
/// in the cam angle.
fn cycloidal_lift(theta: f64) -> (f64, f64, f64) {
    common::cycloidal_cam_lift(theta, 0.02, 2.0 * PI / 3.0, 2.0 * PI / 3.0)
}

#[test]
fn the_follower_moves_by_the_table_through_its_points_and_close_to_the_law_between() {
    // The cam turns on past 360 deg, where the periodic table repeats.
    let (r, [y, vy, ay]) = common::cam_motion("cam_table.yaml");
    let lift_mm = common::col(&r, "lift_mm");
    let omega = 2.0 * PI;
    let mut worst = [0.0f64; 3];
    for (k, &t) in r.time.iter().enumerate() {
        let (want, d1, d2) = cycloidal_lift(omega * t);
        let lift = y[k] - 0.05;
        assert!((lift_mm[k] - 1000.0 * lift).abs() < 1e-9, "the measure is the joint's table at t = {t}");
        if k % 5 == 0 {
            // On a tabulated point (every 5 deg) the spline is the table's number: within the
            // position solver's tolerance, 1e-10 on the constraint (the CSV holds 17 digits).
            assert!((lift - want).abs() < 1e-10, "t = {t}: lift {lift} vs {want}");
        }
        worst[0] = worst[0].max((lift - want).abs());
        worst[1] = worst[1].max((vy[k] - d1 * omega).abs());
        worst[2] = worst[2].max((ay[k] - d2 * omega * omega).abs());
    }
    // Between the points the spline's error is that of interpolation with h = 5 deg = 0.087 rad:
    // where the law is smooth, at most 5/384 h^4 max|y| = 2e-7 m (de Boor, ch. V; y peaks
    // at H (2 pi)^3 / beta^4 = 0.26 m/rad^4), one order of h less a derivative. The law's
    // third derivative jumps where rise meets dwell, which the spline rounds off over a piece.
    // Measured: 3.6e-8 m, 8.7e-6 m/s and 6.5e-3 m/s^2 (against peaks of 0.02 m, 0.12 m/s and
    // 1.1 m/s^2); the bounds are about twice that, so a table twice as coarse (errors 8 to 16
    // times larger) or a wrong derivative fails them.
    assert!(worst[0] < 1e-7, "lift error {:e}", worst[0]);
    assert!(worst[1] < 2e-5, "velocity error {:e}", worst[1]);
    assert!(worst[2] < 1.5e-2, "acceleration error {:e}", worst[2]);
}

#[test]
fn the_motor_torque_pays_the_followers_work() {
    let (_, r) = common::run("cam_table.yaml", "drive");
    let (vy, ay, torque) =
        (common::col(&r, "follower.vy"), common::col(&r, "follower.ay"), common::col(&r, "motor.effort"));
    // Virtual work: the cam turns steadily about its centre of mass, so the motor's power T omega
    // goes wholly into the follower, which the guide holds sideways: m (a_y + g) v_y.
    let (m, g, omega) = (0.3, 9.81, 2.0 * PI);
    let peak = torque.iter().fold(0.0f64, |p, t| p.max(t.abs()));
    for k in 0..r.len() {
        let want = m * (ay[k] + g) * vy[k] / omega;
        // The multipliers come from one well-conditioned linear solve: 1e-10 N m against a peak
        // of 0.06 N m is rounding with room.
        assert!((torque[k] - want).abs() < 1e-10, "t = {}: {} vs {want}", r.time[k], torque[k]);
    }
    assert!(peak > 0.01, "the follower's lift needs torque: peak {peak}");
}

#[test]
fn an_inline_table_drives_with_its_derivatives() {
    // A crank turned by a measured angle history: 0, a quarter turn, a half turn at 0, 1, 2 s.
    let model = Model::from_yaml(
        "bodies:\n  crank: {mass: 1, inertia: 0.1, position: [0, 0]}\n\
         joints:\n  pin: {type: revolute, body_i: ground, body_j: crank, at: [0, 0]}\n\
         tables:\n  history: {x: [0, 1, 2], y: [0, 1.5707963267948966, 3.141592653589793]}\n\
         drivers:\n  turn: {type: angle, body: crank, function: 'spline(history, t)'}\n\
         analyses:\n  run: {type: kinematic, drivers: [turn], t_end: 3, step: 0.25}\n",
    )
    .unwrap();
    let r = model.run("run", &Default::default()).unwrap_or_else(|f| panic!("{}", f.error));
    let (phi, omega, alpha) =
        (r.column("crank.phi").unwrap(), r.column("crank.omega").unwrap(), r.column("crank.alpha").unwrap());
    for (k, &t) in r.time.iter().enumerate() {
        // The points lie on a line (pi/2 a second): the parabola is that line, and past the last
        // point the table continues it (a straight line continues each end).
        let (want, rate) = (PI / 2.0 * t, PI / 2.0);
        assert!((phi[k] - want).abs() < 1e-12 && (omega[k] - rate).abs() < 1e-12 && alpha[k].abs() < 1e-12, "t {t}");
    }
}

#[test]
fn bad_tables_are_problems_at_their_fields() {
    let model = |tables: &str, function: &str| {
        format!(
            "bodies:\n  crank: {{mass: 1, inertia: 0.1, position: [0, 0]}}\n\
             joints:\n  pin: {{type: revolute, body_i: ground, body_j: crank, at: [0, 0]}}\n\
             tables:\n{tables}\
             drivers:\n  turn: {{type: angle, body: crank, function: '{function}'}}\n"
        )
    };
    let cases = [
        ("  a: {x: [0, 1, 1], y: [0, 1, 2]}\n", "t", "tables.a.x: x must increase strictly: x[2] = 1 follows x[1] = 1"),
        ("  a: {x: [0, 1], y: [0, 1, 2]}\n", "t", "tables.a: x has 2 values and y 3"),
        ("  a: {x: [0, 1, 2], y: [0, 1, 2], method: periodic}\n", "t", "tables.a.y: a periodic table ends where"),
        ("  a: {x: [0, 1], y: [0, 1], method: linear}\n", "t", "tables.a.method: unknown variant `linear`"),
        ("  a: {x: time, y: [0, 1]}\n", "t", "tables.a.x: expected a list of numbers (a column name needs `file:`)"),
        ("  a: {file: nowhere.csv, x: t, y: angle}\n", "t", "tables.a.file: cannot read 'nowhere.csv'"),
        ("  a: {x: [0, '1 deg'], y: [0, 1]}\n", "t", "tables.a.x: a list of plain numbers (SI, without units"),
        ("  my table: {x: [0, 1], y: [0, 1]}\n", "t", "tables.my table: 'my table' is not a valid name"),
        (
            "  a: {x: [0, 1], y: [0, 1]}\n",
            "spline(b, t)",
            "drivers.turn.function: cannot read the function 'spline(b, t)': unknown table 'b'",
        ),
    ];
    for (tables, function, want) in cases {
        let list = problems(&model(tables, function));
        assert!(list.iter().any(|p| p.starts_with(want)), "no '{want}' in {list:#?}");
    }
    // A bad table used by an expression is one problem, the table's, not also the expression's.
    for tables in ["  a: {x: [0, 1, 1], y: [0, 1, 2]}\n", "  a: {x: [0, 1], z: [0, 1]}\n"] {
        let list = problems(&model(tables, "spline(a, t)"));
        assert!(list.len() == 1 && list[0].starts_with("tables.a"), "{list:#?}");
    }
}

#[test]
fn a_files_columns_are_found_by_name_and_read_as_numbers() {
    let dir = std::env::temp_dir().join(format!("linkwork-tables-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: &str, text: &str| std::fs::write(dir.join(name), text).unwrap();
    write("good.csv", "# a comment line\ntime, angle\n0, 0\n1, 2\n2, 4\n");
    write("bad.csv", "time,angle\n0,0\n1,two\n");
    write("back.csv", "time,angle\n# a comment line\n0,0\n1,1\n0.5,2\n");
    let model = |file: &str, y: &str| {
        format!(
            "bodies:\n  crank: {{mass: 1, inertia: 0.1, position: [0, 0]}}\n\
             joints:\n  pin: {{type: revolute, body_i: ground, body_j: crank, at: [0, 0]}}\n\
             tables:\n  a: {{file: {file}, x: time, y: {y}}}\n\
             drivers:\n  turn: {{type: angle, body: crank, function: 'spline(a, t)'}}\n\
             analyses:\n  run: {{type: kinematic, drivers: [turn], t_end: 2, step: 0.5}}\n"
        )
    };
    // A model loaded from a file reads the table's file beside it.
    std::fs::write(dir.join("model.yaml"), model("good.csv", "angle")).unwrap();
    let r = Model::load(dir.join("model.yaml"))
        .unwrap()
        .run("run", &Default::default())
        .unwrap_or_else(|f| panic!("{}", f.error));
    assert_eq!(r.column("crank.phi").unwrap(), &[0.0, 1.0, 2.0, 3.0, 4.0]);
    let list = problems(&model(&dir.join("good.csv").display().to_string(), "angel"));
    assert!(
        list.iter()
            .any(|p| p.starts_with("tables.a.y:") && p.contains("has no column 'angel'; its columns are time, angle")),
        "{list:#?}"
    );
    let list = problems(&model(&dir.join("bad.csv").display().to_string(), "angle"));
    assert!(
        list.iter()
            .any(|p| p.starts_with("tables.a.y:")
                && p.contains("line 3, column 'angle': expected a number, found 'two'")),
        "{list:#?}"
    );
    // A point's problem names the file's line (comment lines counted).
    let list = problems(&model(&dir.join("back.csv").display().to_string(), "angle"));
    let backwards = |p: &String| p.starts_with("tables.a.x: x must increase strictly") && p.ends_with("line 5)");
    assert!(list.iter().any(backwards), "{list:#?}");
    // A folder (or a device) is not a table file.
    let list = problems(&model(&dir.display().to_string(), "angle"));
    assert!(list.iter().any(|p| p.starts_with("tables.a.file:") && p.contains("is not a file")), "{list:#?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
