//! Container formats carrying `sensor_msgs/Imu`: ROS 1 bags (the `rosbag` crate), MCAP files
//! (the `mcap` crate; ROS 2's default storage, CDR messages, or ROS 1 messages in MCAP) and
//! ROS 2 `.db3` bags (SQLite, the `rusqlite` crate; CDR messages).
//!
//! The messages of the selected topic are streamed (memory does not grow with the file) and
//! decoded from their fixed field layout, bounds-checked. A sample's time is `header.stamp`
//! ([`Stamp::Header`], default) or the time the recorder received it ([`Stamp::Record`]: bag record time, MCAP log time); which one
//! is said in [`SourceInfo::notes`]. Errors name the file and the 1-based message of the topic
//! ([`Location::Message`]).

mod bag;
mod db3;
mod imu_msg;
mod mcap_file;
mod queue;

use crate::channel::{ChannelSample, ChannelStream, Sensor};
use crate::detect::Format;
use crate::error::{IoError, Location};
use crate::reader::{ImuReader, Located, Progress, ReadOptions, SourceInfo, Stamp};
use crate::units::Units;
use imu_msg::ImuMsg;
use nalgebra::Vector3;
use preint::ImuSample;
use std::path::Path;

/// Message type names of `sensor_msgs/Imu` (ROS 1 and ROS 2 spellings).
const IMU_TYPES: [&str; 2] = ["sensor_msgs/Imu", "sensor_msgs/msg/Imu"];

/// A topic of a container and the type of its messages.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Topic {
    /// Topic name, e.g. `/imu0`.
    pub name: String,
    /// Message type, e.g. `sensor_msgs/Imu`.
    pub type_name: String,
}

impl Topic {
    fn is_imu(&self) -> bool {
        IMU_TYPES.contains(&self.type_name.as_str())
    }
}

/// One message of the selected topic: record time \[ns\] and content, or what is wrong with it
/// (the caller adds the file and the message number).
pub(crate) type RawItem = Result<(u64, ImuMsg), String>;

/// The decoded messages of one topic, in file order, with a progress counter.
pub(crate) struct Messages {
    pub items: Box<dyn Iterator<Item = RawItem> + Send>,
    pub progress: Progress,
}

/// An opened container: its topics, and the messages of any of them.
enum Container {
    Bag(bag::Bag),
    Mcap(mcap_file::McapFile),
    Db3(db3::Db3),
}

impl Container {
    fn open(path: &Path, format: Format) -> Result<Self, IoError> {
        let name = path.display().to_string();
        match format {
            Format::RosBag => Ok(Container::Bag(bag::Bag::open(path)?)),
            Format::Mcap => Ok(Container::Mcap(mcap_file::McapFile::open(path)?)),
            Format::Db3 => Ok(Container::Db3(db3::Db3::open(path)?)),
            other => Err(IoError::format(
                &name,
                format!("{other} is not a container format (bag, mcap, db3)"),
            )),
        }
    }

    fn topics(&self) -> &[Topic] {
        match self {
            Container::Bag(b) => b.topics(),
            Container::Mcap(m) => m.topics(),
            Container::Db3(d) => d.topics(),
        }
    }

    fn messages(&self, topic: &str) -> Result<Messages, IoError> {
        match self {
            Container::Bag(b) => b.messages(topic),
            Container::Mcap(m) => m.messages(topic),
            Container::Db3(d) => d.messages(topic),
        }
    }
}

/// `topics` listed as `/a (type), /b (type)`.
fn list(topics: &[&Topic]) -> String {
    if topics.is_empty() {
        return "none".into();
    }
    let names: Vec<String> = topics
        .iter()
        .map(|t| format!("{} ({})", t.name, t.type_name))
        .collect();
    names.join(", ")
}

/// The `sensor_msgs/Imu` topic to read: `wanted`, or the file's only one (said in `notes`).
fn select_topic(
    name: &str,
    topics: &[Topic],
    wanted: Option<&str>,
    notes: &mut Vec<String>,
) -> Result<String, IoError> {
    let imu: Vec<&Topic> = topics.iter().filter(|t| t.is_imu()).collect();
    match wanted {
        Some(w) => match topics.iter().find(|t| t.name == w) {
            Some(t) if t.is_imu() => Ok(t.name.clone()),
            Some(t) => Err(IoError::format(
                name,
                format!(
                    "topic {w} carries {}, not sensor_msgs/Imu; sensor_msgs/Imu topics: {}",
                    t.type_name,
                    list(&imu)
                ),
            )),
            None => Err(IoError::format(
                name,
                format!("no topic {w}; sensor_msgs/Imu topics: {}", list(&imu)),
            )),
        },
        None => match imu.as_slice() {
            [only] => {
                notes.push(format!(
                    "topic {}: the only sensor_msgs/Imu topic (--topic selects another)",
                    only.name
                ));
                Ok(only.name.clone())
            }
            [] => {
                let all: Vec<&Topic> = topics.iter().collect();
                Err(IoError::format(
                    name,
                    format!("no sensor_msgs/Imu topic; topics: {}", list(&all)),
                ))
            }
            several => Err(IoError::format(
                name,
                format!(
                    "{} sensor_msgs/Imu topics: {}; choose one with --topic (or a gyro and an \
                     accelerometer topic with --gyro-topic and --accel-topic)",
                    several.len(),
                    list(several)
                ),
            )),
        },
    }
}

/// The note saying which stamp the samples carry.
fn stamp_note(stamp: Stamp) -> String {
    match stamp {
        Stamp::Header => "time stamps: header.stamp of each message (--stamp record for the \
                          time the recorder received it)"
            .into(),
        Stamp::Record => "time stamps: record time of each message (bag record time, MCAP log \
                          time, .db3 timestamp), not header.stamp"
            .into(),
    }
}

/// Numbers the messages, picks the stamp and names the file in errors.
struct Numbered {
    items: Box<dyn Iterator<Item = RawItem> + Send>,
    name: String,
    stamp: Stamp,
    n: u64,
}

impl Iterator for Numbered {
    type Item = Result<(Location, i64, ImuMsg), IoError>;

    fn next(&mut self) -> Option<Self::Item> {
        let item = self.items.next()?;
        self.n += 1;
        let at = Location::Message(self.n);
        Some(match item {
            Err(msg) => Err(IoError::parse(&self.name, at, msg)),
            Ok((record, m)) => match self.stamp {
                Stamp::Header => Ok((at, m.stamp_ns, m)),
                Stamp::Record => i64::try_from(record).map(|t| (at, t, m)).map_err(|_| {
                    IoError::parse(&self.name, at, format!("record time {record} ns overflows"))
                }),
            },
        })
    }
}

/// The numbered messages of the topic `opts.topic` selects, and how it was chosen.
fn open_numbered(
    path: &Path,
    format: Format,
    topic: Option<&str>,
    stamp: Stamp,
    notes: &mut Vec<String>,
) -> Result<(Numbered, Progress), IoError> {
    let name = path.display().to_string();
    let container = Container::open(path, format)?;
    let topic = select_topic(&name, container.topics(), topic, notes)?;
    let m = container.messages(&topic)?;
    let numbered = Numbered {
        items: m.items,
        name,
        stamp,
        n: 0,
    };
    Ok((numbered, m.progress))
}

/// Opens the container `path` of format `format`: the `sensor_msgs/Imu` messages of
/// `opts.topic`, or the gyro of `opts.gyro_topic` merged with the accelerometer of
/// `opts.accel_topic`.
pub fn open(path: &Path, format: Format, opts: &ReadOptions) -> Result<ImuReader, IoError> {
    let name = path.display().to_string();
    match (&opts.gyro_topic, &opts.accel_topic) {
        (Some(g), Some(a)) => return open_split(path, format, g, a, opts).map(|(r, _)| r),
        (Some(_), None) | (None, Some(_)) => {
            return Err(IoError::format(
                &name,
                "a split recording needs both --gyro-topic and --accel-topic",
            ));
        }
        (None, None) => {}
    }
    let mut notes = Vec::new();
    let (numbered, progress) =
        open_numbered(path, format, opts.topic.as_deref(), opts.stamp, &mut notes)?;
    notes.push(stamp_note(opts.stamp));
    let info = SourceInfo {
        source_name: name,
        format,
        layout: None,
        units: Units::SI_NS,
        notes,
        warnings: Vec::new(),
    };
    let samples = numbered.map(|r| {
        r.map(|(at, t_ns, m)| Located {
            at,
            sample: ImuSample::new(t_ns, Vector3::from(m.gyro), Vector3::from(m.accel)),
        })
    });
    Ok(ImuReader::from_source(
        Box::new(samples),
        info,
        progress,
        opts.max_samples,
    ))
}

/// The gyro of topic `gyro` merged with the accelerometer of topic `accel` ([`crate::split`]),
/// with the handle of the merge's report (for the effective accelerometer density).
pub fn open_split(
    path: &Path,
    format: Format,
    gyro: &str,
    accel: &str,
    opts: &ReadOptions,
) -> Result<(ImuReader, crate::split::MergeHandle), IoError> {
    let g = open_channel(path, format, gyro, Sensor::Gyro, opts)?;
    let a = open_channel(path, format, accel, Sensor::Accel, opts)?;
    let info = SourceInfo {
        source_name: path.display().to_string(),
        format,
        layout: None,
        units: Units::SI_NS,
        notes: vec![
            format!(
                "gyro: angular_velocity of {gyro}; accelerometer: linear_acceleration of {accel}"
            ),
            stamp_note(opts.stamp),
        ],
        warnings: Vec::new(),
    };
    crate::split::merge_with_report(g, a, info, opts)
}

/// The readings of one sensor (`sensor`) from the `sensor_msgs/Imu` messages of `topic`:
/// `angular_velocity` [rad/s] for [`Sensor::Gyro`], `linear_acceleration` [m/s²] for
/// [`Sensor::Accel`], stamped as `opts.stamp` says.
pub fn open_channel(
    path: &Path,
    format: Format,
    topic: &str,
    sensor: Sensor,
    opts: &ReadOptions,
) -> Result<ChannelStream, IoError> {
    let mut notes = Vec::new();
    let (numbered, _) = open_numbered(path, format, Some(topic), opts.stamp, &mut notes)?;
    Ok(Box::new(numbered.map(move |r| {
        r.map(|(at, t_ns, m)| ChannelSample {
            at,
            t_ns,
            value: Vector3::from(match sensor {
                Sensor::Gyro => m.gyro,
                Sensor::Accel => m.accel,
            }),
        })
    })))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(name: &str, type_name: &str) -> Topic {
        Topic {
            name: name.into(),
            type_name: type_name.into(),
        }
    }

    #[test]
    fn topic_selection() {
        let topics = [
            t("/imu0", "sensor_msgs/Imu"),
            t("/status", "std_msgs/String"),
        ];
        let mut notes = Vec::new();
        assert_eq!(
            select_topic("f", &topics, None, &mut notes).unwrap(),
            "/imu0"
        );
        assert!(notes[0].contains("only sensor_msgs/Imu topic"));
        let e = select_topic("f", &topics, Some("/status"), &mut notes).unwrap_err();
        assert!(e.to_string().contains("carries std_msgs/String"), "{e}");
        let e = select_topic("f", &topics, Some("/cam"), &mut notes).unwrap_err();
        assert!(e.to_string().contains("no topic /cam"), "{e}");
        assert!(e.to_string().contains("/imu0 (sensor_msgs/Imu)"), "{e}");
        let two = [t("/a", "sensor_msgs/msg/Imu"), t("/b", "sensor_msgs/Imu")];
        let e = select_topic("f", &two, None, &mut notes).unwrap_err();
        assert!(
            e.to_string().contains("2 sensor_msgs/Imu topics: /a"),
            "{e}"
        );
        let e = select_topic("f", &topics[1..], None, &mut notes).unwrap_err();
        assert!(e.to_string().contains("no sensor_msgs/Imu topic"), "{e}");
    }
}
