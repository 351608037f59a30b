//! The kinematic time loop allocates nothing: a run of 2001 output points makes exactly as many
//! heap allocations as a run of 41 (setup is the same; only the loop is longer). Counted with a
//! global allocator in this test binary only, on the test's own thread: the test harness's main
//! thread allocates now and then while it waits (more often on a loaded machine), and the engine
//! runs on the calling thread.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Whether allocations on this thread are counted (a const initialiser: no allocation).
    static COUNTED: Cell<bool> = const { Cell::new(false) };
}

fn count() {
    if COUNTED.try_with(Cell::get).unwrap_or(false) {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    }
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

#[test]
fn time_loop_allocates_nothing() {
    COUNTED.with(|c| c.set(true));
    let path = format!("{}/../../examples/quick_return_a.yaml", env!("CARGO_MANIFEST_DIR"));
    let mut model = linkwork::Model::load(path).unwrap();
    let mut count = |t_end: f64| {
        model.analyses[0].t_end = t_end;
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        let r = model.run("kinematics").unwrap();
        (ALLOCATIONS.load(Ordering::Relaxed) - before, r.len())
    };
    let (short, n_short) = count(2.0);
    let (long, n_long) = count(100.0);
    assert_eq!((n_short, n_long), (41, 2001));
    assert!(short > 0, "the counter sees the engine's setup allocations");
    assert_eq!(
        short,
        long,
        "the 2001-point run allocated {} more times than the 41-point run",
        long as i64 - short as i64
    );
}
