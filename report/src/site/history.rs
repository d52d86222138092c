//! The history pages: a page per tracked configuration of the per-commit instruction history (build and trace
//! tracks, regressions and change points marked, each point linking to its commit on `commits.html`), a page per
//! experiment of the speedup history (`history.csv`), and `history.html` listing them.

use std::path::Path;

use super::chart::{SiteChart, SiteMarks, SitePoint};
use super::html::{escape, num, page, slug};
use crate::error::Error;
use crate::history::change_points::ChangePoint;
use crate::history::commits::{self, CommitEntry, Phase, Track};
use crate::history::{self, SpeedupHistory};

/// The history pages as (file name, HTML), `history.html` first.
pub fn pages(history_dir: &Path) -> Result<Vec<(String, String)>, Error> {
    let commits = commits::read_commits(history_dir)?;
    let counted = commits::read_counted(history_dir)?;
    let tracks = commits::instruction_tracks(&commits, &counted);
    let speedups = history::read(&history_dir.join("history.csv"))?;

    let mut pages = Vec::new();
    let mut index = String::from("<h1>History</h1>\n<h2>Instructions per commit</h2>\n");
    if tracks.is_empty() {
        index.push_str(
            "<p>No per-commit history recorded yet: <code>harness history backfill</code> writes \
             <code>results/history/commits.csv</code> and <code>instructions.csv</code>.</p>\n",
        );
    } else {
        index.push_str(&format!(
            "<p>Callgrind instruction counts of every tracked configuration over {} commits in first-parent order \
             (<a href=\"commits.html\">the commits</a>). A regression: a rise of more than {}% from the previous \
             commit; a change point: a new level (permutation CUSUM test).</p>\n<table class=\"tracks\"><thead><tr>\
             <th>experiment</th><th>series</th><th>point</th><th>commits</th><th>build regressions</th>\
             <th>build change points</th><th>trace regressions</th><th>trace change points</th></tr></thead><tbody>\n",
            commits.len(),
            commits::REGRESSION * 100.0
        ));
        for pair in tracks.chunks(2) {
            let first = &pair[0];
            let file = format!("history-{}.html", slug(&[&first.experiment, &first.series, &first.point]));
            let count = |phase: Phase, what: fn(&Track) -> usize| {
                pair.iter().filter(|t| t.phase == phase).map(what).sum::<usize>()
            };
            let regressions = |t: &Track| t.points.iter().filter(|p| p.regression).count();
            let changes = |t: &Track| t.change_points.len();
            index.push_str(&format!(
                "<tr><td>{}</td><td>{}</td><td><a href=\"{file}\">{}</a></td><td>{}</td><td>{}</td><td>{}</td>\
                 <td>{}</td><td>{}</td></tr>\n",
                escape(&first.experiment),
                escape(&first.series),
                escape(&first.point),
                first.points.len(),
                count(Phase::Build, regressions),
                count(Phase::Build, changes),
                count(Phase::Trace, regressions),
                count(Phase::Trace, changes)
            ));
            pages.push((file, track_page(pair, &commits)));
        }
        index.push_str("</tbody></table>\n");
        pages.push(("commits.html".into(), commits_page(&commits)));
    }

    index.push_str("<h2>Speedups per appended run</h2>\n");
    let histories = history::speedup_histories(&speedups);
    if histories.is_empty() {
        index.push_str(
            "<p>No speedup history (<code>harness history append</code> writes \
                        <code>results/history/history.csv</code>).</p>\n",
        );
    } else {
        index.push_str("<ul>\n");
        for h in &histories {
            let file = format!("speedups-{}.html", slug(&[&h.experiment]));
            let regressions: usize = h.tracks.iter().map(|t| t.regressions.len()).sum();
            let changes: usize = h.tracks.iter().map(|t| t.change_points.len()).sum();
            index.push_str(&format!(
                "<li><a href=\"{file}\">{}</a>: {} tracked speedups over {} runs, {regressions} regressions, \
                 {changes} change points</li>\n",
                escape(&h.experiment),
                h.tracks.len(),
                h.runs.len()
            ));
            let body = format!(
                "<h1>{}: speedup history</h1>\n<p>Every tracked speedup (95% interval) of the appended runs of \
                 <code>history.csv</code>; red crosses: a drop of more than {}% beyond both intervals; rings and \
                 dashed rules: change points.</p>\n{}",
                escape(&h.experiment),
                history::REGRESSION * 100.0,
                speedup_chart(h, &commits).element("chart-0")
            );
            pages.push((file, page(&format!("{}: speedup history", h.experiment), &body)));
        }
        index.push_str("</ul>\n");
    }
    pages.insert(0, ("history.html".into(), page("History", &index)));
    Ok(pages)
}

fn short(commit: &str) -> String {
    commit.chars().take(7).collect()
}

/// The link of a commit on `commits.html`.
fn commit_href(commit: &str) -> String {
    format!("commits.html#{}", escape(commit))
}

/// Marks and rules of change points found at `indices` (into `points`, whose x and y are given).
fn change_marks(changes: &[ChangePoint], at: impl Fn(usize) -> (f64, f64)) -> (SiteMarks, Vec<f64>) {
    let points: Vec<(f64, f64)> = changes.iter().map(|c| at(c.index)).collect();
    let rules = points.iter().map(|p| p.0 - 0.5).collect();
    (SiteMarks { label: "change point (new level from here)".into(), mark: "ring", points }, rules)
}

/// The page of one configuration's build and trace tracks.
fn track_page(pair: &[Track], commits: &[CommitEntry]) -> String {
    let first = &pair[0];
    let title = format!("{} · {} · {}", first.experiment, first.series, first.point);
    let mut body = format!(
        "<h1>{}</h1>\n<p>Instructions (callgrind) per commit, first-parent order; hover a point for its commit, \
         click it for the commit's details. Red crosses: a rise of more than {}% from the previous commit; rings \
         and dashed rules: change points.</p>\n",
        escape(&title),
        commits::REGRESSION * 100.0
    );
    for (k, track) in pair.iter().enumerate() {
        let at = |i: usize| {
            let p = &track.points[i];
            (p.commit as f64, p.instructions as f64)
        };
        let points = track
            .points
            .iter()
            .map(|p| {
                let c = &commits[p.commit];
                let mut tip = vec![
                    format!("{} instructions", track.phase.name()),
                    format!("commit {}", short(&c.commit)),
                    c.subject.clone(),
                    c.date.clone(),
                    format!("count {}", p.instructions),
                ];
                if p.answers_changed {
                    tip.push("answers changed".into());
                }
                let y = p.instructions as f64;
                SitePoint { x: p.commit as f64, y, lo: y, hi: y, tip, href: Some(commit_href(&c.commit)) }
            })
            .collect();
        let regressions: Vec<(f64, f64)> =
            (0..track.points.len()).filter(|&i| track.points[i].regression).map(at).collect();
        let (rings, rules) = change_marks(&track.change_points, at);
        let chart = SiteChart {
            title: format!("{} instructions: {}", track.phase.name(), title),
            x_label: "commit (first-parent order)".into(),
            y_label: format!("{} instructions", track.phase.name()),
            lines: vec![SiteChart::line(track.phase.name().into(), k, points)],
            x_ticks: commits.iter().enumerate().map(|(i, c)| (i as f64, short(&c.commit))).collect(),
            marks: vec![
                SiteMarks {
                    label: format!("regression (rise > {}%)", commits::REGRESSION * 100.0),
                    mark: "cross",
                    points: regressions,
                },
                rings,
            ],
            rules,
            // At least four times the regression gate's rise: a 0.006% change stays a flat line.
            min_span: 4.0 * commits::REGRESSION,
            ..SiteChart::default()
        };
        body.push_str(&chart.element(&format!("chart-{k}")));
        if !track.change_points.is_empty() {
            body.push_str("<ul class=\"changes\">");
            for c in &track.change_points {
                let commit = &commits[track.points[c.index].commit];
                body.push_str(&format!(
                    "<li>{} change point at <a href=\"{}\">{}</a> ({}): {} → {} ({:.1}% confidence)</li>",
                    track.phase.name(),
                    commit_href(&commit.commit),
                    short(&commit.commit),
                    escape(&commit.subject),
                    num(c.before),
                    num(c.after),
                    c.confidence * 100.0
                ));
            }
            body.push_str("</ul>\n");
        }
    }
    page(&title, &body)
}

/// Every visited commit, one anchor per full hash.
fn commits_page(commits: &[CommitEntry]) -> String {
    let mut body = String::from(
        "<h1>Commits</h1>\n<p>Every commit the per-commit history visited, in first-parent order.</p>\n\
         <table class=\"commits\"><thead><tr><th>#</th><th>commit</th><th>date</th><th>subject</th><th>compiler</th>\
         <th>status</th><th>counted</th><th>skipped configurations (why)</th></tr></thead><tbody>\n",
    );
    for c in commits {
        let skipped: Vec<String> = c.skipped.split(" · ").filter(|s| !s.is_empty()).map(escape).collect();
        body.push_str(&format!(
            "<tr id=\"{id}\"><td>{}</td><td><a href=\"#{id}\"><code>{id}</code></a></td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            c.position,
            escape(&c.date),
            escape(&c.subject),
            escape(&c.compiler),
            escape(&c.status),
            c.counted,
            skipped.join("<br>"),
            id = escape(&c.commit)
        ));
    }
    body.push_str("</tbody></table>\n");
    page("Commits", &body)
}

/// The speedup history chart of one experiment.
fn speedup_chart(h: &SpeedupHistory, commits: &[CommitEntry]) -> SiteChart {
    let (mut lines, mut regressions, mut rings, mut rules) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (i, track) in h.tracks.iter().enumerate() {
        let at = |k: usize| (track.entries[k].0 as f64, track.entries[k].1.speedup);
        regressions.extend(track.regressions.iter().map(|&k| at(k)));
        let (marks, r) = change_marks(&track.change_points, at);
        rings.extend(marks.points);
        rules.extend(r);
        let label = format!("{} {}", track.series, track.point);
        let points = track
            .entries
            .iter()
            .map(|&(run, e)| {
                let full = commits.iter().find(|c| c.commit.starts_with(&e.commit) && !e.commit.is_empty());
                SitePoint {
                    x: run as f64,
                    y: e.speedup,
                    lo: e.lower,
                    hi: e.upper,
                    tip: vec![
                        label.clone(),
                        format!("commit {}{}", e.commit, if e.dirty == "true" { " (dirty)" } else { "" }),
                        e.timestamp.clone(),
                        format!("speedup {}", num(e.speedup)),
                        format!("95% interval [{}, {}]", num(e.lower), num(e.upper)),
                    ],
                    href: full.map(|c| commit_href(&c.commit)),
                }
            })
            .collect();
        lines.push(SiteChart::line(label, i, points));
    }
    SiteChart {
        title: format!("{}: speedups over the appended runs", h.experiment),
        x_label: "commit of each appended run, in order".into(),
        y_label: "speedup vs reference (×)".into(),
        log_y: true,
        lines,
        x_ticks: h.runs.iter().enumerate().map(|(i, r)| ((i + 1) as f64, short(&r.commit))).collect(),
        marks: vec![
            SiteMarks {
                label: format!("regression (drop > {}%)", history::REGRESSION * 100.0),
                mark: "cross",
                points: regressions,
            },
            SiteMarks { label: "change point (new level from here)".into(), mark: "ring", points: rings },
        ],
        rules,
        // At least four times the regression threshold's drop around the middle of the speedups.
        min_span: 4.0 * history::REGRESSION,
        ..SiteChart::default()
    }
}
