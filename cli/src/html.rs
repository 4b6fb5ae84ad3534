//! A minimal self-contained HTML page: headings with a table of contents, a conclusions box,
//! paragraphs, tables and inline SVG charts. The page references no external file (no
//! stylesheet, script, font or image), so it can be mailed or archived as one file; the SVGs
//! are also written beside it. Text between backticks is set as code; a table cell holding a
//! scheme's name carries the scheme's chart colour ([`crate::charts::scheme_color`]).

use crate::charts::scheme_color;
use crate::scheme;
use std::fmt::Write as _;
use std::path::Path;

/// Where [`Page::toc`] puts the table of contents, filled in by [`Page::write`].
const TOC_MARK: &str = "<!--toc-->";

/// An HTML page under construction.
pub struct Page {
    body: String,
    title: String,
    /// (id, text) of each section heading.
    sections: Vec<(String, String)>,
}

/// Escapes text for HTML.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Escapes text for HTML and sets the parts between backticks as `<code>`.
pub fn inline(s: &str) -> String {
    let mut out = String::new();
    for (i, part) in s.split('`').enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<code>{}</code>", esc(part));
        } else {
            out.push_str(&esc(part));
        }
    }
    out
}

/// An id for a heading: lower-case ASCII letters and digits, runs of anything else as `-`.
fn slug(text: &str) -> String {
    let mut s = String::new();
    for c in text.chars() {
        if c.is_ascii_alphanumeric() {
            s.push(c.to_ascii_lowercase());
        } else if !s.ends_with('-') {
            s.push('-');
        }
    }
    s.trim_matches('-').to_string()
}

/// The style sheet: the layout scales to the window (charts at 100 % of the text width up to
/// their natural size), and each scheme's colour marks its name in tables.
fn style() -> String {
    let mut css = String::from(
        "*{box-sizing:border-box}\
         body{font-family:sans-serif;max-width:1000px;margin:0 auto;padding:1em 16px;line-height:1.45;color:#222;overflow-wrap:break-word}\
         h1{font-size:1.55em;margin:.3em 0}h2{margin-top:1.8em;padding-bottom:.15em;border-bottom:1px solid #ccc}\
         code{font-family:monospace;font-size:95%;background:#f0f0f0;padding:0 .25em;border-radius:3px}\
         figure{margin:1.2em 0}figure svg{display:block;width:100%;max-width:960px;height:auto}\
         figcaption{color:#444;font-size:90%;margin-top:.3em}\
         table{border-collapse:collapse;margin:.8em 0 1.2em;font-size:14px;max-width:100%}\
         td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}\
         th{background:#f4f4f4;text-align:left}td:first-child,td.scheme{text-align:left}\
         .conclusions{border:2px solid #444;border-radius:4px;background:#fafaf5;padding:.2em 1.2em .6em;margin:1.2em 0}\
         .conclusions h2{margin-top:.5em;border:0}.conclusions li{margin:.35em 0}\
         nav ol{columns:2;column-gap:2.5em;margin:.5em 0}nav li{break-inside:avoid}\
         @media (max-width:700px){nav ol{columns:1}}\
         .scheme::before{content:\"\";display:inline-block;width:.75em;height:.75em;border-radius:50%;margin-right:.35em;vertical-align:-.05em}",
    );
    for s in scheme::ALL {
        let _ = write!(
            css,
            ".s-{}::before{{background:{}}}",
            scheme::label(s),
            scheme_color(s).hex()
        );
    }
    css
}

impl Page {
    /// A new page with a title.
    pub fn new(title: &str) -> Self {
        Self {
            body: format!("<h1>{}</h1>\n", esc(title)),
            title: title.to_string(),
            sections: Vec::new(),
        }
    }

    /// A section heading (with an id, listed in the table of contents).
    pub fn h2(&mut self, text: &str) -> &mut Self {
        let id = slug(text);
        let _ = writeln!(self.body, "<h2 id=\"{id}\">{}</h2>", inline(text));
        self.sections.push((id, text.to_string()));
        self
    }

    /// A paragraph (backticks: code).
    pub fn p(&mut self, text: &str) -> &mut Self {
        let _ = writeln!(self.body, "<p>{}</p>", inline(text));
        self
    }

    /// A paragraph (backticks: code) ending in a link to `href`, a file beside the page, shown
    /// as its name in code.
    pub fn p_link(&mut self, text: &str, href: &str) -> &mut Self {
        let _ = writeln!(
            self.body,
            "<p>{} <a href=\"{}\"><code>{}</code></a></p>",
            inline(text),
            esc(href),
            esc(href)
        );
        self
    }

    /// The conclusions box: a heading and one list item per statement (backticks: code).
    pub fn conclusions(&mut self, items: &[String]) -> &mut Self {
        self.body.push_str(
            "<section id=\"conclusions\" class=\"conclusions\">\n<h2>Conclusions</h2>\n<ul>\n",
        );
        for i in items {
            let _ = writeln!(self.body, "<li>{}</li>", inline(i));
        }
        self.body.push_str("</ul>\n</section>\n");
        self
    }

    /// The table of contents of every section heading, filled in when the page is written.
    pub fn toc(&mut self) -> &mut Self {
        self.body.push_str(TOC_MARK);
        self
    }

    /// A table with a header row (backticks: code; a cell that is a scheme's name is marked
    /// with the scheme's colour).
    pub fn table(&mut self, header: &[&str], rows: &[Vec<String>]) -> &mut Self {
        self.body.push_str("<table>\n<tr>");
        for h in header {
            let _ = write!(self.body, "<th>{}</th>", inline(h));
        }
        self.body.push_str("</tr>\n");
        for r in rows {
            self.body.push_str("<tr>");
            for c in r {
                match scheme::ALL.iter().find(|&&s| scheme::label(s) == c) {
                    Some(_) => {
                        let _ = write!(self.body, "<td class=\"scheme s-{c}\">{c}</td>");
                    }
                    None => {
                        let _ = write!(self.body, "<td>{}</td>", inline(c));
                    }
                }
            }
            self.body.push_str("</tr>\n");
        }
        self.body.push_str("</table>\n");
        self
    }

    /// Embeds an SVG file written earlier (inline, with a caption; backticks: code).
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
            inline(caption)
        );
        Ok(self)
    }

    /// Writes the page.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        let mut toc = String::from("<nav><ol>");
        for (id, text) in &self.sections {
            let _ = write!(toc, "<li><a href=\"#{id}\">{}</a></li>", inline(text));
        }
        toc.push_str("</ol></nav>\n");
        let html = format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
             <title>{}</title>\n<style>{}</style></head>\n<body>\n{}</body></html>\n",
            esc(&self.title),
            style(),
            self.body.replacen(TOC_MARK, &toc, 1)
        );
        if let Some((line, text)) = preint_io::error::non_finite_line(&html) {
            return Err(format!(
                "{}: not written: line {line} of the page would hold a non-finite number ({text})",
                path.display()
            ));
        }
        std::fs::write(path, html).map_err(|e| format!("{}: {e}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backticks_become_code_and_headings_get_ids() {
        assert_eq!(
            inline("run `a < b` & `c`"),
            "run <code>a &lt; b</code> &amp; <code>c</code>"
        );
        assert_eq!(
            slug("Where methods fail: Euler angles"),
            "where-methods-fail-euler-angles"
        );
    }
}
