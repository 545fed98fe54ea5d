//! The one HTML look of csm-lab's reports (`report.html` of `sweep`, `compare.html` of
//! `compare`): a page shell with one stylesheet, tables, inline figures, and the escaping that
//! HTML and XML outputs (JUnit included) share.
//!
//! Pages are self-contained (inline CSS, SVG and PNG data URIs; nothing fetched, no figure read
//! from a file beside the page) and well-formed XML, so they open offline, sent on their own,
//! and parse with an XML reader.

use std::fmt::Write as _;

/// The stylesheet of every report page.
const CSS: &str = "body{font-family:'DejaVu Sans',Helvetica,Arial,sans-serif;max-width:1320px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}\
h1{font-size:1.6em}h2{margin-top:1.8em;border-bottom:1px solid #ddd}\
table{border-collapse:collapse;font-size:0.92em;margin:1em 0}td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}\
th{background:#f3f3f3}td.l,th.l{text-align:left}tr.rec{background:#ffecec;font-weight:bold}\
.rec-box{background:#f6fbf6;border-left:5px solid #2a9d4a;padding:0.8em 1em}\
figure{margin:1.5em 0}figure svg{max-width:100%;height:auto;border:1px solid #eee}figcaption{color:#555;font-size:0.92em}\
pre,code{background:#f5f5f5}pre{padding:0.8em;overflow-x:auto}code{padding:2px 4px}\
ul.notes{font-size:0.92em}dl.defs{font-size:0.88em;color:#444;margin:0.3em 0 1.2em}dl.defs dt{font-weight:bold;float:left;clear:left;margin-right:0.5em}dl.defs dd{margin:0 0 0.2em 0}p.footer{color:#555;font-size:0.92em}";

/// Escapes text for HTML and XML content and attribute values: markup characters, both
/// quote kinds, newlines and tabs as character references (attribute values keep them), and
/// characters XML 1.0 cannot carry replaced by U+FFFD.
pub(crate) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            '\t' => out.push_str("&#9;"),
            // XML 1.0 Char: #x9 | #xA | #xD | [#x20-#xD7FF] | [#xE000-#xFFFD] | [#x10000-#x10FFFF].
            c if (c as u32) < 0x20 || c == '\u{FFFE}' || c == '\u{FFFF}' => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

/// An SVG document made fit for inlining in a page: no XML declaration, no namespace URIs
/// (an HTML parser places `<svg>` in the SVG namespace by itself).
pub(crate) fn inline_svg(svg: &[u8]) -> String {
    let text = String::from_utf8_lossy(svg);
    let text = match text.find("<svg") {
        Some(i) => &text[i..],
        None => &text[..],
    };
    text.trim()
        .replace(" xmlns=\"http://www.w3.org/2000/svg\"", "")
        .replace(" xmlns:xlink=\"http://www.w3.org/1999/xlink\"", "")
}

/// A figure: the inline SVG and its caption.
pub(crate) fn figure(svg: &[u8], caption: &str) -> String {
    format!(
        "<figure>{}<figcaption>{}</figcaption></figure>\n",
        inline_svg(svg),
        escape(caption)
    )
}

/// The largest SVG inlined in a page as SVG; a larger one (a figure of a big grid) is inlined
/// as its PNG file (at most the page's width, [`crate::figures::png_scale`]), linked to the
/// full files beside the page, so the page stays small and still shows every figure when sent
/// on its own.
pub(crate) const INLINE_SVG_LIMIT: usize = 256 * 1024;

/// A figure inlined as a PNG data URI, linked to the full `{stem}.svg` and `{stem}.png` beside
/// the page.
pub(crate) fn figure_png(stem: &str, png: &[u8], width: u32, caption: &str, svg_bytes: usize) -> String {
    format!(
        "<figure><a href=\"{0}.svg\"><img style=\"max-width: 100%\" src=\"data:image/png;base64,{2}\" alt=\"{1}\"/></a><figcaption>{1} (inlined as a {3}-pixel-wide PNG; the full figure: <a href=\"{0}.svg\">{0}.svg</a>, {4} KiB, and <a href=\"{0}.png\">{0}.png</a>, beside this page)</figcaption></figure>\n",
        escape(stem),
        escape(caption),
        base64(png),
        width,
        svg_bytes.div_ceil(1024)
    )
}

/// What a page inlines in place of an SVG larger than [`INLINE_SVG_LIMIT`]: the figure's PNG
/// file itself (`png`, `width` pixels wide: the size a page shows it,
/// [`crate::figures::png_scale`]), so the figure is rasterised and encoded once: (PNG bytes,
/// width in pixels). None for an SVG small enough to inline as it is.
pub(crate) fn inline_png(svg: &[u8], png: &[u8], width: u32) -> Option<(Vec<u8>, u32)> {
    (svg.len() > INLINE_SVG_LIMIT).then(|| (png.to_vec(), width))
}

/// Inline as SVG when small, as the PNG [`inline_png`] made when not ([`INLINE_SVG_LIMIT`]):
/// never a reference to a file the page needs.
pub(crate) fn figure_bounded(stem: &str, svg: &[u8], caption: &str, png: Option<&(Vec<u8>, u32)>) -> String {
    match png {
        Some((png, width)) => figure_png(stem, png, *width, caption, svg.len()),
        None => figure(svg, caption),
    }
}

/// Definitions of a table's columns, as a definition list under the table: (term, text).
pub(crate) fn definitions<K: AsRef<str>, V: AsRef<str>>(defs: &[(K, V)]) -> String {
    let mut h = String::from("<dl class=\"defs\">\n");
    for (k, v) in defs {
        let _ = writeln!(
            h,
            "<dt>{}</dt><dd>{}</dd>",
            escape(k.as_ref()),
            code_spans(&escape(v.as_ref()))
        );
    }
    h.push_str("</dl>\n");
    h
}

/// `name` in backticks → `<code>name</code>` (on escaped text).
fn code_spans(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for (i, part) in s.split('`').enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<code>{part}</code>");
        } else {
            out.push_str(part);
        }
    }
    out
}

/// Raster images side by side (PNG bytes embedded as base64 data URIs), each with its caption.
pub(crate) fn png_figures(images: &[(Vec<u8>, String)]) -> String {
    let mut out = String::from("<div style=\"display: flex; flex-wrap: wrap; gap: 1em\">");
    for (png, caption) in images {
        out.push_str(&format!(
            "<figure style=\"flex: 1 1 420px; margin: 0\"><img style=\"width: 100%\" alt=\"{0}\" src=\"data:image/png;base64,{1}\"/><figcaption>{0}</figcaption></figure>",
            escape(caption),
            base64(png)
        ));
    }
    out.push_str("</div>\n");
    out
}

/// Standard base64 with padding. Three bytes at a time into a byte buffer (a page inlines
/// hundreds of kilobytes of PNG: pushing each character onto a `String` cost three times as much).
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = vec![b'='; bytes.len().div_ceil(3) * 4];
    let sextet = |n: u32, i: u32| ALPHABET[(n >> (18 - 6 * i) & 63) as usize];
    let mut quads = out.chunks_exact_mut(4);
    for (src, dst) in bytes.chunks_exact(3).zip(&mut quads) {
        let n = u32::from(src[0]) << 16 | u32::from(src[1]) << 8 | u32::from(src[2]);
        dst.copy_from_slice(&[sextet(n, 0), sextet(n, 1), sextet(n, 2), sextet(n, 3)]);
    }
    let rest = bytes.chunks_exact(3).remainder();
    if let (false, Some(dst)) = (rest.is_empty(), quads.next()) {
        let n = u32::from(rest[0]) << 16 | u32::from(*rest.get(1).unwrap_or(&0)) << 8;
        // One byte left gives two characters, two give three; the rest stays padding.
        for (i, d) in dst.iter_mut().enumerate().take(rest.len() + 1) {
            *d = sextet(n, i as u32);
        }
    }
    // Every byte is from the alphabet or '=': ASCII.
    String::from_utf8(out).unwrap_or_default()
}

/// A table of already formatted cells. Columns listed in `left` are left-aligned (text),
/// the others right-aligned (numbers); the row at `highlight` is marked as the recommended one.
pub(crate) fn table<S: AsRef<str>>(
    header: &[&str],
    rows: &[Vec<S>],
    left: &[usize],
    highlight: Option<usize>,
) -> String {
    let class = |j: usize| if left.contains(&j) { " class=\"l\"" } else { "" };
    let mut h = String::from("<table>\n<tr>");
    for (j, c) in header.iter().enumerate() {
        let _ = write!(h, "<th{}>{}</th>", class(j), escape(c));
    }
    h.push_str("</tr>\n");
    for (k, row) in rows.iter().enumerate() {
        let _ = write!(h, "<tr{}>", if highlight == Some(k) { " class=\"rec\"" } else { "" });
        for (j, cell) in row.iter().enumerate() {
            let _ = write!(h, "<td{}>{}</td>", class(j), escape(cell.as_ref()));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    h
}

/// A two-column table of labelled facts.
pub(crate) fn facts<K: AsRef<str>, V: AsRef<str>>(pairs: &[(K, V)]) -> String {
    let mut h = String::from("<table>\n");
    for (k, v) in pairs {
        let _ = writeln!(
            h,
            "<tr><th class=\"l\">{}</th><td class=\"l\">{}</td></tr>",
            escape(k.as_ref()),
            escape(v.as_ref())
        );
    }
    h.push_str("</table>\n");
    h
}

/// A bulleted list of text lines.
pub(crate) fn list<S: AsRef<str>>(lines: &[S], class: Option<&str>) -> String {
    let mut h = match class {
        Some(c) => format!("<ul class=\"{}\">\n", escape(c)),
        None => String::from("<ul>\n"),
    };
    for l in lines {
        let _ = writeln!(h, "<li>{}</li>", escape(l.as_ref()));
    }
    h.push_str("</ul>\n");
    h
}

/// A whole page: `title` for the browser tab, `heading` as the `<h1>`, then `body` (already
/// markup) and a footer naming the csm-lab version, with `footer_note` (markup) after it.
pub fn page(title: &str, heading: &str, body: &str, footer_note: &str) -> Vec<u8> {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"/>\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\
         <title>{}</title><style>{CSS}</style></head><body>\n<h1>{}</h1>\n",
        escape(title),
        escape(heading)
    );
    h.push_str(body);
    let _ = writeln!(
        h,
        "<p class=\"footer\">Generated by csm-lab {}.{}{footer_note}</p>\n</body></html>",
        env!("CARGO_PKG_VERSION"),
        if footer_note.is_empty() { "" } else { " " }
    );
    h.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Base64 one character at a time (the encoding before it was done three bytes at a time).
    fn base64_by_character(bytes: &[u8]) -> String {
        const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for chunk in bytes.chunks(3) {
            let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
            let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
            for i in 0..4 {
                out.push(if i <= chunk.len() {
                    ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char
                } else {
                    '='
                });
            }
        }
        out
    }

    #[test]
    fn base64_gives_the_standards_test_vectors() {
        // RFC 4648, section 10.
        for (text, code) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(text.as_bytes()), code);
        }
    }

    proptest! {
        #[test]
        fn base64_three_bytes_at_a_time_is_base64_by_character(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
            prop_assert_eq!(base64(&bytes), base64_by_character(&bytes));
        }
    }

    #[test]
    fn escaping_covers_markup_quotes_and_control_characters() {
        assert_eq!(escape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&apos;");
        assert_eq!(escape("x\ny\tz"), "x&#10;y&#9;z");
        assert_eq!(escape("bell\u{7}"), "bell\u{FFFD}");
        assert_eq!(escape("ünï"), "ünï");
        // Whatever goes in comes back from a real parser, minus the unrepresentable ones.
        let nasty = "]]> <!-- & \"quoted\" 'single' \r\n\u{1} end";
        let doc = format!("<a b=\"{}\">{}</a>", escape(nasty), escape(nasty));
        let parsed = roxmltree::Document::parse(&doc).unwrap();
        let root = parsed.root_element();
        let expected = nasty.replace('\u{1}', "\u{FFFD}");
        assert_eq!(root.attribute("b"), Some(expected.as_str()));
        assert_eq!(root.text(), Some(expected.as_str()));
    }

    #[test]
    fn inline_svg_drops_the_declaration_and_namespaces() {
        let svg = b"<?xml version=\"1.0\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"2\"></svg>\n";
        assert_eq!(inline_svg(svg), "<svg width=\"2\"></svg>");
    }

    #[test]
    fn a_page_is_well_formed_xml() {
        let body = table(&["a", "b"], &[vec!["1".to_string(), "<2>".to_string()]], &[0], Some(0));
        let page = page("t & t", "h", &body, "");
        let text = String::from_utf8(page).unwrap();
        roxmltree::Document::parse_with_options(
            &text,
            roxmltree::ParsingOptions {
                allow_dtd: true,
                ..Default::default()
            },
        )
        .unwrap();
    }
}
