//! The goodness-of-fit test (`preint_calib::fit`): its p-values against tabulated χ² values,
//! its false-alarm rate on correct fits and its verdict on wrong ones.

use preint_calib::fit::{Fit, LARGE_DOF};
use rand::SeedableRng;
use rand_distr::{ChiSquared, Distribution};

/// Upper-tail p-values at the critical values of the NIST/SEMATECH e-Handbook of Statistical
/// Methods, table 1.3.6.7.4 ("Critical values of the chi-square distribution", upper tail),
/// printed there to 3 decimals; the exact p at those rounded values is from mpmath 1.3
/// (`gammainc(dof/2, x/2, inf, regularized=True)`, 40 digits), e.g. 0.050013683763956699 at
/// (3.841, 1).
#[test]
fn p_values_match_the_tables() {
    let table = [
        (3.841, 1, 0.050_013_683_763_956_7),
        (6.635, 1, 0.009_999_419_574_042_53),
        (10.828, 1, 0.000_999_765_719_583_09),
        (18.307, 10, 0.050_000_589_091_398_1),
        (23.209, 10, 0.010_000_865_814_740_8),
        (29.588, 10, 0.001_000_111_941_063_48),
        (124.342, 100, 0.050_000_715_769_971_8),
        (135.807, 100, 0.009_999_573_729_248_80),
        (149.449, 100, 0.001_000_046_221_773_25),
    ];
    for (x, dof, p) in table {
        let f = Fit::new(x, dof);
        assert!(
            (f.p_value / p - 1.0).abs() < 1e-9,
            "χ² {x}, {dof} dof: p {} vs {p}",
            f.p_value
        );
        assert!((f.p_value + f.p_value_lower - 1.0).abs() < 1e-12);
        assert!(f.credible, "{x}, {dof}: {}", f.why);
    }
    // Far tails (mpmath, as above): the upper tail 6.8455110413003194e-7 at (45.7, 9), the
    // lower tail 1.744640104219179e-9 at (0.5, 15), the upper 1.6927979958857088e-37 at
    // (400, 100).
    let f = Fit::new(45.7, 9);
    assert!((f.p_value / 6.845_511_041_300_319e-7 - 1.0).abs() < 1e-8);
    assert!(!f.credible && f.why.contains("p = 6.8e-7"), "{}", f.why);
    let f = Fit::new(0.5, 15);
    assert!((f.p_value_lower / 1.744_640_104_219_179e-9 - 1.0).abs() < 1e-8);
    assert!(f.credible && f.pessimistic, "{}", f.why);
    assert!(f.why.contains("pessimistic"));
    let f = Fit::new(400.0, 100);
    assert!((f.p_value / 1.692_797_995_885_708_8e-37 - 1.0).abs() < 1e-8);
    // χ² = 0 exactly (residuals all zero): the tails are 1 and 0.
    let f = Fit::new(0.0, 9);
    assert_eq!((f.p_value, f.p_value_lower), (1.0, 0.0));
    assert!(f.credible && f.pessimistic);
}

/// χ² drawn from χ²_dof (the fit is correct): credible in ≥ 99.9 % of the draws, for few and
/// many degrees of freedom alike.
#[test]
fn correct_fits_are_credible() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    for dof in [1usize, 2, 3, 9, 15, 29, 30, 43, 100, 223, 1000, 10_000] {
        let d = ChiSquared::new(dof as f64).unwrap();
        let n = 4000;
        let credible = (0..n)
            .filter(|_| Fit::new(d.sample(&mut rng), dof).credible)
            .count();
        assert!(
            credible as f64 >= 0.999 * n as f64,
            "{dof} dof: {credible} of {n} credible"
        );
    }
}

/// Residuals twice the noise model's σ (χ² = 4·dof) are not credible at 100 dof, nor at 1000;
/// at 10 dof the p-value decides; σ √3 times too small is the edge for many dof.
#[test]
fn wrong_fits_are_not_credible() {
    let f = Fit::new(400.0, 100);
    assert!(!f.credible);
    assert!(f.why.contains("2.000 times"), "{}", f.why);
    assert!((f.scale() - 2.0).abs() < 1e-15);
    assert!((f.scaled(0.5) - 1.0).abs() < 1e-15);
    // 10 dof: χ² = 40 has p = 1.7e-5 (credible), 60 has p = 3.6e-9.
    assert!(Fit::new(40.0, 10).credible);
    assert!(!Fit::new(60.0, 10).credible);
    assert!(!Fit::new(4000.0, 1000).credible);
    // dof ≥ 30: the ratio decides (3.0 credible, 3.01 not), though p is tiny at 1000 dof.
    assert!(Fit::new(3.0 * LARGE_DOF as f64, LARGE_DOF).credible);
    assert!(Fit::new(3000.0, 1000).credible);
    assert!(Fit::new(3000.0, 1000).p_value < 1e-100);
    assert!(!Fit::new(3010.0, 1000).credible);
    // Credible at many dof although the χ² is ruled out: said as such, not "consistent".
    let f = Fit::new(1.7 * 11941.0, 11941);
    assert!(f.credible && f.p_value < 1e-6, "{f:?}");
    assert!(
        f.why.contains("more than chance allows") && !f.why.contains("consistent"),
        "{}",
        f.why
    );
    assert!(
        Fit::new(105.0, 100)
            .why
            .contains("consistent with the noise model")
    );
    // Underflow is said, not printed as 0.
    assert!(Fit::new(3.06e7, 223).why.contains("p < 1e-300"));
    // A cause is appended only to a fit that is not credible.
    assert!(
        Fit::new(400.0, 100)
            .because("the poses")
            .why
            .ends_with("; likely cause: the poses")
    );
    assert!(
        !Fit::new(100.0, 100)
            .because("the poses")
            .why
            .contains("poses")
    );
}

/// What cannot be tested says so: no redundancy, or a χ² that is not a number.
#[test]
fn degenerate_inputs() {
    let f = Fit::new(0.0, 0);
    assert!(f.credible && f.chi2_dof.is_nan() && f.p_value.is_nan());
    assert!(f.why.contains("0 degrees of freedom"));
    assert_eq!(f.scale(), 1.0);
    for x in [f64::NAN, f64::INFINITY, -1.0] {
        let f = Fit::new(x, 10);
        assert!(!f.credible, "{x}");
        assert!(f.why.contains("not a finite"));
    }
}
