//! `index.html`: every experiment with what it asks, machine, commits, runs, and its claims with verdicts.

use schema::column;

use super::experiment::{Experiment, badge};
use super::html::{escape, page};

/// The index page.
pub fn page_of(experiments: &[Experiment]) -> String {
    let mut body = String::from(
        "<h1>bvhlab results</h1>\n<p>Every experiment recorded under <code>results/</code>: the same rows, summaries \
         and claim verdicts as each folder's <code>REPORT.md</code>. The <a href=\"history.html\">history pages</a> \
         follow instruction counts and speedups over commits.</p>\n",
    );
    for exp in experiments {
        body.push_str(&format!(
            "<section class=\"experiment\">\n<h2><a href=\"{}\">{}</a></h2>\n<p>{}</p>\n<dl class=\"provenance\">\
             <dt>machine</dt><dd>{}</dd><dt>commit</dt><dd>{}</dd><dt>runs</dt><dd>{}</dd></dl>\n",
            escape(&exp.page()),
            escape(&exp.name),
            escape(&exp.spec.description),
            exp.machines().iter().map(|m| escape(m)).collect::<Vec<_>>().join("<br>"),
            exp.distinct(column::git_commit).iter().map(|c| escape(c)).collect::<Vec<_>>().join(", "),
            exp.rows.runs.len()
        ));
        if !exp.claims.is_empty() {
            body.push_str("<ul class=\"claims\">\n");
            for c in &exp.claims {
                body.push_str(&format!("<li>{} {}</li>\n", badge(c.verdict), escape(&c.text)));
            }
            body.push_str("</ul>\n");
        }
        body.push_str("</section>\n");
    }
    page("bvhlab results", &body)
}
