//! `integrate`'s prediction (`--initial-state`): the state at the window's end, and the deltas
//! (with the state) at each `--at` time inside the window ([`preint::deskew`]).

use preint::deskew::DeltasAt;
use preint::deskew::{deltas_at, states_at};
use preint::{ImuBias, NavState, PreintError, PreintParams};
use preint_analysis::format::{list, rows, text_matrix};
use preint_analysis::stream::StreamWindow;
use serde_json::{Value, json};
use std::fmt::Write as _;

/// The state at the window's end predicted from `--initial-state` ([`preint::predict`] with
/// the bias estimate and the Earth rate of the measurement).
#[derive(Clone, Debug)]
pub struct Prediction(pub NavState);

impl Prediction {
    /// `{position, velocity, rotation, units}`.
    pub fn to_json(&self) -> Value {
        let x = &self.0;
        json!({
            "position": list(&x.p), "velocity": list(&x.v), "rotation": rows(x.r.matrix()),
            "units": {"position": "m (world frame)", "velocity": "m/s (world frame)",
                      "rotation": "3x3 rows, body -> world"},
        })
    }

    /// `predicted at t_j: p = […] m, v = […] m/s` and the rotation matrix.
    pub fn to_text(&self) -> String {
        let x = &self.0;
        let mut h = String::new();
        let _ = writeln!(
            h,
            "predicted at t_j: p = [{:.9}, {:.9}, {:.9}] m, v = [{:.9}, {:.9}, {:.9}] m/s (world frame)",
            x.p.x, x.p.y, x.p.z, x.v.x, x.v.y, x.v.z
        );
        let _ = writeln!(h, "predicted R (body → world):");
        h.push_str(&text_matrix(x.r.matrix(), "  "));
        h
    }
}

/// The deltas from t_i (and with `--initial-state` the predicted state) at each `--at` time.
#[derive(Clone, Debug, Default)]
pub struct AtTimes(pub Vec<(DeltasAt, Option<NavState>)>);

impl AtTimes {
    /// The deltas (and states from `initial`) at `times` inside the window `w`, in one pass.
    pub fn compute(
        params: &PreintParams,
        bias: &ImuBias,
        w: &StreamWindow,
        times: &[i64],
        initial: Option<&NavState>,
    ) -> Result<Self, PreintError> {
        if times.is_empty() {
            return Ok(Self::default());
        }
        let ends = (w.t_i_ns, w.t_j_ns);
        Ok(Self(match initial {
            Some(x) => states_at(params, bias, &w.samples, ends, x, times)?
                .into_iter()
                .map(|s| (s.deltas, Some(s.state)))
                .collect(),
            None => deltas_at(params, bias, &w.samples, ends, times)?
                .into_iter()
                .map(|d| (d, None))
                .collect(),
        }))
    }

    /// Whether no `--at` time was asked for.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// One row per time: `t_ns`, `delta_t`, `delta_R`, `delta_R_log`, `delta_v`, `delta_p`,
    /// and `predicted` with a state.
    pub fn to_json(&self) -> Value {
        self.0
            .iter()
            .map(|(d, x)| {
                let mut row = json!({
                    "t_ns": d.t_ns,
                    "delta_t": d.delta_t,
                    "delta_R": rows(d.delta_r.matrix()),
                    "delta_R_log": list(&d.delta_r.log()),
                    "delta_v": list(&d.delta_v),
                    "delta_p": list(&d.delta_p),
                });
                if let Some(x) = x {
                    row["predicted"] = json!({
                        "position": list(&x.p), "velocity": list(&x.v),
                        "rotation": rows(x.r.matrix()),
                    });
                }
                row
            })
            .collect()
    }

    /// One line per time: the deltas, and the state when predicted.
    pub fn to_text(&self) -> String {
        let mut h = String::new();
        for (d, x) in &self.0 {
            let phi = d.delta_r.log();
            let _ = write!(
                h,
                "at {} ns (Δt = {:.9} s): φ = [{:.9}, {:.9}, {:.9}] rad, Δv = [{:.9}, {:.9}, {:.9}] m/s, \
                 Δp = [{:.9}, {:.9}, {:.9}] m",
                d.t_ns,
                d.delta_t,
                phi.x,
                phi.y,
                phi.z,
                d.delta_v.x,
                d.delta_v.y,
                d.delta_v.z,
                d.delta_p.x,
                d.delta_p.y,
                d.delta_p.z
            );
            if let Some(x) = x {
                let _ = write!(
                    h,
                    "; p = [{:.9}, {:.9}, {:.9}] m, v = [{:.9}, {:.9}, {:.9}] m/s",
                    x.p.x, x.p.y, x.p.z, x.v.x, x.v.y, x.v.z
                );
            }
            h.push('\n');
        }
        h
    }
}
