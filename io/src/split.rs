//! Split recordings: a gyroscope stream and an accelerometer stream with their own timestamps
//! (RealSense: gyro at 200 Hz, accelerometer at 63 Hz), merged into IMU samples.
//!
//! # Model (`docs/SPLIT_STREAMS.md`, equation numbers there)
//!
//! - **Stamps.** One merged sample per gyro sample, at the gyro stamp, with the gyro reading
//!   unchanged: the rotation drives the attitude error, and resampling the gyro would add
//!   its interpolation error to every delta. A gyro sample is merged when two accelerometer
//!   samples are at or before it and two after it (`t_{j−1} < t_j ≤ t < t_{j+1} < t_{j+2}`);
//!   the others, at the ends, are dropped and counted ([`MergeReport::dropped_before`],
//!   [`MergeReport::dropped_after`]). No gyro stamp inside the accelerometer span is an error.
//! - **Accelerometer.** Cubic Hermite interpolation with finite-difference tangents (eq. 1;
//!   Catmull–Rom for uniform stamps, [`hermite_weights`]): exact for quadratic signals, so the
//!   curvature error of linear interpolation, `−λ(1−λ) h_a²/2 · ä` (eq. 2), which has a
//!   non-zero mean and biases Δv, is gone; what remains is `(h_a³/6) λ(1−λ)(1−2λ) a⃛`, zero
//!   mean over λ.
//! - **Noise.** The resampled white noise is correlated between gyro samples and its
//!   per-sample variance is not `σ_a²/h_g`, but what the preintegrator needs is the
//!   covariance of its integrals: every accelerometer sample enters Δv with weight `W_j`
//!   (eq. 3), and `Σ_j W_j²/c_j` against `T` gives the ratio ρ (eq. 4), accumulated during the
//!   merge. The density to preintegrate with is `σ_a,eff² = ρ σ_a² + q_int` (eq. 8), with
//!   `q_int` the interpolation error estimated from the third differences (eq. 6–7):
//!   [`effective_noise`].
//!
//! Memory is bounded: four accelerometer samples and a few weights are held, whatever the
//! length of the files. Each channel is checked as it is read (finite readings, strictly
//! increasing stamps), errors naming its file and line.

mod model;
mod text_channel;

use model::WeightAccumulator;
pub use model::{
    MAX_RATE_WINDOW_SAMPLES, MergeReport, effective_noise, effective_noise_for_rates,
    hermite_weights, interpolation_psd, white_ratio_for_rates,
};
pub use text_channel::{ChannelLayout, detect_channel};

use crate::channel::{ChannelSample, ChannelStream, Sensor};
use crate::error::{IoError, Location};
use crate::lines::LineReader;
use crate::reader::{ImuReader, Located, Progress, ReadOptions, SourceInfo};
use nalgebra::Vector3;
use preint::ImuSample;
use std::collections::VecDeque;
use std::fs::File;
use std::path::Path;
use std::sync::atomic::AtomicU64;
use std::sync::{Arc, Mutex};
use text_channel::TextChannel;

/// Number of lines read to decide a channel file's layout.
const HEAD_LINES: usize = 32;

/// A channel file opened for reading: its samples, layout and byte progress.
struct OpenedChannel {
    stream: ChannelStream,
    layout: ChannelLayout,
    progress: Progress,
}

fn open_channel_file(
    path: &Path,
    sensor: Sensor,
    opts: &ReadOptions,
) -> Result<OpenedChannel, IoError> {
    let name = path.display().to_string();
    let open = || File::open(path).map_err(|e| IoError::file(path, e));
    let mut lines = LineReader::new(open()?, &name);
    let mut head = Vec::new();
    while head.len() < HEAD_LINES {
        match lines.next_line()? {
            Some(l) => head.push(l.text.to_string()),
            None => break,
        }
    }
    let layout = detect_channel(&head, opts, &name, sensor)?;
    let file = open()?;
    let total = file.metadata().map(|m| m.len()).unwrap_or(0);
    let lines = LineReader::new(file, &name);
    let progress = Progress::new(lines.progress(), total);
    let stream = Box::new(TextChannel::new(lines, layout.clone(), sensor));
    Ok(OpenedChannel {
        stream,
        layout,
        progress,
    })
}

/// The readings of one sensor from a text file `path`: rows `t, x, y, z` (comma, semicolon,
/// tab or whitespace separated; an optional header row; `#`/`%` comments). Time unit from
/// `--time-unit`, the header (`t_s`, `timestamp [ns]`) or integer ns since an epoch; value
/// unit from `--gyro-unit` (gyro file) or `--accel-unit` (accelerometer file), else the
/// header, else SI ([`detect_channel`]). Errors name the file and line.
pub fn open_text_channel(
    path: &Path,
    sensor: Sensor,
    opts: &ReadOptions,
) -> Result<ChannelStream, IoError> {
    Ok(open_channel_file(path, sensor, opts)?.stream)
}

/// The report of a merge, readable while and after the merged stream is consumed (complete
/// once the stream has ended).
#[derive(Clone, Debug, Default)]
pub struct MergeHandle(Arc<Mutex<MergeReport>>);

impl MergeHandle {
    /// The counts and statistics so far ([`MergeReport`]).
    pub fn report(&self) -> MergeReport {
        self.0.lock().map(|r| r.clone()).unwrap_or_default()
    }
}

/// IMU samples from a gyroscope stream and an accelerometer stream (see the module docs).
pub fn merge(
    gyro: ChannelStream,
    accel: ChannelStream,
    info: SourceInfo,
    opts: &ReadOptions,
) -> Result<ImuReader, IoError> {
    merge_with_report(gyro, accel, info, opts).map(|(r, _)| r)
}

/// As [`merge`], also returning the handle of its [`MergeReport`] (for [`effective_noise`]).
/// The channels' file names are the two parts of `info.source_name` written `gyro + accel`
/// (else the whole name labels both).
pub fn merge_with_report(
    gyro: ChannelStream,
    accel: ChannelStream,
    info: SourceInfo,
    opts: &ReadOptions,
) -> Result<(ImuReader, MergeHandle), IoError> {
    let progress = Progress::new(Arc::new(AtomicU64::new(0)), 0);
    merged(gyro, accel, info, progress, opts)
}

fn merged(
    gyro: ChannelStream,
    accel: ChannelStream,
    mut info: SourceInfo,
    progress: Progress,
    opts: &ReadOptions,
) -> Result<(ImuReader, MergeHandle), IoError> {
    let (gname, aname) = match info.source_name.split_once(" + ") {
        Some((g, a)) => (g.to_string(), a.to_string()),
        None => (info.source_name.clone(), info.source_name.clone()),
    };
    info.notes.push(
        "merged at the gyro stamps; accelerometer by cubic Hermite interpolation; preintegrate \
         with the effective accelerometer density (docs/SPLIT_STREAMS.md)"
            .to_string(),
    );
    let handle = MergeHandle::default();
    let merger = Merger {
        gyro: Checked::new(gyro, gname, Sensor::Gyro),
        accel: Checked::new(accel, aname, Sensor::Accel),
        win: VecDeque::with_capacity(4),
        next_index: 0,
        last4: [Vector3::zeros(); 4],
        acc: WeightAccumulator::default(),
        report: MergeReport::default(),
        shared: handle.clone(),
        accel_ended: false,
        done: false,
    };
    let reader = ImuReader::from_source(Box::new(merger), info, progress, opts.max_samples);
    Ok((reader, handle))
}

/// IMU samples from a gyroscope file and an accelerometer file.
pub fn open_split(gyro: &Path, accel: &Path, opts: &ReadOptions) -> Result<ImuReader, IoError> {
    open_split_with_report(gyro, accel, opts).map(|(r, _)| r)
}

/// As [`open_split`], also returning the handle of its [`MergeReport`].
pub fn open_split_with_report(
    gyro: &Path,
    accel: &Path,
    opts: &ReadOptions,
) -> Result<(ImuReader, MergeHandle), IoError> {
    let g = open_channel_file(gyro, Sensor::Gyro, opts)?;
    let a = open_channel_file(accel, Sensor::Accel, opts)?;
    let mut notes = g.layout.notes.clone();
    notes.extend(a.layout.notes.iter().cloned());
    let info = SourceInfo {
        source_name: format!("{} + {}", gyro.display(), accel.display()),
        format: crate::Format::Delimited,
        layout: None,
        units: crate::Units {
            time: g.layout.time,
            gyro: g.layout.gyro,
            accel: a.layout.accel,
        },
        notes,
        warnings: Vec::new(),
    };
    merged(g.stream, a.stream, info, g.progress, opts)
}

/// A channel checked as it is read: finite readings, strictly increasing stamps.
struct Checked {
    inner: ChannelStream,
    name: String,
    sensor: Sensor,
    prev: Option<(i64, Location)>,
}

impl Checked {
    fn new(inner: ChannelStream, name: String, sensor: Sensor) -> Self {
        Self {
            inner,
            name,
            sensor,
            prev: None,
        }
    }

    fn next(&mut self) -> Result<Option<ChannelSample>, IoError> {
        let Some(s) = self.inner.next().transpose()? else {
            return Ok(None);
        };
        let err = |m: String| IoError::parse(&self.name, s.at, m);
        if !s.value.iter().all(|x| x.is_finite()) {
            return Err(err(format!("a {} reading is not finite", self.sensor)));
        }
        if let Some((tp, at)) = self.prev {
            if s.t_ns == tp {
                return Err(err(format!(
                    "duplicate {} timestamp {} ns (same as {at})",
                    self.sensor, s.t_ns
                )));
            }
            if s.t_ns < tp {
                return Err(err(format!(
                    "{} timestamp {} ns decreases ({at} has {tp} ns)",
                    self.sensor, s.t_ns
                )));
            }
        }
        self.prev = Some((s.t_ns, s.at));
        Ok(Some(s))
    }
}

/// The merging iterator (see the module docs).
struct Merger {
    gyro: Checked,
    accel: Checked,
    /// Accelerometer samples `j−1 … j+2` with their indices.
    win: VecDeque<(i64, ChannelSample)>,
    next_index: i64,
    /// The last four accelerometer readings, for the third differences.
    last4: [Vector3<f64>; 4],
    acc: WeightAccumulator,
    report: MergeReport,
    shared: MergeHandle,
    accel_ended: bool,
    done: bool,
}

impl Merger {
    fn pull_accel(&mut self) -> Result<Option<(i64, ChannelSample)>, IoError> {
        if self.accel_ended {
            return Ok(None);
        }
        let Some(a) = self.accel.next()? else {
            self.accel_ended = true;
            if self.report.accel_samples == 0 {
                return Err(IoError::Empty {
                    source_name: self.accel.name.clone(),
                });
            }
            return Ok(None);
        };
        let r = &mut self.report;
        if r.accel_samples == 0 {
            r.accel_span_ns.0 = a.t_ns;
        }
        r.accel_span_ns.1 = a.t_ns;
        r.accel_samples += 1;
        self.last4.rotate_left(1);
        self.last4[3] = a.value;
        if r.accel_samples >= 4 {
            let [a0, a1, a2, a3] = self.last4;
            r.third_diff_sq_sum += (a3 - 3.0 * a2 + 3.0 * a1 - a0).norm_squared();
            r.third_diffs += 1;
        }
        let i = self.next_index;
        self.next_index += 1;
        self.acc.see_accel(i, a.t_ns);
        Ok(Some((i, a)))
    }

    /// Moves the window until `win[2]` is after `t` (or the accelerometer ends).
    fn advance(&mut self, t: i64) -> Result<(), IoError> {
        loop {
            if self.win.len() == 4 {
                if self.win[2].1.t_ns > t {
                    return Ok(());
                }
                self.win.pop_front();
            }
            match self.pull_accel()? {
                Some(a) => self.win.push_back(a),
                None => return Ok(()),
            }
        }
    }

    /// The merged sample at gyro sample `g`, or `None` if it is dropped.
    fn merge_one(&mut self, g: &ChannelSample) -> Result<Option<Located>, IoError> {
        let t = g.t_ns;
        self.advance(t)?;
        let full = self.win.len() == 4;
        if full && self.win[1].1.t_ns > t {
            self.report.dropped_before += 1;
            return Ok(None);
        }
        if !full || self.win[2].1.t_ns <= t {
            self.report.dropped_after += 1;
            return Ok(None);
        }
        let ts = [0, 1, 2, 3].map(|k| self.win[k].1.t_ns);
        let w = hermite_weights(ts, t);
        let acc: Vector3<f64> = (0..4).map(|k| self.win[k].1.value * w[k]).sum();
        self.acc.add_gyro(t, self.win[0].0, &w);
        let r = &mut self.report;
        if r.merged == 0 {
            r.merged_span_ns.0 = t;
        }
        r.merged_span_ns.1 = t;
        r.merged += 1;
        r.white_weight_sq = self.acc.sum;
        Ok(Some(Located {
            at: g.at,
            sample: ImuSample::new(t, g.value, acc),
        }))
    }

    fn step(&mut self) -> Result<Option<Located>, IoError> {
        loop {
            let Some(g) = self.gyro.next()? else {
                return self.finish().map(|()| None);
            };
            let r = &mut self.report;
            if r.gyro_samples == 0 {
                r.gyro_span_ns.0 = g.t_ns;
            }
            r.gyro_span_ns.1 = g.t_ns;
            r.gyro_samples += 1;
            if let Some(s) = self.merge_one(&g)? {
                self.publish();
                return Ok(Some(s));
            }
        }
    }

    fn finish(&mut self) -> Result<(), IoError> {
        if self.report.gyro_samples == 0 {
            return Err(IoError::Empty {
                source_name: self.gyro.name.clone(),
            });
        }
        if self.report.accel_samples == 0 {
            self.pull_accel()?;
        }
        let acc = std::mem::take(&mut self.acc);
        self.report.white_weight_sq = acc.finish_seen();
        self.publish();
        let r = &self.report;
        if r.accel_samples < 4 {
            return Err(IoError::format(
                &self.accel.name,
                format!(
                    "{} accelerometer samples; the cubic interpolation needs at least four (two \
                     at or before a gyro stamp and two after it)",
                    r.accel_samples
                ),
            ));
        }
        if r.merged == 0 {
            return Err(IoError::format(
                &format!("{} + {}", self.gyro.name, self.accel.name),
                format!(
                    "no gyro stamp ({} samples, {} … {} ns) lies between the second and the \
                     second-to-last accelerometer stamp ({} samples, {} … {} ns): the files do \
                     not overlap in time",
                    r.gyro_samples,
                    r.gyro_span_ns.0,
                    r.gyro_span_ns.1,
                    r.accel_samples,
                    r.accel_span_ns.0,
                    r.accel_span_ns.1
                ),
            ));
        }
        Ok(())
    }

    fn publish(&self) {
        if let Ok(mut r) = self.shared.0.lock() {
            r.clone_from(&self.report);
        }
    }
}

impl Iterator for Merger {
    type Item = Result<Located, IoError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let item = self.step().transpose();
        self.done = !matches!(item, Some(Ok(_)));
        item
    }
}
