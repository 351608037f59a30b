//! A model's expressions read its parameters as inputs (`Expr::eval_params`, docs/expressions
//! and the module doc of `linkwork::expr`): a measure of the parametrised slider-crank written
//! with parameters, differentiated along each parameter with dual numbers, against central
//! finite differences of the same measure compiled with the parameter set a little up and down.

mod common;

use common::example_text;
use linkwork::expr::{Dual, Scalar};
use linkwork::model::MeasureKind;
use linkwork::Model;

/// The measure: parameters `r`, `L`, `speed` and `m_rod` (= `rho * L`) with the state and time.
const PROBE: &str = "L * slider.x / r + speed^2 * t * crank.omega + m_rod * sin(crank.phi) + r^2";

/// The parametrised slider-crank with the measure `probe`.
fn model(set: &[(String, String)]) -> Model {
    let text = format!("{}\nmeasures:\n  probe: \"{PROBE}\"\n", example_text("slider_crank_param.yaml"));
    Model::from_yaml_with(&text, set).unwrap()
}

/// The probe's value over `S` with the model's parameters `params`, at a made-up state.
fn probe<S: Scalar>(m: &Model, params: &[S]) -> S {
    let MeasureKind::Expression(e) = &m.measures[0].kind else { panic!("probe is an expression") };
    let n = 3 * m.bodies.len();
    let q: Vec<S> = (0..n).map(|i| S::constant(0.1 + 0.07 * i as f64)).collect();
    let qdot: Vec<S> = (0..n).map(|i| S::constant(1.3 - 0.2 * i as f64)).collect();
    e.eval_params(&q, &qdot, &[], &[], S::constant(0.37), params)
}

#[test]
fn a_measure_differentiates_along_each_parameter_like_finite_differences_of_the_model() {
    let nominal = model(&[]);
    let names: Vec<&String> = nominal.parameters.keys().collect();
    assert_eq!(names, ["r", "L", "speed", "rho", "m_crank", "m_rod"]);
    let MeasureKind::Expression(e) = &nominal.measures[0].kind else { panic!("probe is an expression") };
    // r, L, speed and m_rod, by their index in file order.
    assert_eq!(e.parameters(), &[0, 1, 2, 5]);
    let values: Vec<f64> = nominal.parameters.values().copied().collect();
    assert_eq!(probe(&nominal, &values).to_bits(), {
        let n = 3 * nominal.bodies.len();
        let q: Vec<f64> = (0..n).map(|i| 0.1 + 0.07 * i as f64).collect();
        let qdot: Vec<f64> = (0..n).map(|i| 1.3 - 0.2 * i as f64).collect();
        e.eval_global(&q, &qdot, &[], &[], 0.37).to_bits()
    });
    let (rho, length) = (values[3], values[1]);
    for (k, name) in names.iter().enumerate().take(4) {
        // Each parameter's derivative along parameter k: 1 for itself, and m_rod = rho * L
        // follows L (by rho) and rho (by L), as `--set` makes it.
        let chain = |j: usize| match (j, k) {
            (j, k) if j == k => 1.0,
            (5, 1) => rho,
            (5, 3) => length,
            _ => 0.0,
        };
        let params: Vec<Dual> = values.iter().enumerate().map(|(j, &v)| Dual::new(v, chain(j))).collect();
        let exact = probe(&nominal, &params).d;
        // Central differences with h = 1e-6 of the value: truncation h^2 |f'''| / 6 ~ 1e-12 and
        // rounding eps |f| / h ~ 1e-9 relative to the probe's size (below 100 here), so 1e-7
        // relative to 1 + |derivative|.
        let p = values[k];
        let h = 1e-6 * p;
        let at = |v: f64| {
            let m = model(&[(name.to_string(), format!("{v:e}"))]);
            let values: Vec<f64> = m.parameters.values().copied().collect();
            probe(&m, &values)
        };
        let fd = (at(p + h) - at(p - h)) / (2.0 * h);
        assert!((exact - fd).abs() <= 1e-7 * (1.0 + fd.abs()), "d probe / d {name}: {exact:e} against {fd:e}");
    }
}
