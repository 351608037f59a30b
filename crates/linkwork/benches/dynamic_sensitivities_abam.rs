//! Design sensitivities of a dynamic analysis integrated by abam: the quick-return's free motion
//! (`dynamics`, 0 to 2 s, `--integrator abam` at the file's tolerances) with the derivatives of
//! every column with respect to P = 1 and 4 parameters, against the run without them (beside
//! `dynamic_sensitivities.rs`, bdf's).
//!
//! `cargo bench -p linkwork --bench dynamic_sensitivities_abam`. Figures are recorded in
//! `docs/performance.md`, "Design sensitivities of a dynamic analysis".

use criterion::{criterion_group, criterion_main, Criterion};
use linkwork::model::spec::IntegratorKind;
use linkwork::{Model, Overrides, RunOptions};
use std::hint::black_box;

/// The run with P = 0, 1 and 4 parameters (the first P of the file's, as bdf's bench).
fn sensitivities(c: &mut Criterion) {
    let path = format!("{}/../../examples/quick_return_a.yaml", env!("CARGO_MANIFEST_DIR"));
    let model = Model::load(&path).expect("the example loads");
    let names: Vec<String> = model.parameters.keys().cloned().collect();
    let overrides = Overrides { integrator: Some(IntegratorKind::Abam), ..Default::default() };
    let mut group = c.benchmark_group("quick_return_a_dynamic_sensitivities_abam");
    for p in [0, 1, 4] {
        let options =
            RunOptions { sensitivities: names[..p].to_vec(), overrides: overrides.clone(), ..Default::default() };
        group.bench_function(format!("dynamics_2s_P{p}"), |b| {
            b.iter(|| black_box(&model).run("dynamics", &options).map(|r| r.len()).ok())
        });
    }
    group.finish();
}

criterion_group!(benches, sensitivities);
criterion_main!(benches);
