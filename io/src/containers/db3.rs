//! ROS 2 `.db3` bags (rosbag2's SQLite storage), read with `rusqlite`: topics from the
//! `topics` table (`id, name, type, serialization_format`), messages from the `messages` table
//! (`topic_id, timestamp, data`) in insertion order (`id`), which is the order the recorder
//! wrote them. `timestamp` is the record time \[ns\]; `data` is the CDR payload.
//!
//! A statement borrows its connection, so the rows are read on a thread ([`super::queue`]);
//! SQLite steps through the rows with its page cache, so memory does not grow with the file.

use super::imu_msg::Encoding;
use super::queue::on_thread;
use super::{Messages, RawItem, Topic};
use crate::error::IoError;
use crate::reader::Progress;
use rusqlite::{Connection, OpenFlags};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// One row of the `topics` table.
struct DbTopic {
    id: i64,
    topic: Topic,
    serialization_format: String,
}

/// An opened `.db3` bag: its topics.
pub(crate) struct Db3 {
    path: PathBuf,
    topics: Vec<Topic>,
    rows: Vec<DbTopic>,
}

/// Opens the database read-only (it is never written).
fn connect(path: &Path) -> rusqlite::Result<Connection> {
    Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
}

impl Db3 {
    /// Opens `path` and reads its `topics` table.
    pub fn open(path: &Path) -> Result<Self, IoError> {
        let name = path.display().to_string();
        if !path.exists() {
            let e = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
            return Err(IoError::file(path, e));
        }
        let bad = |e: rusqlite::Error| {
            IoError::format(
                &name,
                format!("not a readable ROS 2 .db3 (SQLite) bag: {e}"),
            )
        };
        let conn = connect(path).map_err(bad)?;
        let mut stmt = conn
            .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")
            .map_err(bad)?;
        let rows = stmt
            .query_map([], |r| {
                Ok(DbTopic {
                    id: r.get(0)?,
                    topic: Topic {
                        name: r.get(1)?,
                        type_name: r.get(2)?,
                    },
                    serialization_format: r.get(3)?,
                })
            })
            .map_err(bad)?
            .collect::<rusqlite::Result<Vec<_>>>()
            .map_err(bad)?;
        let mut topics: Vec<Topic> = Vec::new();
        for r in &rows {
            if !topics.iter().any(|t| t.name == r.topic.name) {
                topics.push(r.topic.clone());
            }
        }
        Ok(Self {
            path: path.to_path_buf(),
            topics,
            rows,
        })
    }

    /// The topics of the bag, in `topics.id` order.
    pub fn topics(&self) -> &[Topic] {
        &self.topics
    }

    /// The messages of `topic`, decoded, in the order they were recorded.
    pub fn messages(&self, topic: &str) -> Result<Messages, IoError> {
        let name = self.path.display().to_string();
        let mut ids = Vec::new();
        for r in self.rows.iter().filter(|r| r.topic.name == topic) {
            if r.serialization_format != "cdr" {
                return Err(IoError::format(
                    &name,
                    format!(
                        "topic {topic} is serialised as `{}`; sensor_msgs/Imu is read from `cdr`",
                        r.serialization_format
                    ),
                ));
            }
            ids.push(r.id);
        }
        let total = count(&self.path, &ids).map_err(|e| IoError::format(&name, e))?;
        let done = Arc::new(AtomicU64::new(0));
        let (path, counter) = (self.path.clone(), done.clone());
        let items = on_thread("db3-reader", &self.path, move |send| {
            if let Err(e) = produce(&path, &ids, send, &counter) {
                send(Err(format!("corrupt ROS 2 .db3 bag: {e}")));
            }
        })?;
        Ok(Messages {
            items,
            progress: Progress::new(done, total),
        })
    }
}

/// `topic_id IN (…)` for `ids` (integers from the database, not user text).
fn topic_filter(ids: &[i64]) -> String {
    let list: Vec<String> = ids.iter().map(i64::to_string).collect();
    format!("topic_id IN ({})", list.join(","))
}

/// Number of messages of topics `ids`.
fn count(path: &Path, ids: &[i64]) -> Result<u64, String> {
    let sql = format!("SELECT COUNT(*) FROM messages WHERE {}", topic_filter(ids));
    let n: i64 = connect(path)
        .and_then(|c| c.query_row(&sql, [], |r| r.get(0)))
        .map_err(|e| format!("not a readable ROS 2 .db3 (SQLite) bag: {e}"))?;
    Ok(n.max(0) as u64)
}

/// Sends the messages of topics `ids`, decoded, until the end, the first error, or the
/// consumer hanging up.
fn produce(
    path: &Path,
    ids: &[i64],
    send: &mut dyn FnMut(RawItem) -> bool,
    done: &AtomicU64,
) -> rusqlite::Result<()> {
    let conn = connect(path)?;
    let sql = format!(
        "SELECT timestamp, data FROM messages WHERE {} ORDER BY id",
        topic_filter(ids)
    );
    let mut stmt = conn.prepare(&sql)?;
    let mut rows = stmt.query([])?;
    while let Some(row) = rows.next()? {
        let record: i64 = row.get(0)?;
        let data = row.get_ref(1)?.as_blob()?;
        done.fetch_add(1, Ordering::Relaxed);
        let item = match u64::try_from(record) {
            Ok(t) => Encoding::Cdr.decode(data).map(|m| (t, m)),
            Err(_) => Err(format!("negative record timestamp {record} ns")),
        };
        let failed = item.is_err();
        if !send(item) || failed {
            break;
        }
    }
    Ok(())
}
