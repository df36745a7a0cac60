//! A solve with an unchanged grasp and a new wrench or warm start allocates nothing:
//! counted with a wrapping global allocator.

use grasp_torque::{load_problem, GraspSolver, SolverConfig, WarmStart};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    // Per thread: the test harness allocates on its own threads meanwhile.
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    ALLOCS.with(|c| c.set(c.get() + 1));
}

fn allocations() -> usize {
    ALLOCS.with(Cell::get)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static A: Counting = Counting;

#[test]
fn native_solves_reuse_the_workspace() {
    for name in [
        "paper-example",
        "hand5-pcwf",
        "hand4-sfcl",
        "hand4-sfce",
        "hand5-mixed",
    ] {
        let p = load_problem(format!(
            "{}/fixtures/{name}.json",
            concat!(env!("CARGO_MANIFEST_DIR"), "/../..")
        ))
        .unwrap();
        let mut s = GraspSolver::new(&p, &SolverConfig::default()).unwrap();
        let mut w = p.wrench;
        // Warm up: buffers grow to size once.
        s.solve(&w, &WarmStart::default()).unwrap();
        s.resolve(&w).unwrap();
        let before = allocations();
        for k in 0..50 {
            w[k % 3] *= 1.0 + 0.002 * (k as f64).sin();
            assert!(s.resolve(&w).unwrap().is_optimal());
            assert!(s.solve(&w, &WarmStart::default()).unwrap().is_optimal());
        }
        assert_eq!(allocations() - before, 0, "{name} allocated");
    }
}
