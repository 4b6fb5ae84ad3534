//! No heap allocation per sample: a counting global allocator watches `integrate`.
//!
//! - `with_capacity(n)` (samples kept) and `keep_samples = false` (with `new`): no allocation
//!   at all while integrating, one sample at a time or as slices, and none in `finish`.
//! - `new` with `keep_samples = true` (the default): the stored-sample `Vec` grows
//!   geometrically, so the count is a handful of reallocations (≤ log₂ n + 1), not one per
//!   sample.

use nalgebra::Vector3;
use preint::{ImuBias, ImuSample, Level, PreintParams, Preintegrator, Scheme};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;
// Per thread, so that tests running in parallel do not count each other's allocations.
thread_local! {
    static ON: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

/// The allocation counter of this thread.
struct Allocs;
impl Allocs {
    fn store(&self, v: usize) {
        COUNT.with(|c| c.set(v));
    }
    fn load(&self) -> usize {
        COUNT.with(|c| c.get())
    }
    fn bump(&self) {
        COUNT.with(|c| c.set(c.get() + 1));
    }
}
static ALLOCS: Allocs = Allocs;

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        if ON.with(|c| c.get()) {
            ALLOCS.bump();
        }
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        if ON.with(|c| c.get()) {
            ALLOCS.bump();
        }
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static A: Counting = Counting;

/// Runs `f` with the counter on; returns its result and the allocations it made.
fn counted<R>(f: impl FnOnce() -> R) -> (R, usize) {
    ALLOCS.store(0);
    ON.with(|c| c.set(true));
    let r = f();
    ON.with(|c| c.set(false));
    (r, ALLOCS.load())
}

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
    for &scheme in Scheme::ALL {
        for level in [Level::Deltas, Level::Covariance, Level::Combined] {
            for (keep, slice) in [(false, false), (true, false), (false, true), (true, true)] {
                let mut prm = PreintParams::default()
                    .with_scheme(scheme)
                    .with_level(level);
                prm.keep_samples = keep;
                let mut pi =
                    Preintegrator::with_capacity(prm, ImuBias::zero(), n as usize).unwrap();
                // One by one, or as slices (Level::Deltas with Euler and midpoint takes the
                // slice path, `Core::run_deltas`).
                let ((), count) = counted(|| {
                    if slice {
                        for chunk in samples.chunks(1000) {
                            pi.integrate_slice(chunk).unwrap();
                        }
                    } else {
                        for s in &samples {
                            pi.integrate(s).unwrap();
                        }
                    }
                });
                assert_eq!(
                    count, 0,
                    "{scheme:?} {level:?} keep={keep} slice={slice}: {count} allocations"
                );
                // The counter works: finish() allocates nothing either, a Vec does.
                let ((m, v), count) = counted(|| {
                    let m = pi.finish().unwrap();
                    let v: Vec<u8> = Vec::with_capacity(std::hint::black_box(8));
                    (m, v)
                });
                assert_eq!(count, 1);
                drop(v);
                assert!(m.delta_v.norm().is_finite());
            }
        }
    }
}

#[test]
fn new_allocates_only_for_stored_samples_and_only_amortised() {
    let n = 10_000usize;
    let samples: Vec<_> = (0..n as i64).map(sample).collect();
    for &scheme in Scheme::ALL {
        for keep in [false, true] {
            let mut prm = PreintParams::default()
                .with_scheme(scheme)
                .with_level(Level::Combined);
            prm.keep_samples = keep;
            let mut pi = Preintegrator::new(prm, ImuBias::zero()).unwrap();
            let ((), count) = counted(|| {
                for s in &samples {
                    pi.integrate(s).unwrap();
                }
            });
            eprintln!("{scheme:?} new, keep_samples={keep}: {count} allocations for {n} samples");
            if keep {
                let bound = (n as f64).log2().ceil() as usize + 1;
                assert!(
                    count >= 1 && count <= bound,
                    "{scheme:?}: {count} > {bound}"
                );
            } else {
                assert_eq!(count, 0, "{scheme:?}: {count} allocations");
            }
            assert_eq!(pi.samples().len(), if keep { n } else { 0 });
        }
    }
}

/// The state inside a window (`preint::deskew`): a query allocates nothing; `deltas_at` makes
/// exactly the output vector (and the running pass's one box at construction).
#[test]
fn queries_inside_a_window_do_not_allocate() {
    let samples: Vec<_> = (0..2000).map(sample).collect();
    for &scheme in Scheme::ALL {
        let prm = PreintParams::default().with_scheme(scheme);
        let (t_i, t_j) = (12_345_678, 9_000_000_000);
        let mut w =
            preint::deskew::WindowDeltas::new(&prm, &ImuBias::zero(), &samples, t_i, t_j).unwrap();
        let times: Vec<i64> = (1..=3000).map(|k| t_i + k * 2_990_001).collect();
        let (last, count) = counted(|| {
            let mut last = None;
            for &t in &times {
                last = Some(w.at(t).unwrap());
            }
            last
        });
        assert_eq!(count, 0, "{scheme:?}: {count} allocations in 3000 queries");
        assert!(last.unwrap().delta_p.norm().is_finite());
        let (out, count) = counted(|| {
            preint::deskew::deltas_at(&prm, &ImuBias::zero(), &samples, (t_i, t_j), &times).unwrap()
        });
        assert_eq!((out.len(), count), (times.len(), 2), "{scheme:?}");
    }
}
