//! ROS 1 bag, MCAP and ROS 2 `.db3` input: the fixtures of `tests/data/ros` (written from the EuRoC CSV by
//! `tests/data/ros/generate.py`) give the CSV's samples bit for bit; topic, stamp and damage
//! errors are typed and name the file and the message.

use preint_io::containers::open_channel;
use preint_io::*;
use std::path::{Path, PathBuf};

/// Rows of the CSV in `euroc_imu.*` (2.5 s at 200 Hz).
const ROWS: usize = 500;
/// Rows of the CSV behind `split.*`.
const SPLIT_ROWS: usize = 400;
/// Record (log) time minus header stamp of every fixture message [ns].
const RECORD_OFFSET_NS: i64 = 1_000_000;
/// The EuRoC fixtures, one per container format.
const ALL: [&str; 3] = [
    "ros/euroc_imu.bag",
    "ros/euroc_imu.mcap",
    "ros/euroc_imu.db3",
];

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(p)
}

/// The first `n` rows of the EuRoC CSV, parsed here with `str::parse` (timestamp [ns], gyro
/// [rad/s], accelerometer [m/s²]).
fn csv_rows(n: usize) -> Vec<(i64, [f64; 6])> {
    let text = std::fs::read_to_string(data("euroc/V1_01_easy_imu0.csv")).unwrap();
    text.lines()
        .skip(1)
        .take(n)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let mut v = [0.0; 6];
            for (i, x) in v.iter_mut().enumerate() {
                *x = f[i + 1].trim().parse().unwrap();
            }
            (f[0].parse().unwrap(), v)
        })
        .collect()
}

fn read(path: &Path, opts: &ReadOptions) -> (Vec<preint::ImuSample>, SourceInfo) {
    let r = ImuReader::open(path, opts).unwrap();
    let info = r.info().clone();
    (r.read_all().unwrap(), info)
}

fn assert_same_as_csv(samples: &[preint::ImuSample], shift_ns: i64) {
    let rows = csv_rows(ROWS);
    assert_eq!(samples.len(), ROWS);
    for (s, (t, v)) in samples.iter().zip(&rows) {
        assert_eq!(s.t_ns, t + shift_ns);
        // Bit for bit: f64 written by the generator, read back unchanged.
        let got = [s.gyro.x, s.gyro.y, s.gyro.z, s.acc.x, s.acc.y, s.acc.z];
        assert_eq!(got.map(f64::to_bits), v.map(f64::to_bits), "t = {t}");
    }
}

#[test]
fn bag_mcap_and_db3_give_the_csv_rows_bit_for_bit() {
    for file in ALL {
        let (samples, info) = read(&data(file), &ReadOptions::default());
        assert_same_as_csv(&samples, 0);
        let notes = info.notes.join("; ");
        assert!(
            notes.contains("topic /imu0: the only sensor_msgs/Imu topic"),
            "{notes}"
        );
        assert!(notes.contains("header.stamp"), "{notes}");
        assert!(info.format.is_container());
    }
}

#[test]
fn explicit_topic_and_format() {
    let opts = ReadOptions {
        topic: Some("/imu0".into()),
        format: Some(Format::Mcap),
        ..ReadOptions::default()
    };
    let (samples, info) = read(&data("ros/euroc_imu.mcap"), &opts);
    assert_same_as_csv(&samples, 0);
    assert!(!info.notes.join(" ").contains("only sensor_msgs/Imu topic"));
}

#[test]
fn record_stamp_is_the_header_stamp_plus_the_recorders_offset() {
    let opts = ReadOptions {
        stamp: Stamp::Record,
        ..ReadOptions::default()
    };
    for file in ALL {
        let (samples, info) = read(&data(file), &opts);
        assert_same_as_csv(&samples, RECORD_OFFSET_NS);
        assert!(
            info.notes.join(" ").contains("record time"),
            "{:?}",
            info.notes
        );
    }
}

/// The message of a [`IoError::Format`] from opening `file` with `opts`.
fn format_error(file: &Path, opts: &ReadOptions) -> String {
    match ImuReader::open(file, opts) {
        Err(e @ IoError::Format { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains(&file.display().to_string()), "{msg}");
            msg
        }
        Err(e) => panic!("expected a format error, got {e:?}"),
        Ok(_) => panic!("expected a format error, got a reader"),
    }
}

fn topic(t: &str) -> ReadOptions {
    ReadOptions {
        topic: Some(t.into()),
        ..ReadOptions::default()
    }
}

#[test]
fn topic_errors_list_the_imu_topics() {
    for ext in ["bag", "mcap", "db3"] {
        let euroc = data(&format!("ros/euroc_imu.{ext}"));
        let e = format_error(&euroc, &topic("/imu1"));
        assert!(e.contains("no topic /imu1"), "{e}");
        assert!(e.contains("/imu0 (sensor_msgs"), "{e}");

        let split = data(&format!("ros/split.{ext}"));
        let e = format_error(&split, &ReadOptions::default());
        assert!(e.contains("2 sensor_msgs/Imu topics"), "{e}");
        assert!(e.contains("/camera/gyro/sample"), "{e}");
        assert!(e.contains("/camera/accel/sample"), "{e}");
        assert!(e.contains("--topic"), "{e}");

        let e = format_error(&split, &topic("/status"));
        assert!(e.contains("topic /status carries std_msgs"), "{e}");
        assert!(e.contains("String"), "{e}");
    }
}

/// A copy of fixture `file` cut to `keep` of its bytes, in the temporary directory.
fn truncated(file: &str, keep: f64) -> PathBuf {
    let bytes = std::fs::read(data(file)).unwrap();
    let name = Path::new(file).file_name().unwrap().to_str().unwrap();
    let out = std::env::temp_dir().join(format!("preint-io-{}-cut-{name}", std::process::id()));
    std::fs::write(&out, &bytes[..(bytes.len() as f64 * keep) as usize]).unwrap();
    out
}

#[test]
fn truncated_mcap_fails_at_the_message_where_it_ends() {
    let cut = truncated("ros/euroc_imu.mcap", 0.5);
    let mut reader = ImuReader::open(&cut, &ReadOptions::default()).unwrap();
    let rows = csv_rows(ROWS);
    let mut good = 0;
    let err = loop {
        match reader.next().expect("an error before the end") {
            Ok(s) => {
                assert_eq!(s.t_ns, rows[good].0);
                good += 1;
            }
            Err(e) => break e,
        }
    };
    assert!(good > 0 && good < ROWS, "{good} samples before the damage");
    match &err {
        IoError::Parse {
            source_name,
            at: Location::Message(m),
            msg,
        } => {
            assert_eq!(*m, good as u64 + 1);
            assert_eq!(source_name, &cut.display().to_string());
            assert!(msg.contains("truncated"), "{msg}");
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
    assert!(reader.next().is_none());
    std::fs::remove_file(cut).unwrap();
}

#[test]
fn truncated_bag_is_a_typed_error() {
    for keep in [0.5, 0.99] {
        let cut = truncated("ros/euroc_imu.bag", keep);
        let e = format_error(&cut, &ReadOptions::default());
        assert!(e.contains("truncated ROS 1 bag"), "{e}");
        std::fs::remove_file(cut).unwrap();
    }
}

#[test]
fn unindexed_bag_is_a_typed_error() {
    // A recording that was not closed has index_pos = 0 in its header.
    let mut bytes = std::fs::read(data("ros/euroc_imu.bag")).unwrap();
    let at = bytes.windows(10).position(|w| w == b"index_pos=").unwrap() + 10;
    bytes[at..at + 8].fill(0);
    let out = std::env::temp_dir().join(format!("preint-io-{}-open.bag", std::process::id()));
    std::fs::write(&out, &bytes).unwrap();
    let e = format_error(&out, &ReadOptions::default());
    assert!(e.contains("without an index"), "{e}");
    std::fs::remove_file(out).unwrap();
}

#[test]
fn truncated_db3_is_a_typed_error() {
    let cut = truncated("ros/euroc_imu.db3", 0.5);
    let err = ImuReader::open(&cut, &ReadOptions::default()).and_then(|r| r.read_all());
    match err {
        Err(IoError::Parse {
            at: Location::Message(m),
            source_name,
            ..
        }) => {
            assert!(m >= 1 && m <= ROWS as u64);
            assert_eq!(source_name, cut.display().to_string());
        }
        Err(IoError::Format { source_name, .. }) => {
            assert_eq!(source_name, cut.display().to_string())
        }
        other => panic!("expected a typed error naming the file, got {other:?}"),
    }
    std::fs::remove_file(cut).unwrap();
}

#[test]
fn files_that_are_not_containers_are_typed_errors() {
    let csv = data("euroc/V1_01_easy_imu0.csv");
    for format in [Format::RosBag, Format::Mcap, Format::Db3] {
        let opts = ReadOptions {
            format: Some(format),
            ..ReadOptions::default()
        };
        let e = format_error(&csv, &opts);
        assert!(e.contains("not a"), "{e}");
    }
    let missing = data("ros/no_such_file.db3");
    assert!(matches!(
        ImuReader::open(&missing, &ReadOptions::default()),
        Err(IoError::File { .. })
    ));
}

#[test]
fn channels_of_a_split_recording() {
    let rows = csv_rows(SPLIT_ROWS);
    let opts = ReadOptions::default();
    for ext in ["bag", "mcap", "db3"] {
        let file = data(&format!("ros/split.{ext}"));
        let fmt = Format::from_extension(&file).unwrap();
        let gyro: Vec<ChannelSample> =
            open_channel(&file, fmt, "/camera/gyro/sample", Sensor::Gyro, &opts)
                .unwrap()
                .collect::<Result<_, _>>()
                .unwrap();
        assert_eq!(gyro.len(), SPLIT_ROWS);
        for (i, (g, (t, v))) in gyro.iter().zip(&rows).enumerate() {
            assert_eq!(g.at, Location::Message(i as u64 + 1));
            assert_eq!(g.t_ns, *t);
            assert_eq!([g.value.x, g.value.y, g.value.z], [v[0], v[1], v[2]]);
        }
        let accel: Vec<ChannelSample> =
            open_channel(&file, fmt, "/camera/accel/sample", Sensor::Accel, &opts)
                .unwrap()
                .collect::<Result<_, _>>()
                .unwrap();
        // 63 Hz from the first gyro stamp to the last: t_k = t_0 + round(k·10⁹/63) ns.
        let (t0, t_end) = (rows[0].0, rows[SPLIT_ROWS - 1].0);
        let expected_len = ((t_end - t0) as f64 * 63e-9).floor() as usize + 1;
        assert_eq!(accel.len(), expected_len);
        for (k, a) in accel.iter().enumerate() {
            assert_eq!(a.t_ns, t0 + (k as f64 * 1e9 / 63.0).round() as i64);
            // Linear interpolation of the CSV accelerometer between the rows around t_k.
            let j = rows
                .partition_point(|r| r.0 <= a.t_ns)
                .clamp(1, SPLIT_ROWS - 1);
            let ((ta, va), (tb, vb)) = (rows[j - 1], rows[j]);
            let w = (a.t_ns - ta) as f64 / (tb - ta) as f64;
            for i in 0..3 {
                let want = va[i + 3] + w * (vb[i + 3] - va[i + 3]);
                assert!(
                    (a.value[i] - want).abs() < 1e-12,
                    "k {k}: {} vs {want}",
                    a.value[i]
                );
            }
        }
        let e = open_channel(&file, fmt, "/status", Sensor::Gyro, &opts)
            .err()
            .expect("a type error");
        assert!(e.to_string().contains("carries std_msgs"), "{e}");
    }
}

/// A container without its extension is recognised by its first bytes.
#[test]
fn containers_renamed_without_their_extension_are_read_by_their_first_bytes() {
    let dir = std::env::temp_dir().join(format!("preint-io-magic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, format) in [
        ("euroc_imu.bag", preint_io::Format::RosBag),
        ("euroc_imu.mcap", preint_io::Format::Mcap),
        ("euroc_imu.db3", preint_io::Format::Db3),
    ] {
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/data/ros")
            .join(name);
        let renamed = dir.join(format!("{name}.dat"));
        std::fs::copy(&src, &renamed).unwrap();
        let reader = preint_io::ImuReader::open(&renamed, &preint_io::ReadOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(reader.info().format, format, "{name}");
        let from_original = preint_io::ImuReader::open(&src, &preint_io::ReadOptions::default())
            .unwrap()
            .read_all()
            .unwrap();
        assert_eq!(reader.read_all().unwrap(), from_original, "{name}");
    }
}
