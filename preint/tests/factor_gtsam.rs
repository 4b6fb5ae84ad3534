//! Agreement of `ImuFactor` with GTSAM 4.3 (`ImuFactor` residual and Jacobians, reproduced by
//! `tests/fixtures/gtsam/gtsam_preint.py` from `PreintegratedImuMeasurementsManifold::predict`).
//!
//! The `PreintegratedImu` is built from each fixture's own ΔR, Δv, Δp, bias Jacobians and
//! covariance (GTSAM's Forster-chart covariance, reordered from [φ, p, v] to [φ, v, p]), so
//! only the factor is under test here. Mapping (derived in `preint::ImuFactor` docs), with
//! `M = R_jᵀ R_i`, GTSAM order [rot, pos, vel], bias order [acc, gyro]:
//!
//! - ComponentWise: `e = [−r_φ, −M r_p, −M r_v]`; Jacobians
//!   `∂e/∂x = [−∂r_φ, −M ∂r_p, −M ∂r_v]` plus, for the rotations,
//!   `∂e_{pos,vel}/∂δφ_i += M [r_{p,v}]×`, `∂e_{pos,vel}/∂δφ_j −= [M r_{p,v}]×`. GTSAM's pose
//!   perturbation `[dw, dt]` (Pose3 retract, `dt` in body) and world-frame velocity match
//!   [`NavState`]'s [δφ, δp, δv] to first order.
//! - Logmap (GTSAM 4.3 default): `e = [w, Jl(w)⁻¹(−M r_p), Jl(w)⁻¹(−M r_v)]`, `w = −r_φ`, from
//!   the component-wise residual; and the factor's own [`ResidualMode::Logmap`] residual
//!   `r_L` with its Jacobians maps exactly as `e = −P r_L`, `∂e/∂x = −P ∂r_L/∂x` (`P`: [φ, v, p]
//!   → [rot, pos, vel]; `preint::ResidualMode` docs).
//!
//! Fixtures: `tests/fixtures/gtsam/*.gtsam.json` with their `*.params.json` (states, bias).
//! The `factor_*` ones are ComponentWise variants; regenerate with
//! `python gtsam_preint.py X.csv factor_X.params.json --out factor_X.gtsam.json`
//! from `tests/fixtures/gtsam/` (see `factor_README.md` there).

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3};
use preint::edges::EdgeNoise;
use preint::{
    BiasJacobians, Cov9, Cov15, ImuBias, ImuFactor, Level, NavState, PreintegratedImu,
    ResidualMode, predict,
};
use preint_lie::{SO3, hat, jl_inv};
use std::path::PathBuf;

// ------------------------------------------------------------------ minimal JSON reader
#[derive(Debug, Clone)]
enum J {
    Num(f64),
    Str(String),
    Arr(Vec<J>),
    Obj(Vec<(String, J)>),
    Lit,
}

struct P<'a> {
    s: &'a [u8],
    i: usize,
}

impl P<'_> {
    fn ws(&mut self) {
        while self.i < self.s.len() && (self.s[self.i] as char).is_ascii_whitespace() {
            self.i += 1;
        }
    }
    fn val(&mut self) -> J {
        self.ws();
        match self.s[self.i] {
            b'{' => {
                self.i += 1;
                let mut v = Vec::new();
                loop {
                    self.ws();
                    if self.s[self.i] == b'}' {
                        self.i += 1;
                        break;
                    }
                    let J::Str(k) = self.val() else { panic!("key") };
                    self.ws();
                    assert_eq!(self.s[self.i], b':');
                    self.i += 1;
                    v.push((k, self.val()));
                    self.ws();
                    if self.s[self.i] == b',' {
                        self.i += 1;
                    }
                }
                J::Obj(v)
            }
            b'[' => {
                self.i += 1;
                let mut v = Vec::new();
                loop {
                    self.ws();
                    if self.s[self.i] == b']' {
                        self.i += 1;
                        break;
                    }
                    v.push(self.val());
                    self.ws();
                    if self.s[self.i] == b',' {
                        self.i += 1;
                    }
                }
                J::Arr(v)
            }
            b'"' => {
                self.i += 1;
                let st = self.i;
                while self.s[self.i] != b'"' {
                    self.i += if self.s[self.i] == b'\\' { 2 } else { 1 };
                }
                self.i += 1;
                J::Str(String::from_utf8_lossy(&self.s[st..self.i - 1]).into_owned())
            }
            b't' | b'f' | b'n' => {
                while self.i < self.s.len() && (self.s[self.i] as char).is_ascii_alphabetic() {
                    self.i += 1;
                }
                J::Lit
            }
            _ => {
                let st = self.i;
                while self.i < self.s.len() && b"+-0123456789.eE".contains(&self.s[self.i]) {
                    self.i += 1;
                }
                let t = std::str::from_utf8(&self.s[st..self.i]).unwrap();
                J::Num(t.parse().unwrap_or_else(|_| panic!("number {t}")))
            }
        }
    }
}

impl J {
    fn get(&self, k: &str) -> Option<&J> {
        match self {
            J::Obj(v) => v.iter().find(|(kk, _)| kk == k).map(|(_, x)| x),
            _ => None,
        }
    }
    fn at(&self, k: &str) -> &J {
        self.get(k).unwrap_or_else(|| panic!("missing key {k}"))
    }
    fn num(&self) -> f64 {
        match self {
            J::Num(x) => *x,
            _ => panic!("not a number: {self:?}"),
        }
    }
    fn vec(&self) -> Vec<f64> {
        match self {
            J::Arr(v) => v.iter().map(J::num).collect(),
            _ => panic!("not an array"),
        }
    }
    fn v3(&self) -> Vector3<f64> {
        Vector3::from_column_slice(&self.vec())
    }
    fn mat(&self) -> DMatrix<f64> {
        let J::Arr(rows) = self else {
            panic!("not a matrix")
        };
        let rows: Vec<Vec<f64>> = rows.iter().map(J::vec).collect();
        DMatrix::from_fn(rows.len(), rows[0].len(), |r, c| rows[r][c])
    }
    fn m3(&self) -> Matrix3<f64> {
        let m = self.mat();
        Matrix3::from_fn(|r, c| m[(r, c)])
    }
}

fn load(path: &PathBuf) -> J {
    let s = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    P { s: &s, i: 0 }.val()
}

// ------------------------------------------------------------------ fixture → our types
fn fixture_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/gtsam")
}

struct Case {
    name: String,
    mode: String,
    pim: PreintegratedImu,
    xi: NavState,
    xj: NavState,
    bias_i: ImuBias,
    out: J,
}

fn state(s: &J) -> NavState {
    let r = if let Some(m) = s.get("R") {
        SO3::from_matrix(&m.m3())
    } else {
        let q = s.at("q_wxyz").vec();
        SO3::from_wxyz(q[0], q[1], q[2], q[3]).expect("unit quaternion")
    };
    NavState::new(r, s.at("p").v3(), s.at("v").v3())
}

fn bias(b: &J) -> ImuBias {
    ImuBias::new(b.at("bg").v3(), b.at("ba").v3())
}

fn load_case(name: &str) -> Case {
    let dir = fixture_dir();
    let out = load(&dir.join(format!("{name}.gtsam.json")));
    let params = load(&dir.join(format!("{name}.params.json")));
    let zero = || Vector3::zeros();
    let bias_hat = ImuBias::new(
        params.get("bg").map_or_else(zero, J::v3),
        params.get("ba").map_or_else(zero, J::v3),
    );
    // Covariance: GTSAM Forster chart, order [φ, p, v] → ours [φ, v, p].
    let perm = [0, 1, 2, 6, 7, 8, 3, 4, 5];
    let c = out.at("covariance").mat();
    let cov = Cov9::from_fn(|r, col| c[(perm[r], perm[col])]);
    let bj = out.at("bias_jacobians");
    let delta_t = out.at("delta_t").num();
    let pim = PreintegratedImu {
        t_i_ns: 0,
        t_j_ns: (delta_t * 1e9).round() as i64,
        delta_t,
        delta_r: SO3::from_matrix(&out.at("delta_R").m3()),
        delta_v: out.at("delta_v").v3(),
        delta_p: out.at("delta_p").v3(),
        cov,
        cov15: Cov15::identity(),
        jac: BiasJacobians {
            d_r_d_bg: bj.at("dR_dbg").m3(),
            d_v_d_bg: bj.at("dv_dbg").m3(),
            d_v_d_ba: bj.at("dv_dba").m3(),
            d_p_d_bg: bj.at("dp_dbg").m3(),
            d_p_d_ba: bj.at("dp_dba").m3(),
        },
        jac_td: Default::default(),
        bias_hat,
        gravity: out.at("n_gravity").v3(),
        omega_coriolis: None,
        coriolis: preint::CoriolisMode::Exact,
        level: Level::Covariance,
        edge_noise: EdgeNoise::default(),
        bias_correction: preint::BiasCorrection::Additive,
    };
    let f = params.at("factor");
    Case {
        name: name.to_string(),
        mode: match out.at("factor").at("error_mode") {
            J::Str(s) => s.clone(),
            _ => panic!(),
        },
        pim,
        xi: state(f.at("state_i")),
        xj: state(f.at("state_j")),
        bias_i: f.get("bias_i").map_or(bias_hat, bias),
        out,
    }
}

fn all_cases() -> Vec<Case> {
    let mut names: Vec<String> = std::fs::read_dir(fixture_dir())
        .expect("fixture dir")
        .filter_map(|e| {
            let n = e.ok()?.file_name().into_string().ok()?;
            n.strip_suffix(".gtsam.json").map(str::to_string)
        })
        // The combined, body_P_sensor, Earth-rotation and Galilean fixtures have their own
        // formats and tests (`combined_gtsam.rs`, `body_p_sensor_gtsam.rs`, `earth_gtsam.rs`,
        // `galilean_gtsam.rs`).
        .filter(|n| {
            !n.starts_with("combined_")
                && !n.starts_with("body_p_sensor_")
                && !n.starts_with("earth_")
                && !n.starts_with("galilean_")
        })
        .collect();
    names.sort();
    names
        .iter()
        .map(|n| load_case(n))
        .filter(|c| c.out.get("factor").is_some())
        .collect()
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

fn blk<const R: usize, const C: usize>(m: &DMatrix<f64>, r: usize, c: usize) -> SMatrix<f64, R, C> {
    SMatrix::<f64, R, C>::from_fn(|i, j| m[(r + i, c + j)])
}

// ------------------------------------------------------------------ tests
#[test]
fn fixtures_present() {
    let cases = all_cases();
    let cw = cases.iter().filter(|c| c.mode == "ComponentWise").count();
    let lm = cases.iter().filter(|c| c.mode == "Logmap").count();
    assert!(
        cw >= 2 && lm >= 3,
        "ComponentWise {cw}, Logmap {lm} factor fixtures"
    );
}

#[test]
fn prediction_matches_gtsam() {
    for c in all_cases() {
        let p = c.out.at("factor").at("predicted_state_j");
        let ours = predict(&c.pim, &c.xi, &c.bias_i);
        let rg = SO3::from_matrix(&p.at("R").m3());
        assert!(ours.r.minus(&rg).norm() < 1e-12, "{}: R", c.name);
        for k in 0..3 {
            assert!(close(ours.p[k], p.at("p").vec()[k], 1e-12), "{}: p", c.name);
            assert!(close(ours.v[k], p.at("v").vec()[k], 1e-12), "{}: v", c.name);
        }
    }
}

#[test]
fn residual_matches_gtsam_in_both_error_modes() {
    for c in all_cases() {
        let f = ImuFactor::with_mode(c.pim.clone(), ResidualMode::ComponentWise).unwrap();
        let r = f.residual(&c.xi, &c.xj, &c.bias_i);
        let (rphi, rv, rp) = (
            r.fixed_rows::<3>(0).into_owned(),
            r.fixed_rows::<3>(3).into_owned(),
            r.fixed_rows::<3>(6).into_owned(),
        );
        let m = c.xj.r.inverse().compose(&c.xi.r);
        let (mut e_pos, mut e_vel) = (-m.act(&rp), -m.act(&rv));
        if c.mode == "Logmap" {
            let jli = jl_inv(&(-rphi));
            e_pos = jli * e_pos;
            e_vel = jli * e_vel;
        }
        let mapped: Vec<f64> = (-rphi)
            .iter()
            .chain(e_pos.iter())
            .chain(e_vel.iter())
            .copied()
            .collect();
        let e = c.out.at("factor").at("residual").vec();
        for k in 0..9 {
            assert!(
                (mapped[k] - e[k]).abs() < 1e-10 * (1.0 + e[k].abs()),
                "{} ({}): e[{k}] ours {:e} gtsam {:e}",
                c.name,
                c.mode,
                mapped[k],
                e[k]
            );
        }
        assert!(
            r.amax() > 1e-4,
            "{}: a non-trivial residual is tested",
            c.name
        );
    }
}

#[test]
fn jacobians_match_gtsam_componentwise() {
    let mut n = 0;
    for c in all_cases()
        .into_iter()
        .filter(|c| c.mode == "ComponentWise")
    {
        n += 1;
        let f = ImuFactor::with_mode(c.pim.clone(), ResidualMode::ComponentWise).unwrap();
        let (r, j) = f.evaluate(&c.xi, &c.xj, &c.bias_i);
        let m = *c.xj.r.inverse().compose(&c.xi.r).matrix();
        let rv = r.fixed_rows::<3>(3).into_owned();
        let rp = r.fixed_rows::<3>(6).into_owned();
        // Our 9×3 block (rows [φ, v, p]) → GTSAM rows [rot, pos, vel].
        let map = |b: &SMatrix<f64, 9, 3>| {
            let mut o = SMatrix::<f64, 9, 3>::zeros();
            o.fixed_rows_mut::<3>(0).copy_from(&(-b.fixed_rows::<3>(0)));
            o.fixed_rows_mut::<3>(3)
                .copy_from(&(-m * b.fixed_rows::<3>(6)));
            o.fixed_rows_mut::<3>(6)
                .copy_from(&(-m * b.fixed_rows::<3>(3)));
            o
        };
        let mut phi_i = map(&j.phi_i);
        {
            let mut v = phi_i.fixed_rows_mut::<3>(3);
            v += m * hat(&rp);
        }
        {
            let mut v = phi_i.fixed_rows_mut::<3>(6);
            v += m * hat(&rv);
        }
        let mut phi_j = map(&j.phi_j);
        {
            let mut v = phi_j.fixed_rows_mut::<3>(3);
            v += -hat(&(m * rp));
        }
        {
            let mut v = phi_j.fixed_rows_mut::<3>(6);
            v += -hat(&(m * rv));
        }

        let fac = c.out.at("factor");
        let (hpi, hvi, hpj, hvj, hb) = (
            fac.at("H_pose_i").mat(),
            fac.at("H_vel_i").mat(),
            fac.at("H_pose_j").mat(),
            fac.at("H_vel_j").mat(),
            fac.at("H_bias_i").mat(),
        );
        let pairs: [(&str, SMatrix<f64, 9, 3>, SMatrix<f64, 9, 3>); 8] = [
            ("phi_i", phi_i, blk(&hpi, 0, 0)),
            ("p_i", map(&j.p_i), blk(&hpi, 0, 3)),
            ("v_i", map(&j.v_i), blk(&hvi, 0, 0)),
            ("phi_j", phi_j, blk(&hpj, 0, 0)),
            ("p_j", map(&j.p_j), blk(&hpj, 0, 3)),
            ("v_j", map(&j.v_j), blk(&hvj, 0, 0)),
            ("ba_i", map(&j.ba_i), blk(&hb, 0, 0)),
            ("bg_i", map(&j.bg_i), blk(&hb, 0, 3)),
        ];
        for (name, ours, theirs) in pairs {
            let scale = 1.0 + theirs.amax();
            assert!(
                (ours - theirs).amax() < 1e-9 * scale,
                "{}: block {name}: ours {ours} gtsam {theirs}",
                c.name
            );
        }
    }
    assert!(n >= 2, "{n} ComponentWise fixtures");
}

#[test]
fn chi2_matches_gtsam_after_frame_change() {
    // GTSAM weights e with its native covariance (p, v errors in the ΔR-rotated frame):
    // chi2_gtsam = r'ᵀ Σ⁻¹ r' with r' = [r_φ, ΔR M r_v, ΔR M r_p] (M = R_jᵀR_i; ΔR the
    // uncorrected delta). Ours uses r directly; the two agree to first order in the residual
    // rotation, exactly after this change of frame.
    for c in all_cases()
        .into_iter()
        .filter(|c| c.mode == "ComponentWise")
    {
        let f = ImuFactor::with_mode(c.pim.clone(), ResidualMode::ComponentWise).unwrap();
        let r = f.residual(&c.xi, &c.xj, &c.bias_i);
        let t = c.pim.delta_r.matrix() * c.xj.r.inverse().compose(&c.xi.r).matrix();
        let mut r2 = r;
        r2.fixed_rows_mut::<3>(3)
            .copy_from(&(t * r.fixed_rows::<3>(3)));
        r2.fixed_rows_mut::<3>(6)
            .copy_from(&(t * r.fixed_rows::<3>(6)));
        let chi2_g = c.out.at("factor").at("chi2").num();
        let ours = (f.sqrt_information() * r2).norm_squared();
        assert!(close(ours, chi2_g, 1e-8), "{}: {ours} vs {chi2_g}", c.name);
        let plain: f64 = f.chi2(&c.xi, &c.xj, &c.bias_i);
        let rel = (plain - chi2_g).abs() / chi2_g;
        eprintln!(
            "{}: chi2 ours {plain:.6e}, gtsam {chi2_g:.6e}, rel diff {rel:.2e}",
            c.name
        );
    }
}

#[test]
fn whitened_residual_norm_is_chi2() {
    for c in all_cases() {
        let f = ImuFactor::with_mode(c.pim.clone(), ResidualMode::ComponentWise).unwrap();
        let (rw, _) = f.evaluate_whitened(&c.xi, &c.xj, &c.bias_i);
        let r: SVector<f64, 9> = f.residual(&c.xi, &c.xj, &c.bias_i);
        let chi2_ref = r.dot(&c.pim.cov.lu().solve(&r).unwrap());
        assert!(close(rw.norm_squared(), chi2_ref, 1e-7), "{}", c.name);
    }
}

/// Our 9×3 block (rows [φ, v, p]) as GTSAM's Logmap rows [rot, pos, vel]: `−P b`.
fn minus_p(b: &SMatrix<f64, 9, 3>) -> SMatrix<f64, 9, 3> {
    let mut o = SMatrix::<f64, 9, 3>::zeros();
    o.fixed_rows_mut::<3>(0).copy_from(&(-b.fixed_rows::<3>(0)));
    o.fixed_rows_mut::<3>(3).copy_from(&(-b.fixed_rows::<3>(6)));
    o.fixed_rows_mut::<3>(6).copy_from(&(-b.fixed_rows::<3>(3)));
    o
}

#[test]
fn logmap_mode_residual_and_jacobians_match_gtsam_logmap() {
    let mut n = 0;
    for c in all_cases().into_iter().filter(|c| c.mode == "Logmap") {
        n += 1;
        let f = ImuFactor::with_mode(c.pim.clone(), ResidualMode::Logmap).unwrap();
        let (r, j) = f.evaluate(&c.xi, &c.xj, &c.bias_i);
        let fac = c.out.at("factor");
        let e = fac.at("residual").vec();
        let mapped = minus_p(&SMatrix::<f64, 9, 3>::from_fn(|row, col| {
            if col == 0 { r[row] } else { 0.0 }
        }));
        let mut worst = 0.0f64;
        for k in 0..9 {
            let d = (mapped[(k, 0)] - e[k]).abs() / (1.0 + e[k].abs());
            worst = worst.max(d);
            assert!(
                d < 1e-9,
                "{}: e[{k}] ours {:e} gtsam {:e}",
                c.name,
                mapped[(k, 0)],
                e[k]
            );
        }
        let (hpi, hvi, hpj, hvj, hb) = (
            fac.at("H_pose_i").mat(),
            fac.at("H_vel_i").mat(),
            fac.at("H_pose_j").mat(),
            fac.at("H_vel_j").mat(),
            fac.at("H_bias_i").mat(),
        );
        let pairs: [(&str, SMatrix<f64, 9, 3>, SMatrix<f64, 9, 3>); 8] = [
            ("phi_i", j.phi_i, blk(&hpi, 0, 0)),
            ("p_i", j.p_i, blk(&hpi, 0, 3)),
            ("v_i", j.v_i, blk(&hvi, 0, 0)),
            ("phi_j", j.phi_j, blk(&hpj, 0, 0)),
            ("p_j", j.p_j, blk(&hpj, 0, 3)),
            ("v_j", j.v_j, blk(&hvj, 0, 0)),
            ("ba_i", j.ba_i, blk(&hb, 0, 0)),
            ("bg_i", j.bg_i, blk(&hb, 0, 3)),
        ];
        let mut worst_j = 0.0f64;
        for (name, ours, theirs) in pairs {
            let d = (minus_p(&ours) - theirs).amax() / (1.0 + theirs.amax());
            worst_j = worst_j.max(d);
            assert!(
                d < 1e-9,
                "{}: block {name}: ours {} gtsam {theirs}",
                c.name,
                minus_p(&ours)
            );
        }
        // GTSAM weights with residualCovariance(), its ΔRᵀ-rotated chart: the same χ² exactly.
        let (ours, theirs) = (f.chi2(&c.xi, &c.xj, &c.bias_i), fac.at("chi2").num());
        assert!(
            close(ours, theirs, 1e-8),
            "{}: χ² {ours} vs {theirs}",
            c.name
        );
        eprintln!(
            "{}: Logmap residual worst {worst:.1e}, Jacobians worst {worst_j:.1e}, χ² {ours:.6e} vs {theirs:.6e}",
            c.name
        );
        assert!(
            r.fixed_rows::<6>(3).amax() > 1e-4,
            "{}: non-trivial",
            c.name
        );
    }
    assert!(n >= 5, "{n} Logmap fixtures");
}
