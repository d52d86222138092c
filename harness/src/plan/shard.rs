//! Shards: a plan cut into N parts for N machines, whole scene cells at a time.
//!
//! A *cell* is one scene and its work: scene, objects, seed, workload, image size and depth. Every series of a
//! cell (every accelerator, strategy and thread count) lands in one shard, so a speedup over the reference is
//! always a ratio of two timings of one machine. Cells are dealt out largest first (by the cost model at one core,
//! so every machine computes the same cut) to the shard with the least estimated work so far; within a shard the
//! runs keep the plan's order (interleaved rounds, by default).

use schema::Settings;

use super::{Configuration, Plan, estimate_seconds};

/// The settings that make a cell (see the module docs).
fn cell_key(s: &Settings) -> (String, u64, u64, String, u32, u32, u32) {
    (
        schema::Named::name(s.scene).to_string(),
        s.objects,
        s.seed,
        schema::Named::name(s.workload).to_string(),
        s.width,
        s.height,
        s.max_depth,
    )
}

/// The cell of each configuration, numbered in order of first appearance; and the number of cells.
pub fn cells(configurations: &[Configuration]) -> (Vec<usize>, usize) {
    let mut keys = Vec::new();
    let of = configurations
        .iter()
        .map(|c| {
            let key = cell_key(&c.settings);
            keys.iter().position(|k| *k == key).unwrap_or_else(|| {
                keys.push(key);
                keys.len() - 1
            })
        })
        .collect();
    (of, keys.len())
}

/// The 0-based shard of each configuration of `plan` when cut into `n` shards.
pub fn assign(plan: &Plan, n: usize) -> Vec<usize> {
    let (cell_of, cells) = cells(&plan.configurations);
    let mut cost = vec![0.0_f64; cells];
    for run in &plan.runs {
        cost[cell_of[run.config]] += estimate_seconds(&plan.configurations[run.config].settings, 1);
    }
    let mut order: Vec<usize> = (0..cells).collect();
    order.sort_by(|a, b| cost[*b].total_cmp(&cost[*a]).then(a.cmp(b)));
    let (mut load, mut shard_of_cell) = (vec![0.0_f64; n.max(1)], vec![0; cells]);
    for cell in order {
        let lightest = (0..load.len()).min_by(|a, b| load[*a].total_cmp(&load[*b]).then(a.cmp(b))).expect("n >= 1");
        load[lightest] += cost[cell];
        shard_of_cell[cell] = lightest;
    }
    cell_of.iter().map(|cell| shard_of_cell[*cell]).collect()
}

impl Plan {
    /// Keeps only the runs of shard `i` of `n` (1-based) and records the shard for the rows.
    pub fn keep_shard(&mut self, i: usize, n: usize) {
        let shard_of = assign(self, n);
        self.runs.retain(|r| shard_of[r.config] == i - 1);
        self.shard = Some((i, n));
    }

    /// The number of scene cells: the most shards that are not empty.
    pub fn cell_count(&self) -> usize {
        cells(&self.configurations).1
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;
    use std::path::Path;

    use crate::config::Experiment;
    use crate::plan::Plan;

    const TEXT: &str = "name = \"t\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nrepetitions = 2\nreference = \"list\"\n[sweep]\nobjects = [10, 100, 1000]\nseed = [1, 2]\n\
                        workload = \"primary\"\n[[series]]\nlabel = \"list\"\naccel = \"list\"\nstrategy = \"serial\"\n\
                        [[series]]\nlabel = \"par\"\naccel = \"flat-bvh\"\nstrategy = \"rayon-bands\"\nthreads = [1, 2, \"all\"]\n";

    fn plan(cores: usize) -> Plan {
        Plan::new(&Experiment::parse(Path::new("t.toml"), TEXT).unwrap(), cores).unwrap()
    }

    #[test]
    fn shards_cover_the_plan_once_with_every_cell_whole() {
        let full = plan(2);
        assert_eq!(full.cell_count(), 6);
        for n in 1..=7 {
            let mut seen = HashSet::new();
            for i in 1..=n {
                let mut p = plan(2);
                p.keep_shard(i, n);
                assert_eq!(p.shard, Some((i, n)));
                let configs: HashSet<usize> = p.runs.iter().map(|r| r.config).collect();
                for c in &configs {
                    let s = &p.configurations[*c].settings;
                    // Every series of the cell is in this shard.
                    for (j, other) in p.configurations.iter().enumerate() {
                        if (other.settings.objects, other.settings.seed) == (s.objects, s.seed) {
                            assert!(configs.contains(&j), "n={n}: cell objects={} seed={} split", s.objects, s.seed);
                        }
                    }
                }
                for r in &p.runs {
                    assert!(seen.insert((r.config, r.repetition)), "n={n}: run in two shards");
                }
                if n <= 6 {
                    assert!(!p.runs.is_empty(), "shard {i}/{n} is empty");
                }
            }
            assert_eq!(seen.len(), full.runs.len(), "n={n}: every run in some shard");
        }
    }

    #[test]
    fn the_cut_is_the_same_on_every_machine_and_keeps_the_order() {
        let (mut a, mut b) = (plan(2), plan(64));
        a.keep_shard(2, 3);
        b.keep_shard(2, 3);
        let ids =
            |p: &Plan| p.runs.iter().map(|r| (p.configurations[r.config].id.clone(), r.repetition)).collect::<Vec<_>>();
        assert_eq!(ids(&a), ids(&b));
        let full = plan(2);
        let kept: Vec<_> = full.runs.iter().filter(|r| a.runs.contains(r)).copied().collect();
        assert_eq!(kept, a.runs, "interleaved as in the full plan");
    }
}
