//! Design sensitivities of a dynamic analysis: the quick-return's free motion (`dynamics`, 0 to
//! 2 s, bdf at the file's tolerances) with the derivatives of every column with respect to P = 1,
//! 4 and 6 parameters (all the file has: P = 16 needs a model with more), against the run without
//! them.
//!
//! `cargo bench -p linkwork --bench dynamic_sensitivities`. Figures are recorded in
//! `docs/performance.md`, "Design sensitivities of a dynamic analysis".

use criterion::{criterion_group, criterion_main, Criterion};
use linkwork::{Model, RunOptions};
use std::hint::black_box;

/// The run with P = 0, 1, 4 and 6 parameters (the first P of the file's: the steps the error test
/// takes with a parameter, and the elements whose numbers move with it, depend on which it is).
fn sensitivities(c: &mut Criterion) {
    let path = format!("{}/../../examples/quick_return_a.yaml", env!("CARGO_MANIFEST_DIR"));
    let model = Model::load(&path).expect("the example loads");
    let names: Vec<String> = model.parameters.keys().cloned().collect();
    let mut group = c.benchmark_group("quick_return_a_dynamic_sensitivities");
    for p in [0, 1, 4, 6] {
        let options = RunOptions { sensitivities: names[..p].to_vec(), ..Default::default() };
        group.bench_function(format!("dynamics_2s_P{p}"), |b| {
            b.iter(|| black_box(&model).run("dynamics", &options).map(|r| r.len()).ok())
        });
    }
    group.finish();
}

criterion_group!(benches, sensitivities);
criterion_main!(benches);
