//! MCAP files, read with the `mcap` crate's streaming (sans-io) readers: channels, schemas and
//! message counts from the summary section (or, in a file without one, from a first pass over
//! the records), then the messages of one topic read front to back through a fixed buffer,
//! zstd and lz4 chunks decompressed one at a time. Messages are decoded as ROS 2 CDR (message
//! encoding `cdr`) or ROS 1 serialisation (`ros1`).

use super::imu_msg::Encoding;
use super::{Messages, RawItem, Topic};
use crate::error::IoError;
use crate::reader::Progress;
use ::mcap::records::{Record, op};
use ::mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use ::mcap::sans_io::summary_reader::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Read buffer \[bytes\]: the linear reader asks for one record at a time (a few hundred
/// bytes for an IMU message), so reads go through a buffer, not one system call each.
const READ_BUFFER: usize = 1 << 20;

/// Largest record (other than a chunk) accepted \[bytes\]: bounds the allocation a corrupt
/// length field can cause.
const RECORD_LIMIT: usize = 256 << 20;

/// One channel of the file.
struct Channel {
    id: u16,
    topic: Topic,
    message_encoding: String,
}

/// An opened MCAP file: its channels.
pub(crate) struct McapFile {
    path: PathBuf,
    len: u64,
    topics: Vec<Topic>,
    channels: Vec<Channel>,
}

fn io_err(path: &Path, e: std::io::Error) -> IoError {
    IoError::file(path, e)
}

/// The summary section of `file`, if the file has one.
fn read_summary(file: &mut File, len: u64) -> Result<Option<::mcap::Summary>, String> {
    let opts = SummaryReaderOptions::default()
        .with_file_size(len)
        .with_record_length_limit(RECORD_LIMIT);
    let mut reader = SummaryReader::new_with_options(opts);
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| e.to_string())? {
            SummaryReadEvent::ReadRequest(n) => {
                let k = file.read(reader.insert(n)).map_err(|e| e.to_string())?;
                reader.notify_read(k);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let pos = file.seek(to).map_err(|e| e.to_string())?;
                reader.notify_seeked(pos);
            }
        }
    }
    Ok(reader.finish())
}

/// A linear reader over `file` from its start.
fn linear() -> LinearReader {
    LinearReader::new_with_options(
        LinearReaderOptions::default().with_record_length_limit(RECORD_LIMIT),
    )
}

/// The channels of a file without a summary, from a pass over its records. A file that ends
/// early (a recording cut off) keeps the channels found before the damage; reading its
/// messages then fails at the message where the damage is.
fn scan_channels(path: &Path, name: &str) -> Result<Vec<Channel>, IoError> {
    let file = File::open(path).map_err(|e| io_err(path, e))?;
    let mut file = BufReader::with_capacity(READ_BUFFER, file);
    let mut reader = linear();
    let mut schemas: BTreeMap<u16, String> = BTreeMap::new();
    let mut channels = Vec::new();
    let mut failure = None;
    while let Some(event) = reader.next_event() {
        match event {
            Err(e) => {
                failure = Some(e.to_string());
                break;
            }
            Ok(LinearReadEvent::ReadRequest(n)) => {
                let k = file.read(reader.insert(n)).map_err(|e| io_err(path, e))?;
                reader.notify_read(k);
            }
            Ok(LinearReadEvent::Record { opcode, data }) => {
                if opcode != op::SCHEMA && opcode != op::CHANNEL {
                    continue;
                }
                match ::mcap::parse_record(opcode, data) {
                    Ok(Record::Schema { header, .. }) => {
                        schemas.insert(header.id, header.name);
                    }
                    Ok(Record::Channel(c)) => channels.push(c),
                    Ok(_) => {}
                    Err(e) => {
                        failure = Some(e.to_string());
                        break;
                    }
                }
            }
        }
    }
    if channels.is_empty()
        && let Some(f) = failure
    {
        return Err(IoError::format(
            name,
            format!("not a readable MCAP file: {f}"),
        ));
    }
    Ok(channels
        .into_iter()
        .map(|c| Channel {
            id: c.id,
            topic: Topic {
                name: c.topic,
                type_name: schemas.get(&c.schema_id).cloned().unwrap_or_default(),
            },
            message_encoding: c.message_encoding,
        })
        .collect())
}

impl McapFile {
    /// Opens `path` and reads its channels.
    pub fn open(path: &Path) -> Result<Self, IoError> {
        let name = path.display().to_string();
        let mut file = File::open(path).map_err(|e| io_err(path, e))?;
        let len = file.metadata().map_err(|e| io_err(path, e))?.len();
        let mut magic = [0u8; 8];
        if file.read_exact(&mut magic).is_err() || magic != ::mcap::MAGIC {
            return Err(IoError::format(
                &name,
                "not an MCAP file (no MCAP magic at the start)",
            ));
        }
        let channels = match read_summary(&mut file, len) {
            Ok(Some(summary)) => {
                let mut v: Vec<Channel> = summary
                    .channels
                    .values()
                    .map(|c| Channel {
                        id: c.id,
                        topic: Topic {
                            name: c.topic.clone(),
                            type_name: c
                                .schema
                                .as_ref()
                                .map(|s| s.name.clone())
                                .unwrap_or_default(),
                        },
                        message_encoding: c.message_encoding.clone(),
                    })
                    .collect();
                v.sort_by_key(|c| c.id);
                v
            }
            // No summary, or a damaged end of file: find the channels in the records.
            Ok(None) | Err(_) => scan_channels(path, &name)?,
        };
        let mut topics: Vec<Topic> = Vec::new();
        for c in &channels {
            if !topics.iter().any(|t| t.name == c.topic.name) {
                topics.push(c.topic.clone());
            }
        }
        Ok(Self {
            path: path.to_path_buf(),
            len,
            topics,
            channels,
        })
    }

    /// The topics of the file, in channel id order.
    pub fn topics(&self) -> &[Topic] {
        &self.topics
    }

    /// The messages of `topic` (every channel publishing it), decoded, in file order.
    pub fn messages(&self, topic: &str) -> Result<Messages, IoError> {
        let name = self.path.display().to_string();
        let mut wanted = Vec::new();
        for c in self.channels.iter().filter(|c| c.topic.name == topic) {
            let enc = match c.message_encoding.as_str() {
                "cdr" => Encoding::Cdr,
                "ros1" => Encoding::Ros1,
                other => {
                    return Err(IoError::format(
                        &name,
                        format!(
                            "topic {topic} has message encoding `{other}`; sensor_msgs/Imu is \
                             read from `cdr` (ROS 2) or `ros1`"
                        ),
                    ));
                }
            };
            wanted.push((c.id, enc));
        }
        let file = File::open(&self.path).map_err(|e| io_err(&self.path, e))?;
        let file = BufReader::with_capacity(READ_BUFFER, file);
        let done = Arc::new(AtomicU64::new(0));
        Ok(Messages {
            items: Box::new(McapMessages {
                file,
                reader: linear(),
                wanted,
                done: done.clone(),
                ended: false,
            }),
            progress: Progress::new(done, self.len),
        })
    }
}

/// The messages of some channels, read front to back. Progress counts bytes of the file.
struct McapMessages {
    file: BufReader<File>,
    reader: LinearReader,
    wanted: Vec<(u16, Encoding)>,
    done: Arc<AtomicU64>,
    ended: bool,
}

impl McapMessages {
    fn step(&mut self) -> Option<RawItem> {
        loop {
            match self.reader.next_event()? {
                Err(e) => return Some(Err(format!("corrupt or truncated MCAP file: {e}"))),
                Ok(LinearReadEvent::ReadRequest(n)) => {
                    match self.file.read(self.reader.insert(n)) {
                        Ok(k) => {
                            self.reader.notify_read(k);
                            self.done.fetch_add(k as u64, Ordering::Relaxed);
                        }
                        Err(e) => return Some(Err(format!("reading failed: {e}"))),
                    }
                }
                Ok(LinearReadEvent::Record { opcode, data }) => {
                    if opcode != op::MESSAGE {
                        continue;
                    }
                    let (header, payload) = match ::mcap::parse_record(opcode, data) {
                        Ok(Record::Message { header, data }) => (header, data),
                        Ok(_) => continue,
                        Err(e) => return Some(Err(format!("corrupt MCAP message record: {e}"))),
                    };
                    let Some(&(_, enc)) = self.wanted.iter().find(|w| w.0 == header.channel_id)
                    else {
                        continue;
                    };
                    return Some(enc.decode(&payload).map(|m| (header.log_time, m)));
                }
            }
        }
    }
}

impl Iterator for McapMessages {
    type Item = RawItem;

    fn next(&mut self) -> Option<RawItem> {
        if self.ended {
            return None;
        }
        let item = self.step();
        self.ended = !matches!(item, Some(Ok(_)));
        item
    }
}
