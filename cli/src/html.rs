//! A minimal self-contained HTML page: headings, paragraphs, tables and inline SVG charts
//! (the page references no external file, so it can be mailed or archived as one file; the
//! SVGs are also written beside it).

use std::fmt::Write as _;
use std::path::Path;

/// An HTML page under construction.
pub struct Page {
    body: String,
    title: String,
}

/// Escapes text for HTML.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

impl Page {
    /// A new page with a title.
    pub fn new(title: &str) -> Self {
        Self {
            body: format!("<h1>{}</h1>\n", esc(title)),
            title: title.to_string(),
        }
    }

    /// A section heading.
    pub fn h2(&mut self, text: &str) -> &mut Self {
        let _ = writeln!(self.body, "<h2>{}</h2>", esc(text));
        self
    }

    /// A paragraph of plain text.
    pub fn p(&mut self, text: &str) -> &mut Self {
        let _ = writeln!(self.body, "<p>{}</p>", esc(text));
        self
    }

    /// A table with a header row.
    pub fn table(&mut self, header: &[&str], rows: &[Vec<String>]) -> &mut Self {
        self.body.push_str("<table>\n<tr>");
        for h in header {
            let _ = write!(self.body, "<th>{}</th>", esc(h));
        }
        self.body.push_str("</tr>\n");
        for r in rows {
            self.body.push_str("<tr>");
            for c in r {
                let _ = write!(self.body, "<td>{}</td>", esc(c));
            }
            self.body.push_str("</tr>\n");
        }
        self.body.push_str("</table>\n");
        self
    }

    /// Embeds an SVG file written earlier (inline, with a caption).
    pub fn svg(&mut self, path: &Path, caption: &str) -> Result<&mut Self, String> {
        let svg = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("chart.svg");
        let _ = writeln!(
            self.body,
            "<figure data-file=\"{}\">{}<figcaption>{}</figcaption></figure>",
            esc(name),
            svg.trim_start_matches(|c| c != '<'),
            esc(caption)
        );
        Ok(self)
    }

    /// Writes the page.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        let html = format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>\
             body{{font-family:sans-serif;max-width:1000px;margin:2em auto;line-height:1.45}}\
             table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #bbb;padding:3px 8px;text-align:right}}\
             figure{{margin:1em 0}}figcaption{{color:#444;font-size:90%}}</style></head>\n<body>\n{}</body></html>\n",
            esc(&self.title),
            self.body
        );
        std::fs::write(path, html).map_err(|e| format!("{}: {e}", path.display()))
    }
}
