//! Messages read on a thread: for the container crates whose readers borrow their file or
//! database handle (`rosbag`'s map, `rusqlite`'s statement), so that their iterators cannot be
//! kept in a `'static` iterator. The thread sends decoded messages through a bounded channel
//! ([`QUEUE`] messages): memory does not grow with the file.

use super::RawItem;
use crate::error::IoError;
use std::path::Path;
use std::sync::mpsc::{Receiver, sync_channel};

/// Decoded messages in flight between the reading thread and the consumer.
const QUEUE: usize = 4096;

/// What the reading thread sends.
enum Sent {
    Item(RawItem),
    End,
}

/// Runs `produce` on a thread named `name`. `produce` hands each message to its argument,
/// which returns false when the consumer has gone (then `produce` should return). The
/// iterator ends after the first error, and reports one if the thread stops without
/// finishing (a panic in a container crate).
pub(crate) fn on_thread<F>(
    name: &str,
    path: &Path,
    produce: F,
) -> Result<Box<dyn Iterator<Item = RawItem> + Send>, IoError>
where
    F: FnOnce(&mut dyn FnMut(RawItem) -> bool) + Send + 'static,
{
    let (tx, rx) = sync_channel(QUEUE);
    std::thread::Builder::new()
        .name(name.into())
        .spawn(move || {
            let mut send = |item: RawItem| tx.send(Sent::Item(item)).is_ok();
            produce(&mut send);
            let _ = tx.send(Sent::End);
        })
        .map_err(|e| IoError::file(path, e))?;
    Ok(Box::new(Received { rx, ended: false }))
}

/// The consumer's end.
struct Received {
    rx: Receiver<Sent>,
    ended: bool,
}

impl Iterator for Received {
    type Item = RawItem;

    fn next(&mut self) -> Option<RawItem> {
        if self.ended {
            return None;
        }
        match self.rx.recv() {
            Ok(Sent::Item(item)) => {
                self.ended = item.is_err();
                Some(item)
            }
            Ok(Sent::End) => {
                self.ended = true;
                None
            }
            Err(_) => {
                self.ended = true;
                Some(Err("the reader stopped before the end of the file".into()))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_thread_that_dies_is_an_error_not_an_early_end() {
        let it = on_thread("t", Path::new("x"), |send| {
            send(Ok((
                1,
                super::super::imu_msg::ImuMsg {
                    stamp_ns: 1,
                    gyro: [0.0; 3],
                    accel: [0.0; 3],
                },
            )));
            panic!("container crate failure");
        })
        .unwrap();
        let items: Vec<RawItem> = it.collect();
        assert_eq!(items.len(), 2);
        assert!(
            items[1]
                .as_ref()
                .unwrap_err()
                .contains("stopped before the end")
        );
    }
}
