//! The pickle state of `Params` and `PreintegratedImu`: every field as little-endian bytes, so
//! that a round trip is exact to the bit.

use crate::errors::shape_err;
use nalgebra::{Matrix3, SMatrix, Vector3};
use preint::edges::EdgeNoise;
use preint::edges::EdgeSource;
use preint::lie::SO3;
use preint::{
    BiasCorrection, BiasJacobians, CellRule, CoriolisMode, ImuBias, Level, LeverArm, PreintParams,
    PreintegratedImu, Scheme, SensorPose,
};
use pyo3::PyResult;

/// Format version written first.
const VERSION: u8 = 3;

#[derive(Default)]
struct Writer(Vec<u8>);

impl Writer {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn i64(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn mat<const R: usize, const C: usize>(&mut self, m: &SMatrix<f64, R, C>) {
        m.iter().for_each(|&x| self.f64(x));
    }
    fn opt_mat<const R: usize, const C: usize>(&mut self, m: &Option<SMatrix<f64, R, C>>) {
        match m {
            Some(m) => {
                self.u8(1);
                self.mat(m);
            }
            None => self.u8(0),
        }
    }
}

struct Reader<'a>(&'a [u8]);

fn truncated() -> pyo3::PyErr {
    shape_err("pickle state: truncated or not written by this version of preint")
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> PyResult<[u8; N]> {
        if self.0.len() < N {
            return Err(truncated());
        }
        let (a, b) = self.0.split_at(N);
        self.0 = b;
        Ok(a.try_into().expect("length checked"))
    }
    fn u8(&mut self) -> PyResult<u8> {
        Ok(self.take::<1>()?[0])
    }
    fn i64(&mut self) -> PyResult<i64> {
        Ok(i64::from_le_bytes(self.take()?))
    }
    fn f64(&mut self) -> PyResult<f64> {
        Ok(f64::from_le_bytes(self.take()?))
    }
    fn mat<const R: usize, const C: usize>(&mut self) -> PyResult<SMatrix<f64, R, C>> {
        let mut m = SMatrix::<f64, R, C>::zeros();
        for x in m.iter_mut() {
            *x = self.f64()?;
        }
        Ok(m)
    }
    fn opt_mat<const R: usize, const C: usize>(&mut self) -> PyResult<Option<SMatrix<f64, R, C>>> {
        match self.u8()? {
            0 => Ok(None),
            _ => Ok(Some(self.mat()?)),
        }
    }
    fn end(&self) -> PyResult<()> {
        if self.0.is_empty() {
            Ok(())
        } else {
            Err(truncated())
        }
    }
}

fn index_of<T: PartialEq + Copy>(all: &[T], v: T) -> u8 {
    all.iter().position(|&x| x == v).expect("listed") as u8
}

fn pick<T: Copy>(all: &[T], i: u8) -> PyResult<T> {
    all.get(i as usize).copied().ok_or_else(truncated)
}

const LEVELS: [Level; 3] = [Level::Deltas, Level::Covariance, Level::Combined];
const CORIOLIS: [CoriolisMode; 3] = [
    CoriolisMode::FirstOrder,
    CoriolisMode::SecondOrder,
    CoriolisMode::Exact,
];
const LEVERS: [LeverArm; 2] = [LeverArm::Exact, LeverArm::Centripetal];
const CELLS: [CellRule; 2] = [CellRule::Held, CellRule::Centered];
const CORRECTIONS: [BiasCorrection; 2] = BiasCorrection::ALL;

/// The bytes of `p`.
pub(crate) fn encode_params(p: &PreintParams) -> Vec<u8> {
    let mut w = Writer::default();
    w.u8(VERSION);
    w.mat(&p.gravity);
    w.mat(&p.gyro_cov);
    w.mat(&p.acc_cov);
    w.mat(&p.gyro_bias_rw_cov);
    w.mat(&p.acc_bias_rw_cov);
    w.opt_mat(&p.integration_cov);
    w.u8(index_of(Scheme::ALL, p.scheme));
    w.u8(index_of(&LEVELS, p.level));
    w.f64(p.reintegrate_gyro_threshold);
    w.f64(p.reintegrate_acc_threshold);
    w.i64(p.max_gap_ns);
    w.u8(p.keep_samples as u8);
    w.opt_mat(&p.body_p_sensor.map(|s| *s.rotation.matrix()));
    w.mat(
        &p.body_p_sensor
            .map(|s| s.translation)
            .unwrap_or_else(Vector3::zeros),
    );
    w.u8(index_of(&LEVERS, p.lever_arm));
    w.opt_mat(&p.omega_coriolis);
    w.u8(index_of(&CORIOLIS, p.coriolis));
    // 0 = None (the scheme's default), 1 + index otherwise.
    w.u8(p
        .bias_correction
        .map_or(0, |c| 1 + index_of(&CORRECTIONS, c)));
    w.f64(p.reintegrate_time_offset_threshold);
    w.0
}

/// The parameters written by [`encode_params`].
pub(crate) fn decode_params(b: &[u8]) -> PyResult<PreintParams> {
    let mut r = Reader(b);
    if r.u8()? != VERSION {
        return Err(truncated());
    }
    let gravity = r.mat()?;
    let gyro_cov = r.mat()?;
    let acc_cov = r.mat()?;
    let gyro_bias_rw_cov = r.mat()?;
    let acc_bias_rw_cov = r.mat()?;
    let integration_cov = r.opt_mat()?;
    let scheme = pick(Scheme::ALL, r.u8()?)?;
    let level = pick(&LEVELS, r.u8()?)?;
    let reintegrate_gyro_threshold = r.f64()?;
    let reintegrate_acc_threshold = r.f64()?;
    let max_gap_ns = r.i64()?;
    let keep_samples = r.u8()? != 0;
    let rot: Option<Matrix3<f64>> = r.opt_mat()?;
    let t: Vector3<f64> = r.mat()?;
    let body_p_sensor = rot.map(|m| SensorPose::new(SO3::from_matrix_unchecked(m), t));
    let lever_arm = pick(&LEVERS, r.u8()?)?;
    let omega_coriolis = r.opt_mat()?;
    let coriolis = pick(&CORIOLIS, r.u8()?)?;
    let bias_correction = match r.u8()? {
        0 => None,
        i => Some(pick(&CORRECTIONS, i - 1)?),
    };
    let reintegrate_time_offset_threshold = r.f64()?;
    let p = PreintParams {
        gravity,
        gyro_cov,
        acc_cov,
        gyro_bias_rw_cov,
        acc_bias_rw_cov,
        integration_cov,
        scheme,
        level,
        reintegrate_gyro_threshold,
        reintegrate_acc_threshold,
        max_gap_ns,
        keep_samples,
        body_p_sensor,
        lever_arm,
        omega_coriolis,
        coriolis,
        bias_correction,
        intrinsics: None,
        reintegrate_time_offset_threshold,
    };
    r.end()?;
    Ok(p)
}

/// The bytes of `m`.
pub(crate) fn encode_measurement(m: &PreintegratedImu) -> Vec<u8> {
    let mut w = Writer::default();
    w.u8(VERSION);
    w.i64(m.t_i_ns);
    w.i64(m.t_j_ns);
    w.f64(m.delta_t);
    w.mat(m.delta_r.matrix());
    w.mat(&m.delta_v);
    w.mat(&m.delta_p);
    w.mat(&m.cov);
    w.mat(&m.cov15);
    w.mat(&m.jac.as_matrix());
    w.mat(&m.jac_td);
    w.mat(&m.bias_hat.gyro);
    w.mat(&m.bias_hat.acc);
    w.mat(&m.gravity);
    w.opt_mat(&m.omega_coriolis);
    w.u8(index_of(&CORIOLIS, m.coriolis));
    w.u8(index_of(&LEVELS, m.level));
    w.u8(index_of(&CORRECTIONS, m.bias_correction));
    let e = &m.edge_noise;
    w.mat(&e.gyro_cov);
    w.mat(&e.acc_cov);
    w.u8(index_of(&CELLS, e.cell_rule));
    w.u8(e.len() as u8);
    for s in e.sources() {
        w.i64(s.t_ns);
        w.mat(&s.gain);
        w.f64(s.left_s);
        w.f64(s.right_s);
        w.u8(s.start as u8);
        w.u8(s.end as u8);
    }
    w.0
}

/// The measurement written by [`encode_measurement`].
pub(crate) fn decode_measurement(b: &[u8]) -> PyResult<PreintegratedImu> {
    let mut r = Reader(b);
    if r.u8()? != VERSION {
        return Err(truncated());
    }
    let t_i_ns = r.i64()?;
    let t_j_ns = r.i64()?;
    let delta_t = r.f64()?;
    let delta_r = SO3::from_matrix_unchecked(r.mat()?);
    let delta_v = r.mat()?;
    let delta_p = r.mat()?;
    let cov = r.mat()?;
    let cov15 = r.mat()?;
    let jac = BiasJacobians::from_matrix(&r.mat()?);
    let jac_td = r.mat()?;
    let bias_hat = ImuBias::new(r.mat()?, r.mat()?);
    let gravity = r.mat()?;
    let omega_coriolis = r.opt_mat()?;
    let coriolis = pick(&CORIOLIS, r.u8()?)?;
    let level = pick(&LEVELS, r.u8()?)?;
    let bias_correction = pick(&CORRECTIONS, r.u8()?)?;
    let (gc, ac) = (r.mat()?, r.mat()?);
    let mut edge_noise = EdgeNoise::new(gc, ac, pick(&CELLS, r.u8()?)?);
    for _ in 0..r.u8()? {
        let s = EdgeSource {
            t_ns: r.i64()?,
            gain: r.mat()?,
            left_s: r.f64()?,
            right_s: r.f64()?,
            start: r.u8()? != 0,
            end: r.u8()? != 0,
        };
        if !edge_noise.push(s) {
            return Err(truncated());
        }
    }
    r.end()?;
    Ok(PreintegratedImu {
        t_i_ns,
        t_j_ns,
        delta_t,
        delta_r,
        delta_v,
        delta_p,
        cov,
        cov15,
        jac,
        jac_td,
        bias_hat,
        gravity,
        omega_coriolis,
        coriolis,
        level,
        edge_noise,
        bias_correction,
    })
}
