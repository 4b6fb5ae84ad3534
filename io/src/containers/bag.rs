//! ROS 1 bags (format 2.0), read with the `rosbag` crate: connections and message counts from
//! the index section, messages from the chunks (bz2 and lz4 chunks decompressed one at a time).
//!
//! The crate borrows its memory-mapped file, so the messages are read on a thread
//! ([`super::queue`]); the mapped pages are the operating system's file cache.

use super::imu_msg::Encoding;
use super::queue::on_thread;
use super::{Messages, RawItem, Topic};
use crate::error::IoError;
use crate::reader::Progress;
use rosbag::{ChunkRecord, IndexRecord, MessageRecord, RosBag};
use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// One connection (publisher of a topic) of the bag.
struct Connection {
    id: u32,
    topic: Topic,
}

/// An opened ROS 1 bag: its connections and how many messages each has.
pub(crate) struct Bag {
    path: PathBuf,
    topics: Vec<Topic>,
    connections: Vec<Connection>,
    counts: HashMap<u32, u64>,
}

/// Length of the bag's version line, `#ROSBAG V2.0\n`.
const VERSION_LEN: usize = 13;

/// Where the bag's sections start, from its header record: `(chunks, index)` \[bytes\], the
/// chunk section right after the header record and the index section at the header's
/// `index_pos` field. Read here only to refuse, with a typed error, the truncated, unindexed
/// and damaged files on which `rosbag` 0.6 would slice its map out of bounds.
fn sections(path: &Path) -> Result<Option<(u64, u64)>, IoError> {
    let mut head = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(8192).read_to_end(&mut head))
        .map_err(|e| IoError::file(path, e))?;
    let u32_at = |at: usize| {
        head.get(at..at + 4)
            .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")) as usize)
    };
    if !head.starts_with(b"#ROSBAG V2.0\n") {
        return Ok(None);
    }
    let Some(header_len) = u32_at(VERSION_LEN) else {
        return Ok(None);
    };
    let start = VERSION_LEN + 4;
    let end = start + header_len;
    // Header record: header fields, then its data (padding) of `data_len` bytes.
    let Some(data_len) = u32_at(end) else {
        return Ok(None);
    };
    let chunks = (end + 4 + data_len) as u64;
    let mut at = start;
    while let Some(len) = u32_at(at).filter(|_| at < end) {
        let field = head.get(at + 4..(at + 4 + len).min(end)).unwrap_or(&[]);
        if let Some(v) = field.strip_prefix(b"index_pos=")
            && let Ok(b) = <[u8; 8]>::try_from(v)
        {
            return Ok(Some((chunks, u64::from_le_bytes(b))));
        }
        at += 4 + len;
    }
    Ok(None)
}

impl Bag {
    /// Opens `path` and reads its index.
    pub fn open(path: &Path) -> Result<Self, IoError> {
        let name = path.display().to_string();
        let len = std::fs::metadata(path)
            .map_err(|e| IoError::file(path, e))?
            .len();
        let bad = |msg: String| IoError::format(&name, msg);
        match sections(path)? {
            Some((_, p)) if p > len => {
                return Err(bad(format!(
                    "truncated ROS 1 bag: its index starts at byte {p}, beyond the end of the \
                     file ({len} bytes); `rosbag reindex` rebuilds the index of what is left"
                )));
            }
            Some((chunks, p)) if p < chunks => {
                return Err(bad(format!(
                    "ROS 1 bag without an index (index_pos {p}, before the first chunk at byte \
                     {chunks}: a recording not closed, or a damaged header); run `rosbag reindex`"
                )));
            }
            Some(_) => {}
            None => return Err(bad("not a ROS 1 bag (version 2.0 header expected)".into())),
        }
        let bag = RosBag::new(path).map_err(|e| bad(format!("not a readable ROS 1 bag: {e}")))?;
        let mut connections = Vec::new();
        let mut counts = HashMap::new();
        for rec in bag.index_records() {
            match rec.map_err(|e| bad(format!("corrupt ROS 1 bag index: {e}")))? {
                IndexRecord::Connection(c) => connections.push(Connection {
                    id: c.id,
                    topic: Topic {
                        name: c.topic.to_string(),
                        type_name: c.tp.to_string(),
                    },
                }),
                IndexRecord::ChunkInfo(info) => {
                    for e in info.entries() {
                        *counts.entry(e.conn_id).or_insert(0) += u64::from(e.count);
                    }
                }
                IndexRecord::IndexData(_) => {}
            }
        }
        let mut topics: Vec<Topic> = Vec::new();
        for c in &connections {
            if !topics.iter().any(|t| t.name == c.topic.name) {
                topics.push(c.topic.clone());
            }
        }
        Ok(Self {
            path: path.to_path_buf(),
            topics,
            connections,
            counts,
        })
    }

    /// The topics of the bag, in the order of their first connection.
    pub fn topics(&self) -> &[Topic] {
        &self.topics
    }

    /// The messages of `topic` (every connection publishing it), decoded, in file order.
    pub fn messages(&self, topic: &str) -> Result<Messages, IoError> {
        let ids: Vec<u32> = self
            .connections
            .iter()
            .filter(|c| c.topic.name == topic)
            .map(|c| c.id)
            .collect();
        let total = ids.iter().map(|id| self.counts.get(id).unwrap_or(&0)).sum();
        let done = Arc::new(AtomicU64::new(0));
        let path = self.path.clone();
        let counter = done.clone();
        let items = on_thread("bag-reader", &self.path, move |send| {
            produce(&path, &ids, send, &counter)
        })?;
        Ok(Messages {
            items,
            progress: Progress::new(done, total),
        })
    }
}

/// Reads the messages of connections `ids` and sends them decoded, until the end of the bag,
/// the first error, or the consumer hanging up.
fn produce(path: &Path, ids: &[u32], send: &mut dyn FnMut(RawItem) -> bool, done: &AtomicU64) {
    if let Err(msg) = read_chunks(path, ids, send, done) {
        send(Err(msg));
    }
}

/// [`produce`], with the container's errors returned.
fn read_chunks(
    path: &Path,
    ids: &[u32],
    send: &mut dyn FnMut(RawItem) -> bool,
    done: &AtomicU64,
) -> Result<(), String> {
    let bag = RosBag::new(path).map_err(|e| format!("not a readable ROS 1 bag: {e}"))?;
    for rec in bag.chunk_records() {
        let chunk = match rec.map_err(|e| format!("corrupt ROS 1 bag chunk: {e}"))? {
            ChunkRecord::Chunk(c) => c,
            ChunkRecord::IndexData(_) => continue,
        };
        for msg in chunk.messages() {
            let m = match msg.map_err(|e| format!("corrupt ROS 1 bag message record: {e}"))? {
                MessageRecord::MessageData(m) => m,
                MessageRecord::Connection(_) => continue,
            };
            if !ids.contains(&m.conn_id) {
                continue;
            }
            done.fetch_add(1, Ordering::Relaxed);
            let item = Encoding::Ros1.decode(m.data).map(|d| (m.time, d));
            let failed = item.is_err();
            if !send(item) || failed {
                return Ok(());
            }
        }
    }
    Ok(())
}
