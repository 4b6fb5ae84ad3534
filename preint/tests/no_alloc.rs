//! No heap allocation per sample: a counting global allocator watches `integrate`.

use nalgebra::Vector3;
use preint::{ImuBias, ImuSample, Level, PreintParams, Preintegrator, Scheme};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static ALLOCS: AtomicUsize = AtomicUsize::new(0);
thread_local! { static ON: Cell<bool> = const { Cell::new(false) }; }

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        if ON.with(|c| c.get()) {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        if ON.with(|c| c.get()) {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static A: Counting = Counting;

fn sample(k: i64) -> ImuSample {
    let t = k as f64 * 5e-3;
    ImuSample::new(
        k * 5_000_000,
        Vector3::new(t.sin(), 0.3, t.cos()),
        Vector3::new(0.1, t.sin(), 9.81),
    )
}

#[test]
fn integrate_does_not_allocate() {
    let n = 10_000;
    let samples: Vec<_> = (0..n).map(sample).collect();
    for scheme in [Scheme::Euler, Scheme::Midpoint, Scheme::Rk4] {
        for level in [Level::Deltas, Level::Covariance, Level::Combined] {
            for keep in [false, true] {
                let mut prm = PreintParams::default()
                    .with_scheme(scheme)
                    .with_level(level);
                prm.keep_samples = keep;
                let mut pi =
                    Preintegrator::with_capacity(prm, ImuBias::zero(), n as usize).unwrap();
                ALLOCS.store(0, Ordering::Relaxed);
                ON.with(|c| c.set(true));
                for s in &samples {
                    pi.integrate(s).unwrap();
                }
                ON.with(|c| c.set(false));
                let count = ALLOCS.load(Ordering::Relaxed);
                assert_eq!(
                    count, 0,
                    "{scheme:?} {level:?} keep={keep}: {count} allocations"
                );
                // The counter works: finish() allocates nothing either, a Vec does.
                ON.with(|c| c.set(true));
                let m = pi.finish().unwrap();
                let v: Vec<u8> = Vec::with_capacity(std::hint::black_box(8));
                ON.with(|c| c.set(false));
                assert_eq!(ALLOCS.load(Ordering::Relaxed), 1);
                drop(v);
                assert!(m.delta_v.norm().is_finite());
            }
        }
    }
}
