//! `index.html`: the answers first — the experiments that answer the project's questions, each with its headline
//! (and, for the first, its grid of points) — then every other experiment in a line each.

use schema::column;

use super::experiment::{Experiment, context, headline_html, inline_code, still_holds_html};
use super::html::{escape, page};
use crate::spec::Verdict;

/// The experiments the index leads with, in this order: ours against the peers on real meshes, then the paper's
/// question and the harness's resolution.
pub const LEAD: [&str; 5] = ["incoherent", "meshes", "peers", "paper", "resolution"];

/// How many lead experiments show their grid on the index (the rest: their sentence).
const GRIDS: usize = 2;

/// The claims' verdicts counted, as badges ("5 hold", "2 fail", "1 inconclusive").
fn claim_counts(exp: &Experiment) -> String {
    if exp.claims.is_empty() {
        return String::new();
    }
    [
        (Verdict::Holds, "holds", "hold"),
        (Verdict::Fails, "fails", "fail"),
        (Verdict::Inconclusive, "inconclusive", "inconclusive"),
    ]
    .into_iter()
    .filter_map(|(v, class, word)| {
        let n = exp.claims.iter().filter(|c| c.verdict == v).count();
        (n > 0).then(|| format!("<span class=\"verdict {class}\">{n} {word}</span>"))
    })
    .collect::<Vec<_>>()
    .join(" ")
}

/// The index page.
pub fn page_of(experiments: &[Experiment]) -> String {
    let mut body = String::from(
        "<h1>bvhlab results</h1>\n<p class=\"direction\">Every ratio reads <b>how much faster ours is</b>: the \
         other side's time over ours, above 1 = ours faster; <span class=\"key faster\">green</span> ours faster \
         (95% interval above 1), <span class=\"key slower\">red</span> slower, <span class=\"key same\">grey</span> \
         not told apart. Each experiment's page has its claims, figures and every configuration; the \
         <a href=\"history.html\">history pages</a> follow counters and speedups over commits.</p>\n",
    );
    let lead: Vec<&Experiment> = LEAD.iter().filter_map(|name| experiments.iter().find(|e| e.name == *name)).collect();
    for (i, exp) in lead.iter().enumerate() {
        body.push_str(&format!(
            "<section class=\"lead\" id=\"{name}\">\n<h2><a href=\"{}\">{name}</a> {}</h2>\n{}<p class=\"constant\">{}; \
             {}<br>{}</p>\n</section>\n",
            escape(&exp.page()),
            claim_counts(exp),
            headline_html(exp, i < GRIDS),
            escape(&context(exp)),
            escape(&exp.machines().join(", ")),
            still_holds_html(exp),
            name = escape(&exp.name),
        ));
    }
    body.push_str(
        "<h2>Every other experiment</h2>\n<table class=\"experiments\"><thead><tr><th>experiment</th><th>claims</th>\
         <th>answer</th><th>recorded at</th><th>at HEAD</th></tr></thead><tbody>\n",
    );
    for exp in experiments.iter().filter(|e| !LEAD.contains(&e.name.as_str())) {
        let answer = match &exp.headline {
            Some(h) => escape(&h.sentence()),
            None => inline_code(&exp.spec.description),
        };
        body.push_str(&format!(
            "<tr><td><a href=\"{}\">{}</a></td><td>{}</td><td>{answer}</td><td>{}</td><td>{}</td></tr>\n",
            escape(&exp.page()),
            escape(&exp.name),
            claim_counts(exp),
            exp.distinct(column::git_commit)
                .iter()
                .map(|c| escape(&c[..c.len().min(7)]))
                .collect::<Vec<_>>()
                .join(", "),
            still_holds_html(exp),
        ));
    }
    body.push_str("</tbody></table>\n");
    page("bvhlab results", &body)
}
