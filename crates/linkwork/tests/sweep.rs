//! Sweeps (linkwork::sweep): the parametrised slider-crank's stroke against `2 r`, each
//! aggregation against a closed form, failed variants as rows, and the same table on one thread
//! or two.

mod common;

use common::example;
use linkwork::progress::{Progress, StopToken};
use linkwork::sweep::{sweep, Output};
use linkwork::{Error, Model};
use std::f64::consts::PI;

fn model() -> Model {
    Model::load(example("slider_crank_param.yaml")).unwrap()
}

fn radii(values: &[f64]) -> Vec<Vec<(String, String)>> {
    values.iter().map(|r| vec![("r".to_string(), format!("{r:?}"))]).collect()
}

fn outputs(list: &[(&str, &str)]) -> Vec<Output> {
    list.iter().map(|(n, s)| Output::parse(n, s).unwrap_or_else(|e| panic!("{n}: {e}"))).collect()
}

/// The Done-when case of the sweep: `--grid r=0.05:0.15:5`, stroke `2 r` to 1e-9 m (the
/// kinematic solver's tolerance on `Phi` is 1e-10, and the dead centres are output times).
#[test]
fn the_stroke_of_each_radius_is_twice_it() {
    let r = [0.05, 0.075, 0.1, 0.125, 0.15];
    let rows = sweep(
        &model(),
        "kinematics",
        &radii(&r),
        &outputs(&[("stroke", "max(slider.x) - min(slider.x)")]),
        None,
        &Progress::new(),
        &StopToken::new(),
    )
    .unwrap();
    for (r, row) in r.iter().zip(&rows) {
        let stroke = row.as_ref().unwrap()[0];
        assert!((stroke - 2.0 * r).abs() < 1e-9, "r = {r}: {stroke}");
    }
}

/// Each aggregation on the crank angle `phi = 2 pi t` over one second (201 rows), the crank speed
/// and the slider's start, against closed forms. Every one is exact up to round-off (1e-12
/// relative): max, min, peak, at and the first and last rows of a linear function, and the
/// integrals of `phi` and of `phi^2` (for `rms`), polynomials of degree below 4 that the cubic
/// spline of the quadrature reproduces (the trapezoidal rule erred by 1.25e-5 in `rms`).
#[test]
fn aggregations_match_their_closed_forms() {
    let list = [
        ("max", "max(crank.phi)"),
        ("min", "min(crank.phi)"),
        ("mean", "mean(crank.phi)"),
        ("rms", "rms(crank.phi)"),
        ("integral", "integral(crank.phi^2)"),
        ("peak", "peak(crank.phi - 4)"),
        ("initial", "initial(slider.x)"),
        ("final", "final(crank.phi) / (2*pi)"),
        ("at", "at(0.25, crank.phi)"),
        ("nested", "max(max(crank.phi, 1) * 2) + 1"),
        ("omega", "mean(crank.omega)"),
    ];
    let rows =
        sweep(&model(), "kinematics", &radii(&[0.1]), &outputs(&list), Some(1), &Progress::new(), &StopToken::new())
            .unwrap();
    let got = rows[0].as_ref().unwrap();
    let expected = [
        2.0 * PI,
        0.0,
        PI,
        2.0 * PI / 3f64.sqrt(),
        4.0 * PI * PI / 3.0,
        4.0,
        0.4,
        1.0,
        PI / 2.0,
        4.0 * PI + 1.0,
        2.0 * PI,
    ];
    for ((name, _), (g, e)) in list.iter().zip(got.iter().zip(expected)) {
        assert!((g - e).abs() <= 1e-12 * e.abs().max(1.0), "{name}: {g} against {e}");
    }
}

/// A variant that cannot be run is a row with its error; the others run. Here the crank longer
/// than the rod (r = 0.35 m, L = 0.3 m) cannot turn.
#[test]
fn a_failed_variant_is_a_row() {
    let rows = sweep(
        &model(),
        "kinematics",
        &radii(&[0.1, 0.35, 0.15]),
        &outputs(&[("s", "final(slider.x)")]),
        None,
        &Progress::new(),
        &StopToken::new(),
    )
    .unwrap();
    assert!(rows[0].is_ok() && rows[2].is_ok(), "{rows:?}");
    let error = rows[1].as_ref().unwrap_err();
    assert!(!matches!(error, Error::Model(_)), "{error}");
    let bad = vec![vec![("r".to_string(), "2 kg".to_string())]];
    let rows = sweep(
        &model(),
        "kinematics",
        &bad,
        &outputs(&[("s", "final(slider.x)")]),
        None,
        &Progress::new(),
        &StopToken::new(),
    )
    .unwrap();
    assert!(rows[0].as_ref().unwrap_err().to_string().contains("parameters.r"), "{rows:?}");
}

/// Bad outputs: a column outside an aggregation, a wrong count of arguments (at parse); an
/// unknown column (on the run, as the row's error at `outputs.<name>`).
#[test]
fn bad_outputs_name_what_is_wrong() {
    let e = Output::parse("s", "slider.x + max(slider.x)").unwrap_err();
    assert!(e.contains("'slider.x' outside an aggregation"), "{e}");
    let e = Output::parse("s", "peak(slider.x, 2)").unwrap_err();
    assert!(e.contains("peak() takes one expression, found 2 arguments"), "{e}");
    let e = Output::parse("s", "at(t1, slider.x)").unwrap_err();
    assert!(e.contains("needs a number for time"), "{e}");
    let rows = sweep(
        &model(),
        "kinematics",
        &radii(&[0.1]),
        &outputs(&[("s", "max(slider.xx)")]),
        None,
        &Progress::new(),
        &StopToken::new(),
    )
    .unwrap();
    let message = rows[0].as_ref().unwrap_err().to_string();
    assert!(message.contains("outputs.s") && message.contains("no result column 'slider.xx'"), "{message}");
    let rows = sweep(
        &model(),
        "kinematics",
        &radii(&[0.1]),
        &outputs(&[("s", "at(2, slider.x)")]),
        None,
        &Progress::new(),
        &StopToken::new(),
    )
    .unwrap();
    assert!(rows[0].as_ref().unwrap_err().to_string().contains("from t = 0 to 1 s"), "{rows:?}");
    assert!(sweep(&model(), "nonesuch", &radii(&[0.1]), &[], None, &Progress::new(), &StopToken::new()).is_err());
}

/// One thread or two: the same rows, bit for bit, in the order of the variants.
#[test]
fn threads_do_not_change_the_table() {
    let r: Vec<f64> = (0..12).map(|k| 0.05 + 0.01 * k as f64).collect();
    let out = outputs(&[("stroke", "max(slider.x) - min(slider.x)"), ("torque", "peak(motor.effort)")]);
    let one = sweep(&model(), "inverse", &radii(&r), &out, Some(1), &Progress::new(), &StopToken::new()).unwrap();
    let two = sweep(&model(), "inverse", &radii(&r), &out, Some(2), &Progress::new(), &StopToken::new()).unwrap();
    let bits = |rows: &[linkwork::sweep::Row]| -> Vec<Vec<u64>> {
        rows.iter().map(|r| r.as_ref().unwrap().iter().map(|v| v.to_bits()).collect()).collect()
    };
    assert_eq!(bits(&one), bits(&two));
}

/// A sweep counts its variants as they finish, and a stop asked of it ends every variant not
/// finished as interrupted while the sweep still returns one row a variant.
#[test]
fn a_stopped_sweep_ends_its_variants_as_interrupted() {
    let out = outputs(&[("s", "final(slider.x)")]);
    let watch = Progress::new();
    let rows = sweep(&model(), "kinematics", &radii(&[0.1, 0.12]), &out, Some(1), &watch, &StopToken::new()).unwrap();
    assert!(rows.iter().all(Result::is_ok));
    assert_eq!(watch.finished(), 2);
    let (stopped, stop) = (Progress::new(), StopToken::new());
    stop.stop();
    let rows = sweep(&model(), "kinematics", &radii(&[0.1, 0.12, 0.14]), &out, Some(2), &stopped, &stop).unwrap();
    assert_eq!(rows.len(), 3);
    assert!(rows.iter().all(|r| matches!(r, Err(Error::Interrupted { .. }))), "{rows:?}");
    assert_eq!(stopped.finished(), 3);
}

/// With gradients: each row's outputs, then each output's derivative with respect to each
/// parameter asked, output by output; the stroke (an expression, and the model's summary by
/// name) has `d/dr = 2` and `d/dL = 0` exactly (closed form `2 r`; 1e-9: the run's convergence),
/// and an output that is neither an expression nor a summary is a model error at its path
/// before anything runs.
#[test]
fn a_sweep_with_gradients_gives_each_outputs_derivatives() {
    let wrt = ["r".to_string(), "L".to_string()];
    let list = outputs(&[("stroke", "max(slider.x) - min(slider.x)"), ("summary", "stroke")]);
    let sweep = linkwork::sweep::sweep_with_gradients;
    let rows =
        sweep(&model(), "kinematics", &radii(&[0.08, 0.12]), &list, &wrt, None, &Progress::new(), &StopToken::new())
            .unwrap();
    for (r, row) in [0.08, 0.12].iter().zip(&rows) {
        let row = row.as_ref().unwrap();
        assert_eq!(row.len(), 2 + 2 * 2);
        assert!((row[0] - 2.0 * r).abs() < 1e-9 && (row[1] - 2.0 * r).abs() < 1e-9, "{row:?}");
        for d in [&row[2..4], &row[4..6]] {
            assert!((d[0] - 2.0).abs() < 1e-9 && d[1].abs() < 1e-9, "{row:?}");
        }
    }
    let unknown = outputs(&[("x", "nothing")]);
    match sweep(&model(), "kinematics", &radii(&[0.1]), &unknown, &wrt, None, &Progress::new(), &StopToken::new()) {
        Err(Error::Model(problems)) => {
            assert!(
                problems[0].path == "outputs.x" && problems[0].message.contains("summaries: stroke"),
                "{problems:?}"
            )
        }
        other => panic!("{other:?}"),
    }
}
