//! The subset of YAML that calibration files use (Kalibr's `yaml.dump`, OpenVINS' OpenCV-style
//! `%YAML:1.0` files): nested block mappings by indentation, block sequences (also at the
//! indentation of their key, as `yaml.dump` writes them), flow lists `[a, [b, c]]`, plain and
//! quoted scalars, `#` comments. Every node keeps its 1-based line for error messages. Anchors,
//! tags, multi-line scalars and flow mappings are not part of it (a line using them is an error
//! or a plain scalar, never silently a different value).

use crate::error::{IoError, Location};

/// A parsed node with the line it starts on.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Node {
    /// A scalar (quotes removed).
    Scalar(String, u64),
    /// A list.
    Seq(Vec<Node>, u64),
    /// A mapping, in file order.
    Map(Vec<(String, Node)>, u64),
}

impl Node {
    pub(crate) fn line(&self) -> u64 {
        match self {
            Node::Scalar(_, l) | Node::Seq(_, l) | Node::Map(_, l) => *l,
        }
    }

    /// The value of `key` in a mapping.
    pub(crate) fn get(&self, key: &str) -> Option<&Node> {
        match self {
            Node::Map(entries, _) => entries.iter().find(|(k, _)| k == key).map(|(_, v)| v),
            _ => None,
        }
    }
}

/// One significant line: indentation, content without comment, 1-based number.
struct Line<'a> {
    indent: usize,
    text: &'a str,
    no: u64,
}

/// `text` without a `#` comment that is outside quotes.
fn strip_comment(text: &str) -> &str {
    let mut quote = None;
    for (i, c) in text.char_indices() {
        match (quote, c) {
            (None, '"' | '\'') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            (None, '#') if i == 0 || text[..i].ends_with([' ', '\t']) => return &text[..i],
            _ => {}
        }
    }
    text
}

/// Parses `text` into its root mapping.
pub(crate) fn parse(text: &str, source: &str) -> Result<Node, IoError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let no = i as u64 + 1;
        if raw.starts_with('%') || raw.trim() == "---" || raw.trim() == "..." {
            continue;
        }
        if raw.contains('\t') && raw.trim_start_matches(' ').starts_with('\t') {
            return Err(IoError::parse(
                source,
                Location::Line(no),
                "tab in indentation",
            ));
        }
        let body = strip_comment(raw).trim_end();
        if body.trim().is_empty() {
            continue;
        }
        let indent = body.len() - body.trim_start().len();
        lines.push(Line {
            indent,
            text: body.trim_start(),
            no,
        });
    }
    let mut p = Parser {
        lines,
        pos: 0,
        source,
    };
    let root = match p.lines.first() {
        Some(l) => p.block(l.indent)?,
        None => Node::Map(Vec::new(), 1),
    };
    if let Some(l) = p.lines.get(p.pos) {
        return Err(p.err(l.no, "unexpected indentation"));
    }
    Ok(root)
}

struct Parser<'a> {
    lines: Vec<Line<'a>>,
    pos: usize,
    source: &'a str,
}

impl Parser<'_> {
    fn err(&self, line: u64, msg: impl Into<String>) -> IoError {
        IoError::parse(self.source, Location::Line(line), msg)
    }

    /// The block (mapping or sequence) whose lines start at indentation `indent`.
    fn block(&mut self, indent: usize) -> Result<Node, IoError> {
        let first = &self.lines[self.pos];
        if first.text == "-" || first.text.starts_with("- ") {
            return self.seq(indent);
        }
        let start = first.no;
        let mut entries: Vec<(String, Node)> = Vec::new();
        while let Some(l) = self.lines.get(self.pos) {
            if l.indent < indent {
                break;
            }
            if l.indent > indent {
                return Err(self.err(l.no, "unexpected indentation"));
            }
            let (no, text) = (l.no, l.text);
            let Some((key, rest)) = split_key(text) else {
                return Err(self.err(no, format!("expected `key: value`, got `{text}`")));
            };
            if entries.iter().any(|(k, _)| k == key) {
                return Err(self.err(no, format!("duplicate key `{key}`")));
            }
            self.pos += 1;
            let value = if rest.is_empty() {
                match self.lines.get(self.pos) {
                    Some(n) if n.indent > indent => self.block(n.indent)?,
                    Some(n) if n.indent == indent && n.text.starts_with('-') => self.seq(indent)?,
                    _ => Node::Scalar(String::new(), no),
                }
            } else {
                self.inline(rest, no)?
            };
            entries.push((key.to_string(), value));
        }
        Ok(Node::Map(entries, start))
    }

    /// A block sequence at `indent` (items `- value`).
    fn seq(&mut self, indent: usize) -> Result<Node, IoError> {
        let start = self.lines[self.pos].no;
        let mut items = Vec::new();
        while let Some(l) = self.lines.get(self.pos) {
            if l.indent != indent || !(l.text == "-" || l.text.starts_with("- ")) {
                break;
            }
            let (no, rest) = (l.no, l.text[1..].trim());
            self.pos += 1;
            if rest.is_empty() || split_key(rest).is_some() {
                return Err(self.err(no, "nested blocks in a list are not supported"));
            }
            items.push(self.inline(rest, no)?);
        }
        Ok(Node::Seq(items, start))
    }

    /// A value on one line: a flow list or a scalar.
    fn inline(&self, text: &str, no: u64) -> Result<Node, IoError> {
        if text.starts_with('[') {
            let (node, rest) = self.flow(text, no)?;
            if !rest.trim().is_empty() {
                return Err(self.err(no, format!("unexpected `{}` after a list", rest.trim())));
            }
            return Ok(node);
        }
        if text.starts_with('{') || text.starts_with('&') || text.starts_with('*') {
            return Err(self.err(no, format!("unsupported YAML construct `{text}`")));
        }
        Ok(Node::Scalar(unquote(text).to_string(), no))
    }

    /// A flow list starting at `text` (`[`): the list and the text after its `]`.
    fn flow<'t>(&self, text: &'t str, no: u64) -> Result<(Node, &'t str), IoError> {
        let mut items = Vec::new();
        let mut rest = text[1..].trim_start();
        if let Some(r) = rest.strip_prefix(']') {
            return Ok((Node::Seq(items, no), r));
        }
        loop {
            let (item, r) = if rest.starts_with('[') {
                self.flow(rest, no)?
            } else {
                let end = rest
                    .find([',', ']'])
                    .ok_or_else(|| self.err(no, "unclosed `[`"))?;
                let s = unquote(rest[..end].trim()).to_string();
                (Node::Scalar(s, no), &rest[end..])
            };
            items.push(item);
            let r = r.trim_start();
            if let Some(r) = r.strip_prefix(',') {
                rest = r.trim_start();
            } else if let Some(r) = r.strip_prefix(']') {
                return Ok((Node::Seq(items, no), r));
            } else {
                return Err(self.err(no, "unclosed `[`"));
            }
        }
    }
}

/// `key: rest` (rest trimmed, possibly empty), or `None` for a line that is not a mapping entry.
fn split_key(text: &str) -> Option<(&str, &str)> {
    if text.starts_with('[') || text.starts_with('"') || text.starts_with('\'') {
        return None;
    }
    let i = text
        .find(": ")
        .or_else(|| text.ends_with(':').then(|| text.len() - 1))?;
    Some((text[..i].trim(), text[i + 1..].trim()))
}

fn unquote(s: &str) -> &str {
    for q in ['"', '\''] {
        if let Some(inner) = s.strip_prefix(q).and_then(|x| x.strip_suffix(q)) {
            return inner;
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_sequences_at_the_key_indentation_and_flow_lists_parse() {
        let t = "%YAML:1.0\nimu0:\n  M:\n  - [1.0, 2, 3]   # c\n  - [4, 5, 6]\n  A: [[1, 2], [3]]\n  model: \"kalibr\"\n  empty:\n";
        let root = parse(t, "t").unwrap();
        let imu = root.get("imu0").unwrap();
        let Node::Seq(rows, 4) = imu.get("M").unwrap() else {
            panic!("{imu:?}")
        };
        assert_eq!(rows.len(), 2);
        assert_eq!(
            rows[1],
            Node::Seq(
                ["4", "5", "6"]
                    .iter()
                    .map(|s| Node::Scalar(s.to_string(), 5))
                    .collect(),
                5
            )
        );
        let Node::Seq(a, _) = imu.get("A").unwrap() else {
            panic!()
        };
        assert_eq!(a.len(), 2);
        assert_eq!(imu.get("model"), Some(&Node::Scalar("kalibr".into(), 7)));
        assert_eq!(imu.get("empty"), Some(&Node::Scalar(String::new(), 8)));
    }

    #[test]
    fn malformed_lines_name_their_line() {
        for (t, line) in [
            ("a: 1\n  b: 2\n", 2),
            ("a:\n  - [1, 2\n", 2),
            ("a: 1\na: 2\n", 2),
            ("a: 1\njunk\n", 2),
        ] {
            match parse(t, "f.yaml") {
                Err(IoError::Parse { at, .. }) => assert_eq!(at, Location::Line(line), "{t}"),
                other => panic!("{t}: {other:?}"),
            }
        }
    }
}
