//! The time loops allocate nothing: a kinematic run of 2001 output points makes exactly as many
//! heap allocations as a run of 41, and a dynamic run of ten times the motion as many as the
//! shorter one, with each integrator (setup is the same; only the loop is longer). Counted with a
//! global allocator in this test binary only, per thread: the test harness's main thread
//! allocates now and then while it waits, tests run side by side, and the engine runs on the
//! calling thread.

use linkwork::{Model, Overrides};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    /// The allocations counted on this thread, when it counts them (a const initialiser: no
    /// allocation). Each test counts on its own thread, so tests running side by side do not
    /// see each other's.
    static ALLOCATIONS: Cell<Option<usize>> = const { Cell::new(None) };
}

fn count() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get().map(|n| n + 1)));
}

/// Allocations counted on this thread so far (counting starts at the first call).
fn allocations() -> usize {
    ALLOCATIONS.with(|c| {
        let n = c.get().unwrap_or(0);
        c.set(Some(n));
        n
    })
}

// SAFETY: forwards to the system allocator unchanged, only counting calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The example `file`, loaded.
fn example(file: &str) -> Model {
    Model::load(format!("{}/../../examples/{file}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// Overrides that end the run at `t_end` and change nothing else.
fn ending_at(t_end: f64) -> Overrides {
    Overrides { t_end: Some(t_end), ..Default::default() }
}

/// The allocations of one run of `analysis` of `model` under `overrides`, and the rows it wrote.
fn run_counted(model: &Model, analysis: &str, overrides: &Overrides) -> (usize, usize) {
    let options = overrides.clone().into();
    let before = allocations();
    let r = model.run(analysis, &options).unwrap_or_else(|f| panic!("{analysis}: {}", f.error));
    (allocations() - before, r.len())
}

#[test]
fn time_loop_allocates_nothing() {
    allocations();
    let model = example("quick_return_a.yaml");
    let (short, n_short) = run_counted(&model, "kinematics", &ending_at(2.0));
    let (long, n_long) = run_counted(&model, "kinematics", &ending_at(100.0));
    assert_eq!((n_short, n_long), (41, 2001));
    assert!(short > 0, "the counter sees the engine's setup allocations");
    assert_eq!(
        short,
        long,
        "the 2001-point run allocated {} more times than the 41-point run",
        long as i64 - short as i64
    );
}

/// The cam joint on a working surface searches its samples and refines the nearest point at every
/// evaluation, allocating nothing: examples/cam_profile.yaml (expressions and a point table) run
/// over a quarter turn and over two turns makes as many allocations.
#[test]
fn a_cam_surface_allocates_nothing_in_the_time_loop() {
    allocations();
    let model = example("cam_profile.yaml");
    let (short, n_short) = run_counted(&model, "motion", &ending_at(0.25));
    let (long, n_long) = run_counted(&model, "motion", &ending_at(2.0));
    assert_eq!((n_short, n_long), (91, 721));
    assert_eq!(short, long, "the long run allocated {} more times than the short one", long as i64 - short as i64);
}

/// The dynamic step allocates nothing either: a run of ten times the motion (ten times the
/// steps, Newton iterations and factorizations) makes as many allocations, with each integrator,
/// on the double pendulum and on the quick-return coasting. The results' columns are sized for
/// the output times at the start. A new partition of `abam` (a new dependent block: its pattern
/// and symbolic factorization) is a new setup and allocates: the quick-return re-partitions
/// about five times a second under `abam`, and though the blocks of the last eight partitions
/// are kept, a partition first met later in the motion allocates its own, so there it is left
/// out; the double pendulum keeps its first partition throughout.
#[test]
fn dynamic_steps_allocate_nothing() {
    use linkwork::analysis::dynamic::IntegratorKind;
    allocations();
    for (file, t_end, integrators) in
        [("double_pendulum.yaml", 1.0, IntegratorKind::NAMES), ("quick_return_a.yaml", 2.0, &["bdf", "hht"][..])]
    {
        let model = example(file);
        for name in integrators {
            let count = |t_end: f64| {
                let overrides = Overrides { integrator: IntegratorKind::from_name(name), ..ending_at(t_end) };
                run_counted(&model, "dynamics", &overrides)
            };
            let ((short, rows_short), (long, rows_long)) = (count(t_end), count(10.0 * t_end));
            assert!(rows_long > 9 * rows_short, "{file} {name}: {rows_short} and {rows_long} output rows");
            assert_eq!(
                short,
                long,
                "{file} {name}: ten times the motion allocated {} more times",
                long as i64 - short as i64
            );
        }
    }
}
