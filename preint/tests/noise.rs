//! The continuous → discrete noise conversion ([`preint::ImuNoise`]): per-sample std from a
//! density and a cell, random-walk step std, and the cell rules, against the formulas written
//! out (the crate's conversion functions themselves: the unit tests of `preint/src/noise.rs`).
//! (That the preintegrator uses the same conversion is checked in `tests/linearisation.rs`,
//! whose reference covariance uses `Σ/c_k` with the cells computed there.)

use preint::{CellRule, ImuNoise, Scheme};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 4.0 * f64::EPSILON * b.abs()
}

#[test]
fn sample_std_is_density_over_root_dt() {
    let n = ImuNoise::euroc();
    for dt in [1e-3, 5e-3, 0.0123, 0.1] {
        assert!(close(n.gyro_sample_std(dt), 1.6968e-4 / dt.sqrt()));
        assert!(close(n.acc_sample_std(dt), 2.0e-3 / dt.sqrt()));
        assert!(close(n.gyro_bias_step_std(dt), 1.9393e-5 * dt.sqrt()));
        assert!(close(n.acc_bias_step_std(dt), 3.0e-3 * dt.sqrt()));
    }
    // 200 Hz EuRoC: σ·√200 per sample (hand-computed: 1.6968e-4 · 14.14214 = 2.399638e-3).
    assert!((n.gyro_sample_std(0.005) - 2.399638e-3).abs() < 1e-9);
    assert!((n.acc_sample_std(0.005) - 2.828427e-2).abs() < 1e-8);
}

#[test]
fn cell_rules() {
    let (l, r) = (0.004, 0.006);
    assert_eq!(Scheme::Euler.cell_rule(), CellRule::Held);
    assert_eq!(Scheme::Midpoint.cell_rule(), CellRule::Centered);
    assert_eq!(Scheme::Hermite4.cell_rule(), CellRule::Centered);
    // Euler holds a sample over the interval after it; the last sample falls back to the one
    // before.
    assert_eq!(CellRule::Held.cell_s(l, r), r);
    assert_eq!(CellRule::Held.cell_s(0.0, r), r);
    assert_eq!(CellRule::Held.cell_s(l, 0.0), l);
    // Quadrature nodes: mean of the adjacent intervals; one interval at an end.
    assert_eq!(CellRule::Centered.cell_s(l, r), 0.005);
    assert_eq!(CellRule::Centered.cell_s(0.0, r), r);
    assert_eq!(CellRule::Centered.cell_s(l, 0.0), l);
    // No neighbour: an infinite cell (no noise), never a division by zero.
    for rule in [CellRule::Held, CellRule::Centered] {
        assert_eq!(rule.cell_s(0.0, 0.0), f64::INFINITY);
    }
}
