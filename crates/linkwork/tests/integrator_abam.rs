//! The `abam` integrator (coordinate partitioning with Adams-Bashforth-Moulton): conservation of
//! energy, convergence against a closed form, constraint residuals, and re-partitioning.

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
fn double_pendulum_energy_abam() {
    let (_, r) = run("double_pendulum.yaml", "dynamics_abam");
    let drift = energy_drift(&r);
    eprintln!("abam drift {drift:e} stats {:?}", r.summary["statistics"]);
    assert!(drift < 5e-2, "drift {drift}");
}
