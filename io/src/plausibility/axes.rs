//! Check 7 of the module docs: do the gyroscope's axes agree with the accelerometer's?
//!
//! Each quasi-static moment of the scale check ([`super::scale`]) is paired with the first later
//! one, within [`MAX_GAP_S`], whose gravity direction (accelerometer frame) differs by at
//! least [`MIN_TURN_RAD`]: the directions `u_i`, `u_j` and the gyro's rotation between them,
//! `R = Π_k Exp(ω_k Δt_k)`. Gravity being fixed in the world, `u_j = Rᵀ u_i` when the gyro's
//! axes are the accelerometer's, whatever the size of the turn (the product is exact). For
//! each of the 48 signed permutations `M` (an axis inverted, two swapped, a left-handed frame,
//! …) the gyro read through it turns by `Π Exp(M ω_k Δt_k)`, which is `M R Mᵀ` for `det M = 1`
//! and `P R₋ Pᵀ` with `P = −M` and `R₋ = Π Exp(−ω_k Δt_k)` otherwise. The gyro's bias is left
//! out (a MEMS bias turns gravity by well under a degree over a few seconds). Each map's
//! misfit is the mean over the pairs of `|u_j − R_Mᵀ u_i| / |u_j − u_i|`, the part of the
//! turn it does not explain (a mean, not a median: a map that keeps one axis explains every
//! turn about that axis, and only the turns about the others tell it from the identity):
//! - **mismatch**: the identity leaves more than a tenth of the turn unexplained and another
//!   map less than a third of what the identity leaves: that map is named ("gyro y looks
//!   inverted relative to the accelerometer");
//! - **agree**: the identity leaves less than a quarter, and every other map more than a tenth
//!   and more than three times the identity's;
//! - **cannot tell**: otherwise, or with fewer than 10 pairs: the maps that fit as well are
//!   named (turning about the gravity direction does not move it, so a body that only turns
//!   about the vertical cannot tell that axis's sign).

use super::median;
use super::scale::{DECISIVE_RATIO, MIN_PAIRS, gyro_turn, quasi_static};
use nalgebra::{Matrix3, Vector3};
use preint::ImuSample;

const AXES: [&str; 3] = ["x", "y", "z"];

/// Longest time between the two moments of a pair \[s\].
pub const MAX_GAP_S: f64 = 5.0;

/// Smallest turn of the gravity direction between the two moments of a pair \[rad\] (5°).
pub const MIN_TURN_RAD: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// Unexplained fraction of the turn above which a map can be excluded (when another leaves
/// three times less).
pub const MISFIT: f64 = 0.1;

/// Most pairs used (the first ones): enough for a verdict, and a bound on the cost (each pair
/// integrates up to [`MAX_GAP_S`] of samples).
pub const MAX_PAIRS: usize = 400;

/// Unexplained fraction of the turn below which the identity fits (agreement).
pub const FIT: f64 = 0.25;

/// Two quasi-static moments between which gravity turned: its directions at both and the
/// gyro's rotation ([`gyro_turn`]).
struct TurnPair {
    ui: Vector3<f64>,
    uj: Vector3<f64>,
    turn: (Matrix3<f64>, Matrix3<f64>),
}

fn turn_pairs(samples: &[ImuSample], dt: f64) -> Vec<TurnPair> {
    let (_, quasi) = quasi_static(samples, dt);
    let mut pairs = Vec::new();
    for (a, &(i, ui)) in quasi.iter().enumerate() {
        let later = quasi[a + 1..]
            .iter()
            .take_while(|(j, _)| (samples[*j].t_ns - samples[i].t_ns) as f64 * 1e-9 <= MAX_GAP_S)
            .find(|(_, uj)| ui.angle(uj) >= MIN_TURN_RAD);
        if pairs.len() == MAX_PAIRS {
            break;
        }
        if let Some(&(j, uj)) = later {
            pairs.push(TurnPair {
                ui,
                uj,
                turn: gyro_turn(samples, (i, j)),
            });
        }
    }
    pairs
}

/// A signed permutation of the gyro's axes: the accelerometer-frame rate's axis `i` is
/// `sign[i]` times the gyro's axis `from[i]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AxisMap {
    /// The gyro axis each accelerometer axis reads.
    pub from: [usize; 3],
    /// Its sign, ±1.
    pub sign: [i8; 3],
}

impl AxisMap {
    /// The gyro's axes as the accelerometer's.
    pub const IDENTITY: AxisMap = AxisMap {
        from: [0, 1, 2],
        sign: [1, 1, 1],
    };

    /// The 48 signed permutations, the identity first.
    pub fn all() -> Vec<AxisMap> {
        const PERMS: [[usize; 3]; 6] = [
            [0, 1, 2],
            [1, 0, 2],
            [0, 2, 1],
            [2, 1, 0],
            [1, 2, 0],
            [2, 0, 1],
        ];
        let mut out = Vec::with_capacity(48);
        for from in PERMS {
            for bits in 0..8u8 {
                let sign = [0, 1, 2].map(|k| if bits >> k & 1 == 1 { -1 } else { 1 });
                out.push(AxisMap { from, sign });
            }
        }
        out
    }

    /// `M`, with `ω_acc = M ω_gyro`.
    pub fn matrix(&self) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| {
            if self.from[i] == j {
                f64::from(self.sign[i])
            } else {
                0.0
            }
        })
    }

    /// Whether `M` has determinant −1 (a left-handed gyro frame against the accelerometer's).
    pub fn left_handed(&self) -> bool {
        self.matrix().determinant() < 0.0
    }

    /// What the map says, in words: "gyro y looks inverted", "gyro x and y look swapped", or
    /// the mapping axis by axis.
    pub fn describe(&self) -> String {
        let inverted: Vec<&str> = (0..3)
            .filter(|&i| self.sign[i] < 0)
            .map(|i| AXES[i])
            .collect();
        let moved: Vec<usize> = (0..3).filter(|&i| self.from[i] != i).collect();
        let hand = if self.left_handed() {
            " (a left-handed gyro frame)"
        } else {
            ""
        };
        if moved.is_empty() {
            let verb = if inverted.len() == 1 { "looks" } else { "look" };
            return format!("gyro {} {verb} inverted{hand}", inverted.join(" and "));
        }
        if moved.len() == 2 && inverted.is_empty() {
            return format!(
                "gyro {} and {} look swapped{hand}",
                AXES[moved[0]], AXES[moved[1]]
            );
        }
        let map: Vec<String> = (0..3)
            .map(|i| {
                let s = if self.sign[i] < 0 { "−" } else { "" };
                format!("accelerometer {} = {s}gyro {}", AXES[i], AXES[self.from[i]])
            })
            .collect();
        format!("the gyro's axes look mapped: {}{hand}", map.join(", "))
    }
}

/// How well each axis map explains the turning of the gravity direction.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisFit {
    /// Pairs of quasi-static moments compared.
    pub pairs: usize,
    /// Median turn of the gravity direction between the moments of a pair \[rad\].
    pub median_turn_rad: f64,
    /// The identity's misfit: the mean unexplained fraction of the turn.
    pub identity: f64,
    /// The best map other than the identity and its misfit.
    pub best_other: (AxisMap, f64),
    /// The maps other than the identity that are not excluded (misfit at most [`MISFIT`] or at
    /// most [`DECISIVE_RATIO`] times the identity's).
    pub as_good: Vec<AxisMap>,
}

/// The verdict of check 7.
#[derive(Clone, Debug, PartialEq)]
pub enum AxisVerdict {
    /// The identity fits and every other map is excluded.
    Agree,
    /// Another map fits much better: what it says.
    Mismatch(String),
    /// The motion cannot tell: why.
    CannotTell(String),
}

impl AxisFit {
    /// The verdict (module docs).
    pub fn verdict(&self) -> AxisVerdict {
        let (best, err) = self.best_other;
        if self.identity > MISFIT && err < self.identity / DECISIVE_RATIO {
            return AxisVerdict::Mismatch(format!(
                "{} relative to the accelerometer: over {} pairs of quasi-static moments between \
                 which gravity turns (by {:.0}° median), the gyro as read leaves {:.0} % of the \
                 turn unexplained (mean), mapped so {:.0} %",
                best.describe(),
                self.pairs,
                self.median_turn_rad.to_degrees(),
                100.0 * self.identity,
                100.0 * err
            ));
        }
        if self.identity < FIT && self.as_good.is_empty() {
            return AxisVerdict::Agree;
        }
        let alt: Vec<String> = self.as_good.iter().take(3).map(AxisMap::describe).collect();
        AxisVerdict::CannotTell(format!(
            "over {} pairs (gravity turning {:.0}° median) the gyro as read leaves {:.0} % of \
             the turn unexplained and {} fit{} about as well: the motion does not turn gravity \
             about every axis",
            self.pairs,
            self.median_turn_rad.to_degrees(),
            100.0 * self.identity,
            if alt.is_empty() {
                "other axis maps".to_string()
            } else {
                alt.join("; ")
            },
            if alt.len() == 1 { "s" } else { "" }
        ))
    }
}

/// The mean over `pairs` of `|u_j − R_Mᵀ u_i| / |u_j − u_i|` with the gyro read through `m`
/// (module docs).
fn misfit(pairs: &[TurnPair], m: &AxisMap) -> f64 {
    let mm = m.matrix();
    let (p, proper) = if m.left_handed() {
        (-mm, false)
    } else {
        (mm, true)
    };
    let sum: f64 = (pairs.iter())
        .map(|q| {
            let r = if proper { q.turn.0 } else { q.turn.1 };
            let turn = p * r * p.transpose();
            (q.uj - turn.transpose() * q.ui).norm() / (q.uj - q.ui).norm()
        })
        .sum();
    sum / pairs.len() as f64
}

/// Fits every [`AxisMap`] on the turning pairs of quasi-static moments of `samples` sampled
/// every `dt` s (module docs); `None` with fewer than [`MIN_PAIRS`] pairs.
pub fn gyro_axes_fit(samples: &[ImuSample], dt: f64) -> Option<AxisFit> {
    let pairs = turn_pairs(samples, dt);
    if pairs.len() < MIN_PAIRS {
        return None;
    }
    let identity = misfit(&pairs, &AxisMap::IDENTITY);
    let mut others: Vec<(AxisMap, f64)> = AxisMap::all()[1..]
        .iter()
        .map(|m| (*m, misfit(&pairs, m)))
        .collect();
    others.sort_by(|a, b| a.1.total_cmp(&b.1));
    let as_good = others
        .iter()
        .filter(|(_, e)| *e <= MISFIT || *e <= identity * DECISIVE_RATIO)
        .map(|(m, _)| *m)
        .collect();
    Some(AxisFit {
        pairs: pairs.len(),
        median_turn_rad: median(pairs.iter().map(|q| q.ui.angle(&q.uj)).collect()),
        identity,
        best_other: others[0],
        as_good,
    })
}
