//! Kinematic analysis of the quick-return mechanism (model A), timed per output point.
//!
//! `cargo bench -p linkwork --bench kinematics`. Two runs: the analysis as the model file gives it
//! (0 to 2 s every 0.05 s: 41 points, so assembly and the symbolic factorization weigh in), and
//! the same mechanism over 100 s (2001 points), where the time loop dominates; and the 2 s run,
//! kinematic and inverse, with design sensitivities. Criterion reports
//! time per element = per output point. Figures are recorded in `docs/performance.md`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use linkwork::{Model, RunOptions};
use std::hint::black_box;

fn quick_return(c: &mut Criterion) {
    let path = format!("{}/../../examples/quick_return_a.yaml", env!("CARGO_MANIFEST_DIR"));
    let mut model = Model::load(&path).expect("the example loads");
    let mut group = c.benchmark_group("quick_return_a");
    for (label, t_end) in [("kinematics_2s", 2.0), ("kinematics_100s", 100.0)] {
        model.analyses[0].t_end = t_end;
        let points = model.run("kinematics", &Default::default()).expect("the example runs").len();
        group.throughput(Throughput::Elements(points as u64));
        group.bench_function(label, |b| {
            b.iter(|| black_box(&model).run("kinematics", &Default::default()).map(|r| r.len()).ok())
        });
    }
    group.finish();
}

/// The same 2 s analysis, and the inverse analysis over the same motion, with the derivatives of
/// every column with respect to P = 1, 4 and 16 parameters (those of the file in turn, repeated:
/// the cost of a parameter does not depend on which it is), against the run without them:
/// `docs/performance.md`, "Design sensitivities".
fn sensitivities(c: &mut Criterion) {
    let path = format!("{}/../../examples/quick_return_a.yaml", env!("CARGO_MANIFEST_DIR"));
    let model = Model::load(&path).expect("the example loads");
    let names: Vec<String> = model.parameters.keys().cloned().collect();
    let mut group = c.benchmark_group("quick_return_a_sensitivities");
    for analysis in ["kinematics", "inverse"] {
        for p in [0, 1, 4, 16] {
            let options =
                RunOptions { sensitivities: names.iter().cycle().take(p).cloned().collect(), ..Default::default() };
            group.bench_function(format!("{analysis}_2s_P{p}"), |b| {
                b.iter(|| black_box(&model).run(analysis, &options).map(|r| r.len()).ok())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, quick_return, sensitivities);
criterion_main!(benches);
