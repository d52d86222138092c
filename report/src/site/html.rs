//! HTML text: escaping, embedded JSON data and the page shell every page shares.

/// `text` with `&`, `<`, `>`, `"` and `'` escaped, safe in element content and quoted attributes.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// `value` as a `<script type="application/json">` element with id `id` (`</` escaped so no text ends it).
pub fn json_script(id: &str, value: &serde_json::Value) -> String {
    let json = value.to_string().replace("</", "<\\/").replace("<!--", "<\\!--");
    format!("<script type=\"application/json\" id=\"{}\">{json}</script>\n", escape(id))
}

/// A whole number as it is, any other with 4 significant digits (plain between 1e-3 and 1e6), as `site.js` shows it.
pub fn num(value: f64) -> String {
    if !value.is_finite() {
        return "–".into();
    }
    if value.fract() == 0.0 && value.abs() < 1e15 {
        return format!("{value:.0}");
    }
    let magnitude = value.abs().log10().floor() as i32;
    if !(-3..6).contains(&magnitude) {
        return format!("{value:.3e}");
    }
    let decimals = (3 - magnitude).max(0) as usize;
    format!("{value:.decimals$}")
}

/// A whole page: `title`, a navigation bar back to the index and the history, `body`, and the shared script.
pub fn page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>{title}</title>\n\
         <link rel=\"icon\" href=\"data:,\">\n<link rel=\"stylesheet\" href=\"site.css\">\n</head>\n<body>\n\
         <nav><a href=\"index.html\">Experiments</a> · <a href=\"history.html\">History</a></nav>\n\
         <main>\n{body}\n</main>\n<div id=\"tooltip\" class=\"tooltip\" hidden></div>\n\
         <script src=\"site.js\"></script>\n</body>\n</html>\n",
        title = escape(title)
    )
}

/// A file name made of `parts`: lowercase letters, digits and `-`, anything else as `-`.
pub fn slug(parts: &[&str]) -> String {
    let joined = parts.join("-").to_lowercase();
    let mut out = String::new();
    for c in joined.chars() {
        let c = if c.is_ascii_alphanumeric() { c } else { '-' };
        if !(c == '-' && out.ends_with('-')) {
            out.push(c);
        }
    }
    out.trim_matches('-').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_and_json_cannot_break_out_of_their_element() {
        assert_eq!(escape("<a href=\"x\">&'</a>"), "&lt;a href=&quot;x&quot;&gt;&amp;&#39;&lt;/a&gt;");
        let script = json_script("d", &serde_json::json!({ "t": "</script><script>alert(1)</script>" }));
        assert_eq!(script.matches("</script>").count(), 1, "{script}");
        assert!(script.contains("<\\/script>"));
    }

    #[test]
    fn numbers_keep_four_significant_digits() {
        assert_eq!(num(0.012345678), "0.01235");
        assert_eq!(num(15.742156), "15.74");
        assert_eq!(num(123456.0), "123456");
        assert_eq!(num(1234.5678), "1235");
        assert_eq!(num(1e7), "10000000");
        assert_eq!(num(1.5e-5), "1.500e-5");
        assert_eq!(slug(&["ci", "flat-bvh", "objects 1000 (threads 1)"]), "ci-flat-bvh-objects-1000-threads-1");
    }
}
