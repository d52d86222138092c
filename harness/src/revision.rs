//! What a past revision of the harness can run. Its worker reads today's JSON request but ignores the settings
//! its schema did not declare yet, so a configuration that sets one of those to anything but its default (or its
//! not-applicable value) would silently run as something else there: such a configuration is one the revision
//! cannot run. The settings a revision declares are read from its own `schema/src/columns.rs`; a setting it declared
//! under an earlier name counts as declared (the request carries that name too: `run::worker::request_line`).

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

use schema::{Axis, Settings};

use crate::run::worker::RENAMED;

/// The file that declares every setting (since the JSON worker).
const DECLARATION: &str = "schema/src/columns.rs";

/// A past revision, as far as the configurations it can run go.
pub struct Revision {
    /// The commit, in full.
    pub commit: String,
    /// The settings its schema declares; `None` when it has no declaration to read (then only its worker tells).
    settings: Option<BTreeSet<String>>,
}

impl Revision {
    /// Reads `commit`'s declaration of settings from the repository at `root`.
    pub fn read(root: &Path, commit: &str) -> Revision {
        let source = Command::new("git")
            .current_dir(root)
            .args(["show", &format!("{commit}:{DECLARATION}")])
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).into_owned());
        Revision { commit: commit.to_string(), settings: source.as_deref().and_then(declared_settings) }
    }

    /// Why this revision cannot run `settings` (today's, normalized), or `None` when nothing says it cannot.
    pub fn cannot_run(&self, settings: &Settings) -> Option<String> {
        let known = self.settings.as_ref()?;
        let default = Settings::default();
        let newer: Vec<String> = Axis::ALL
            .iter()
            .filter(|axis| {
                let then = RENAMED.iter().find(|(now, _)| *now == axis.key()).map(|(_, then)| *then);
                !known.contains(axis.key()) && then.is_none_or(|then| !known.contains(then))
            })
            .filter(|&&axis| {
                let cell = settings.get(axis).cell();
                cell != default.get(axis).cell() && axis.not_applicable().is_none_or(|na| cell != na.cell())
            })
            .map(|&axis| format!("{} = {}", axis.key(), settings.get(axis).cell()))
            .collect();
        (!newer.is_empty())
            .then(|| format!("{} is newer than {} (its worker would ignore it)", newer.join(", "), &self.commit[..12]))
    }
}

/// The names in the `settings { … }` block of a schema declaration (`name: Type = default, …;` entries).
fn declared_settings(source: &str) -> Option<BTreeSet<String>> {
    let mut lines = source.lines().skip_while(|l| l.trim() != "settings {");
    lines.next()?;
    let mut names = BTreeSet::new();
    for line in lines {
        let line = line.trim();
        if line == "}" {
            return Some(names);
        }
        if let Some((name, rest)) = line.split_once(':')
            && !name.is_empty()
            && name.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
            && !rest.starts_with(':')
        {
            names.insert(name.to_string());
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_declared_settings_are_the_entries_of_the_settings_block() {
        let source = "declare_columns! {\n    identity {\n        /// Experiment.\n        experiment: String;\n    }\n    \
                      settings {\n        /// Scene: one of `a`, `b`.\n        scene: SceneName = SceneName::A;\n        \
                      leaf_size: Option<u32> = Some(4),\n            range(*BvhParams::LEAF_SIZES.start(), 8), applies tree else None;\n        \
                      seed: u64 = 1;\n    }\n    measures {\n        trace_s: f64, Metric;\n    }\n}\n";
        let names: Vec<String> = declared_settings(source).unwrap().into_iter().collect();
        assert_eq!(names, ["leaf_size", "scene", "seed"]);
        assert_eq!(declared_settings("settings {\n    scene: S = S::A;\n"), None, "unclosed");
        assert_eq!(declared_settings("no settings here"), None);
    }

    #[test]
    fn a_setting_the_revision_does_not_declare_blocks_it_only_away_from_its_default() {
        let all: BTreeSet<String> = Axis::ALL.iter().map(|a| a.key().to_string()).collect();
        let mut older = all.clone();
        older.remove("reinsertion");
        let revision = Revision { commit: "0123456789abcdef".repeat(2), settings: Some(older) };
        let default = Settings::default().normalized();
        assert_eq!(revision.cannot_run(&default), None, "the default is what the older revision does anyway");
        let mut newer = default.clone();
        newer.set(Axis::reinsertion.parse(schema::Raw::Int(2)).unwrap());
        let why = revision.cannot_run(&newer).expect("reinsertion = 2 does not exist there");
        assert!(why.starts_with("reinsertion = 2 is newer than 0123456789ab"), "{why}");
        let current = Revision { commit: revision.commit.clone(), settings: Some(all) };
        assert_eq!(current.cannot_run(&newer), None);
        let mut packets = Settings { accel: schema::Accel::Ours(tracer::accel::AccelKind::WideBvh), ..default.clone() };
        packets.workload = schema::Workload::Rays(tracer::rays::RayKind::Primary);
        packets.set(Axis::packet.parse(schema::Raw::Str("tile-8x8")).unwrap());
        let packets = packets.normalized();
        let mut declared: BTreeSet<String> = current.settings.clone().unwrap();
        declared.remove("packet");
        declared.remove("embree_packet");
        let before_packets = Revision { commit: revision.commit.clone(), settings: Some(declared.clone()) };
        assert!(before_packets.cannot_run(&packets).unwrap().starts_with("packet = tile-8x8 is newer"));
        declared.insert("packet_size".into());
        let packet_size = Revision { commit: revision.commit.clone(), settings: Some(declared) };
        assert_eq!(packet_size.cannot_run(&packets), None, "it declared packets as packet_size");
        let unknown = Revision { commit: revision.commit.clone(), settings: None };
        assert_eq!(unknown.cannot_run(&newer), None, "without a declaration only the worker can tell");
    }

    #[test]
    fn todays_declaration_is_read_whole() {
        let source = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../", "schema/src/columns.rs"))
            .expect("the declaration");
        let names = declared_settings(&source).expect("a settings block");
        let keys: BTreeSet<String> = Axis::ALL.iter().map(|a| a.key().to_string()).collect();
        assert_eq!(names, keys, "every setting and nothing else");
    }
}
