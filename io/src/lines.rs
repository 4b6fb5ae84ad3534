//! [`LineReader`]: the lines of a text stream in bounded memory, whatever their ends.
//!
//! Accepts `\n`, `\r\n` and `\r`-only line ends (a lone `\r` ends a line, as old Mac files
//! and some loggers write), skips a UTF-8 byte-order mark at the start, and refuses a line
//! longer than [`MAX_LINE_BYTES`] or text that is not UTF-8, naming the line.

use crate::error::{IoError, Location};
use memchr::memchr2;
use std::io::Read;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Longest accepted line \[bytes\]: an IMU row is about 100 bytes; a longer "line" means the
/// file is not line-oriented text (binary, or one huge line).
pub const MAX_LINE_BYTES: usize = 1 << 20;

const INITIAL_BUFFER: usize = 256 * 1024;

/// One line: where it is, and its text without the line end.
#[derive(Clone, Copy, Debug)]
pub struct Line<'a> {
    /// Its location: `Line(n)` when counted from the start of the file, else `Byte(offset)`.
    pub at: Location,
    /// Byte offset of its first byte in the stream.
    pub offset: u64,
    /// Its text, without the line end.
    pub text: &'a str,
}

/// Reads lines from `R` through one reused buffer (see the module docs).
pub struct LineReader<R> {
    inner: R,
    name: String,
    buf: Vec<u8>,
    start: usize,
    end: usize,
    eof: bool,
    /// The previous line ended with `\r`: a `\n` right after it belongs to that line end.
    skip_lf: bool,
    /// Number of the last line returned, when lines are counted from the file's start.
    line: Option<u64>,
    /// Stream offset of `buf[start]`.
    offset: u64,
    bytes_read: Arc<AtomicU64>,
}

impl<R: Read> LineReader<R> {
    /// Lines of `inner` from its start; `name` labels errors (usually the path).
    pub fn new(inner: R, name: &str) -> Self {
        Self::at_offset(inner, name, 0, true)
    }

    /// Lines of `inner`, which starts at byte `offset` of the file, at the start of a line;
    /// with `counted`, `offset` is 0 and lines are numbered, else locations are byte offsets.
    pub fn at_offset(inner: R, name: &str, offset: u64, counted: bool) -> Self {
        Self {
            inner,
            name: name.to_string(),
            buf: vec![0; INITIAL_BUFFER],
            start: 0,
            end: 0,
            eof: false,
            skip_lf: false,
            line: counted.then_some(0),
            offset,
            bytes_read: Arc::new(AtomicU64::new(offset)),
        }
    }

    /// A counter of the bytes consumed from the file so far (for progress bars).
    pub fn progress(&self) -> Arc<AtomicU64> {
        Arc::clone(&self.bytes_read)
    }

    /// The source label given at construction.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The next line, or `None` at the end of the stream.
    pub fn next_line(&mut self) -> Result<Option<Line<'_>>, IoError> {
        loop {
            if self.skip_lf {
                if self.start < self.end {
                    if self.buf[self.start] == b'\n' {
                        self.start += 1;
                        self.offset += 1;
                    }
                    self.skip_lf = false;
                } else if self.eof {
                    self.skip_lf = false;
                } else {
                    self.fill()?;
                    continue;
                }
            }
            let (s, found) = match memchr2(b'\n', b'\r', &self.buf[self.start..self.end]) {
                Some(i) => (self.start, Some(self.start + i)),
                None if self.eof && self.start == self.end => return Ok(None),
                None if self.eof => (self.start, None),
                None => {
                    self.fill()?;
                    continue;
                }
            };
            let e = found.unwrap_or(self.end);
            self.skip_lf = found.is_some_and(|i| self.buf[i] == b'\r');
            self.start = found.map_or(e, |i| i + 1);
            let offset = self.offset;
            self.offset += (self.start - s) as u64;
            let at = match &mut self.line {
                Some(n) => {
                    *n += 1;
                    Location::Line(*n)
                }
                None => Location::Byte(offset),
            };
            let text = std::str::from_utf8(&self.buf[s..e]).map_err(|err| {
                IoError::parse(
                    &self.name,
                    at,
                    format!(
                        "not UTF-8 text (byte {} of the line); is this a binary file?",
                        err.valid_up_to() + 1
                    ),
                )
            })?;
            let text = if offset == 0 {
                text.strip_prefix('\u{feff}').unwrap_or(text)
            } else {
                text
            };
            return Ok(Some(Line { at, offset, text }));
        }
    }

    /// The next row `row` makes something of: lines are trimmed, blank and comment lines
    /// ([`is_comment`]) skipped, and `row(text, at)` returning `Ok(None)` (a header) skips the
    /// line too. `None` at the end of the stream.
    pub fn next_row<T>(
        &mut self,
        mut row: impl FnMut(&str, Location) -> Result<Option<T>, IoError>,
    ) -> Option<Result<T, IoError>> {
        loop {
            let line = match self.next_line() {
                Ok(Some(line)) => line,
                Ok(None) => return None,
                Err(e) => return Some(Err(e)),
            };
            let text = line.text.trim();
            if text.is_empty() || is_comment(text) {
                continue;
            }
            match row(text, line.at) {
                Ok(Some(t)) => return Some(Ok(t)),
                Ok(None) => continue,
                Err(e) => return Some(Err(e)),
            }
        }
    }

    /// Moves the unread bytes to the front, grows the buffer if a line fills it, and reads.
    fn fill(&mut self) -> Result<(), IoError> {
        if self.start > 0 {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        if self.end == self.buf.len() {
            if self.buf.len() > MAX_LINE_BYTES {
                let at = match self.line {
                    Some(n) => Location::Line(n + 1),
                    None => Location::Byte(self.offset),
                };
                return Err(IoError::parse(
                    &self.name,
                    at,
                    format!(
                        "line longer than {MAX_LINE_BYTES} bytes; this is not line-oriented text"
                    ),
                ));
            }
            self.buf.resize(self.buf.len() * 2, 0);
        }
        loop {
            match self.inner.read(&mut self.buf[self.end..]) {
                Ok(0) => {
                    self.eof = true;
                    return Ok(());
                }
                Ok(n) => {
                    self.end += n;
                    self.bytes_read.fetch_add(n as u64, Ordering::Relaxed);
                    return Ok(());
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => {
                    return Err(IoError::File {
                        path: self.name.clone(),
                        source: e,
                    });
                }
            }
        }
    }
}

/// The 1-based number of the line starting at byte `offset` of `text`, counting line ends as
/// A comment line of a text recording: it starts with `#` or `%` (after trimming).
pub fn is_comment(text: &str) -> bool {
    text.starts_with('#') || text.starts_with('%')
}

/// [`LineReader`] does (`\n`, `\r\n`, lone `\r`). Used to name the line of an error found after
/// a seek.
pub fn line_number_at(mut inner: impl Read, offset: u64) -> std::io::Result<u64> {
    let mut buf = vec![0u8; 1 << 16];
    let (mut seen, mut line, mut prev_cr) = (0u64, 1u64, false);
    while seen < offset {
        let want = ((offset - seen) as usize).min(buf.len());
        let n = inner.read(&mut buf[..want])?;
        if n == 0 {
            break;
        }
        for &b in &buf[..n] {
            match b {
                b'\n' if prev_cr => {}
                b'\n' | b'\r' => line += 1,
                _ => {}
            }
            prev_cr = b == b'\r';
        }
        seen += n as u64;
    }
    Ok(line)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(bytes: &[u8]) -> Vec<(Location, String)> {
        let mut r = LineReader::new(bytes, "t");
        let mut out = Vec::new();
        while let Some(l) = r.next_line().unwrap() {
            out.push((l.at, l.text.to_string()));
        }
        out
    }

    #[test]
    fn every_line_end_and_the_bom() {
        let want = |v: &[&str]| {
            v.iter()
                .enumerate()
                .map(|(i, s)| (Location::Line(i as u64 + 1), s.to_string()))
                .collect::<Vec<_>>()
        };
        assert_eq!(lines(b"a\nb\nc"), want(&["a", "b", "c"]));
        assert_eq!(lines(b"a\r\nb\r\nc\r\n"), want(&["a", "b", "c"]));
        assert_eq!(lines(b"a\rb\rc\r"), want(&["a", "b", "c"]));
        assert_eq!(lines(b"a\r\rb"), want(&["a", "", "b"]));
        assert_eq!(lines(b"\xef\xbb\xbfa\nb\n"), want(&["a", "b"]));
        assert_eq!(lines(b""), want(&[]));
    }

    #[test]
    fn line_ends_split_across_reads() {
        // A reader that returns one byte at a time puts every `\r\n` across two reads.
        struct OneByte<'a>(&'a [u8]);
        impl Read for OneByte<'_> {
            fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
                if self.0.is_empty() || out.is_empty() {
                    return Ok(0);
                }
                out[0] = self.0[0];
                self.0 = &self.0[1..];
                Ok(1)
            }
        }
        let mut r = LineReader::new(OneByte(b"x\r\ny\rz\n"), "t");
        let mut got = Vec::new();
        while let Some(l) = r.next_line().unwrap() {
            got.push((l.offset, l.text.to_string()));
        }
        assert_eq!(got, [(0, "x".into()), (3, "y".into()), (5, "z".into())]);
        for (offset, line) in [(0, 1), (3, 2), (5, 3)] {
            assert_eq!(line_number_at(&b"x\r\ny\rz\n"[..], offset).unwrap(), line);
        }
    }

    #[test]
    fn binary_and_endless_lines_are_refused() {
        let mut r = LineReader::new(&b"ok\n\xff\xfe\n"[..], "f.csv");
        r.next_line().unwrap();
        let e = r.next_line().unwrap_err().to_string();
        assert!(e.starts_with("f.csv:2: not UTF-8"), "{e}");
        let long = vec![b'1'; MAX_LINE_BYTES * 2 + 10];
        let mut r = LineReader::new(&long[..], "big.csv");
        let e = r.next_line().unwrap_err().to_string();
        assert!(e.contains("big.csv:1: line longer than"), "{e}");
    }
}
