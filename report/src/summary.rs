//! Per-configuration summaries (`summary.csv`, `summary.parquet`): polars aggregates each
//! configuration's repetitions; 95% intervals and speedups are added from the plain samples.

use polars_core::prelude::*;
use schema::column;

use crate::pool;
use crate::rows::{Rows, Run, SETTINGS};
use crate::spec::ReportSpec;
use crate::stats;

/// Metrics summarised per configuration.
pub const METRICS: [&str; 4] = [column::total_s, column::trace_s, column::build_s, column::mrays_per_s];

/// Columns equal in every repetition of a configuration (the schema's counters), carried from the first one.
fn deterministic() -> Vec<&'static str> {
    schema::row::counter_names()
}

/// Statistics per metric, in column order (`<metric>_<stat>`).
const STATS: [&str; 7] = ["mean", "median", "std", "min", "max", "median_lo", "median_hi"];

/// One row per configuration (first-appearance order) with the columns described in the crate docs.
pub fn summarise(rows: &Rows, spec: &ReportSpec) -> PolarsResult<DataFrame> {
    let mut frame = aggregate(&rows.frame)?;

    let text = |name: &str| -> PolarsResult<Vec<String>> {
        Ok(frame.column(name)?.str()?.iter().map(|v| v.unwrap_or("").to_string()).collect())
    };
    let (ids, machines) = (text(column::config_id)?, text(column::machine_id)?);
    let groups: Vec<Vec<&Run>> = ids
        .iter()
        .zip(&machines)
        .map(|(id, m)| {
            rows.runs.iter().filter(|run| run.config_id() == id && run.text(column::machine_id) == m).collect()
        })
        .collect();

    for metric in METRICS {
        let intervals: Vec<stats::Estimate> = ids
            .iter()
            .zip(&groups)
            .map(|(_, group)| stats::median_ci(&pool::samples(group.iter().copied(), metric)))
            .collect();
        frame.with_column(float_column(&format!("{metric}_median_lo"), intervals.iter().map(|e| Some(e.lo))))?;
        frame.with_column(float_column(&format!("{metric}_median_hi"), intervals.iter().map(|e| Some(e.hi))))?;
    }

    // Speedups are against the page's bar (the headline's, else the reference): how much faster each configuration is.
    let bar = spec.bar();
    let speedups: Vec<Option<stats::Estimate>> = ids
        .iter()
        .zip(&groups)
        .map(|(id, group)| {
            let reference = bar.as_deref()?;
            let key = format!("{id}|speedup");
            let metric = spec.speedup_metric_of(group.first()?.text(column::workload));
            pool::ratio_against(spec, &rows.runs, reference, group, metric, &[], &key)
        })
        .collect();
    let speedup_metrics: Vec<Option<&str>> = groups
        .iter()
        .map(|g| bar.as_ref().and(g.first()).map(|r| spec.speedup_metric_of(r.text(column::workload))))
        .collect();
    frame.with_column(Column::new("speedup_metric".into(), speedup_metrics))?;
    let against: Vec<Option<&str>> = groups.iter().map(|_| bar.as_deref()).collect();
    frame.with_column(Column::new("speedup_against".into(), against))?;
    frame.with_column(float_column("speedup", speedups.iter().map(|e| e.map(|e| e.value))))?;
    frame.with_column(float_column("speedup_lo", speedups.iter().map(|e| e.map(|e| e.lo))))?;
    frame.with_column(float_column("speedup_hi", speedups.iter().map(|e| e.map(|e| e.hi))))?;

    frame.select(column_order())
}

/// Per configuration and machine (timings of different machines are never pooled), in first-appearance order:
/// the settings and counters of the first row, the row count `n`, and per metric its mean, median, sample
/// standard deviation (0 for one row), minimum and maximum.
///
/// polars' eager group-by: its lazy engine would bring its streaming engine and cloud I/O (tokio, object_store,
/// rustls, ...) into the build, about 90 s of compile on 2 cores for the same numbers (docs/build.md, "Build time").
#[allow(deprecated)] // the eager aggregates are deprecated in favour of the lazy ones
fn aggregate(rows: &DataFrame) -> PolarsResult<DataFrame> {
    let groups = rows.group_by_stable([column::config_id, column::machine_id])?;
    let firsts: Vec<&str> = [column::experiment, column::series]
        .into_iter()
        .chain(SETTINGS.iter().copied())
        .chain(deterministic())
        .collect();
    let mut frame = groups.clone().select(firsts.clone()).first()?;
    for name in firsts {
        frame.rename(&format!("{name}_first"), name.into())?;
    }
    let count = groups.clone().select([column::series]).count()?;
    frame.with_column(count.column("series_count")?.cast(&DataType::Int64)?.with_name("n".into()))?;
    for metric in METRICS {
        let stats: [(&str, DataFrame, String); 5] = [
            ("mean", groups.clone().select([metric]).mean()?, format!("{metric}_mean")),
            ("median", groups.clone().select([metric]).median()?, format!("{metric}_median")),
            ("std", groups.clone().select([metric]).std(1)?, format!("{metric}_agg_std")),
            ("min", groups.clone().select([metric]).min()?, format!("{metric}_min")),
            ("max", groups.clone().select([metric]).max()?, format!("{metric}_max")),
        ];
        for (stat, aggregated, name) in stats {
            let mut column = aggregated.column(&name)?.clone().with_name(format!("{metric}_{stat}").into());
            if stat == "std" {
                column = column.fill_null(FillNullStrategy::Zero)?;
            }
            frame.with_column(column)?;
        }
    }
    Ok(frame)
}

/// The summary's columns in output order.
fn column_order() -> Vec<String> {
    let mut names: Vec<String> = [column::config_id, column::machine_id, column::experiment, column::series]
        .iter()
        .chain(SETTINGS.iter())
        .map(|c| c.to_string())
        .collect();
    names.push("n".into());
    for metric in METRICS {
        names.extend(STATS.iter().map(|stat| format!("{metric}_{stat}")));
    }
    names.extend(deterministic().into_iter().map(String::from));
    names.extend(["speedup_metric", "speedup", "speedup_lo", "speedup_hi"].map(String::from));
    names
}

fn float_column(name: &str, values: impl Iterator<Item = Option<f64>>) -> Column {
    Column::new(name.into(), values.collect::<Vec<Option<f64>>>())
}
