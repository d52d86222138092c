//! What the user sees while a sweep runs: a progress bar on a terminal, plain lines otherwise, both with the
//! estimated time left from the first run on.
//!
//! The estimate weighs every run by its configuration's cost: the cost model's seconds before a configuration
//! ran ([`crate::plan::estimate_seconds`], scaled by how far off the model was on the runs so far), then the
//! mean wall time of its own runs. The runs still expected come from the sweep (with `repetitions = "auto"`
//! an expectation, see `run::stopping`).

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// Writes to standard output or standard error, as [`say!`] and [`note!`] do. A reader that has gone (a closed
/// pipe, as in `harness list | head -1`) ends the process quietly with exit 0, as `ls | head` does; any other
/// write error ends it with exit 1 and one line on standard error. Worker pipes never come here: the worker
/// protocol writes through its own handle and fails loudly.
pub fn write_or_exit(to_stderr: bool, text: std::fmt::Arguments<'_>) {
    let written = if to_stderr {
        writeln!(std::io::stderr().lock(), "{text}")
    } else {
        let mut out = std::io::stdout().lock();
        out.write_fmt(format_args!("{text}\n")).and_then(|()| out.flush())
    };
    match written {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
        Err(e) => {
            let _ = writeln!(
                std::io::stderr(),
                "error: cannot write to {}: {e}",
                if to_stderr { "stderr" } else { "stdout" }
            );
            std::process::exit(1);
        }
    }
}

/// `println!` that ends the process quietly when standard output's reader has gone ([`write_or_exit`]).
macro_rules! say {
    () => { $crate::output::write_or_exit(false, format_args!("")) };
    ($($arg:tt)*) => { $crate::output::write_or_exit(false, format_args!($($arg)*)) };
}

/// `eprintln!` that ends the process quietly when standard error's reader has gone ([`write_or_exit`]).
macro_rules! note {
    ($($arg:tt)*) => { $crate::output::write_or_exit(true, format_args!($($arg)*)) };
}

use indicatif::{ProgressBar, ProgressStyle};

/// Progress over a sweep's runs.
pub struct Progress {
    bar: Option<ProgressBar>,
    /// The cost model's seconds for one run of each configuration.
    model: Vec<f64>,
    /// Wall seconds and count of each configuration's finished runs.
    measured: Vec<(f64, u32)>,
    /// Wall seconds of each configuration's validation (its counted pass, once, before its first run).
    validation: Vec<Option<f64>>,
    started: Instant,
    done: usize,
    /// Runs still expected, and their expected seconds.
    runs_left: f64,
    seconds_left: f64,
    /// When the last plain line was printed (lines come at most every 2 s, and for slow runs).
    last_line: Option<Instant>,
}

/// `1h02m`, `4m05s` or `12s`.
pub fn duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m{:02}s", s / 60, s % 60),
        _ => format!("{}h{:02}m", s / 3600, s / 60 % 60),
    }
}

impl Progress {
    /// Progress over runs of configurations whose cost model gives `model[config]` seconds per run.
    pub fn new(model: Vec<f64>) -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = ProgressBar::new(0);
            bar.set_style(
                ProgressStyle::with_template("{bar:40} {pos}/~{len} runs, {elapsed} elapsed, {prefix}  {msg}")
                    .expect("valid template"),
            );
            bar.enable_steady_tick(Duration::from_millis(250));
            bar
        });
        let measured = vec![(0.0, 0); model.len()];
        Self {
            bar,
            validation: vec![None; model.len()],
            model,
            measured,
            started: Instant::now(),
            done: 0,
            runs_left: 0.0,
            seconds_left: 0.0,
            last_line: None,
        }
    }

    /// How far off the cost model has been: measured seconds over modelled seconds of the configurations run.
    fn model_scale(&self) -> f64 {
        let (mut measured, mut modelled) = (0.0, 0.0);
        for (&(seconds, n), &model) in self.measured.iter().zip(&self.model) {
            if n > 0 {
                measured += seconds;
                modelled += model * n as f64;
            }
        }
        if modelled > 0.0 { measured / modelled } else { 1.0 }
    }

    /// Expected seconds of one more run of `config`.
    fn run_seconds(&self, config: usize, scale: f64) -> f64 {
        match self.measured[config] {
            (seconds, n) if n > 0 => seconds / n as f64,
            _ => self.model[config] * scale,
        }
    }

    /// Validation over a run, as measured so far (1 before any configuration has both).
    fn validation_ratio(&self) -> f64 {
        let (mut validation, mut run) = (0.0, 0.0);
        for (v, &(seconds, n)) in self.validation.iter().zip(&self.measured) {
            if let (Some(v), true) = (v, n > 0) {
                validation += v;
                run += seconds / n as f64;
            }
        }
        if run > 0.0 { validation / run } else { 1.0 }
    }

    /// Records that `config` was validated in `seconds` (before its first run).
    pub fn validated(&mut self, config: usize, seconds: f64) {
        self.validation[config] = Some(seconds);
    }

    /// Sets what is left: `runs[config]` further runs expected of each configuration (a configuration not yet
    /// validated also costs its validation, estimated from those so far).
    pub fn update(&mut self, runs: &[f64]) {
        let (scale, validation) = (self.model_scale(), self.validation_ratio());
        let (mut count, mut seconds) = (0.0, 0.0);
        for (config, &r) in runs[..self.model.len()].iter().enumerate() {
            if r > 0.0 {
                let run = self.run_seconds(config, scale);
                count += r;
                seconds += r * run + if self.validation[config].is_none() { validation * run } else { 0.0 };
            }
        }
        let first = self.done == 0 && self.last_line.is_none();
        (self.runs_left, self.seconds_left) = (count, seconds);
        match &self.bar {
            Some(bar) => {
                bar.set_length((self.done as f64 + count).round() as u64);
                bar.set_prefix(format!("about {} left", duration(seconds)));
            }
            None if first => {
                note!("about {:.0} runs, estimated {} (cost model, within about 2x)", count, duration(seconds));
                if seconds > LONG_RUN_S {
                    note!("{}", long_run_warning(seconds));
                }
                self.last_line = Some(Instant::now());
            }
            None => {}
        }
    }

    /// Marks one run of `config` finished, after `seconds` of wall time; `what` describes it.
    pub fn finished(&mut self, config: usize, seconds: f64, what: &str) {
        let m = &mut self.measured[config];
        *m = (m.0 + seconds, m.1 + 1);
        self.show(seconds, what);
    }

    /// Marks one planned run done without timing it (its configuration failed validation).
    pub fn untimed(&mut self, what: &str) {
        self.show(0.0, what);
    }

    fn show(&mut self, seconds: f64, what: &str) {
        self.done += 1;
        match &self.bar {
            Some(bar) => {
                bar.set_message(what.to_string());
                bar.inc(1);
            }
            None => {
                let now = Instant::now();
                if self.last_line.is_none_or(|t| now - t >= Duration::from_secs(2)) || seconds >= 1.0 {
                    // The estimate printed is the one from before this run (update() follows): close enough.
                    note!(
                        "[{}/~{:.0}] {} elapsed, about {} left: {what}",
                        self.done,
                        self.done as f64 + self.runs_left - 1.0,
                        duration(self.started.elapsed().as_secs_f64()),
                        duration(self.seconds_left - seconds.min(self.seconds_left))
                    );
                    self.last_line = Some(now);
                }
            }
        }
    }

    /// Removes the bar and says how long it took.
    pub fn finish(self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
        note!("{} runs in {}", self.done, duration(self.started.elapsed().as_secs_f64()));
    }
}

/// Estimated wall time above which a run says before it starts that it will be long.
pub const LONG_RUN_S: f64 = 3600.0;

/// What a run estimated to take more than [`LONG_RUN_S`] says before it starts.
pub fn long_run_warning(seconds: f64) -> String {
    format!(
        "this run will take over an hour (estimated {}); it can be stopped and resumed (`harness run` again with the \
         same --out), cut with --quick, or split with --shard",
        duration(seconds)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_as_minutes_and_seconds() {
        assert_eq!(duration(4.4), "4s");
        assert_eq!(duration(245.0), "4m05s");
        assert_eq!(duration(3720.0), "1h02m");
    }

    #[test]
    fn the_estimate_uses_the_model_until_a_configuration_ran_then_its_own_times() {
        let mut p = Progress { bar: None, ..Progress::new(vec![1.0, 2.0]) };
        p.update(&[3.0, 3.0]);
        assert_eq!(p.seconds_left, 12.0, "model only: 3 x 1 s + 3 x 2 s, and a validation of 1 run each");
        p.validated(0, 1.0);
        p.finished(0, 0.5, "a");
        p.update(&[2.0, 3.0]);
        // Configuration 0 ran at half the model's time: its own mean (0.5 s), and the model scaled by 0.5 for 1,
        // whose validation takes twice a run as 0's did.
        assert_eq!(p.seconds_left, 2.0 * 0.5 + 3.0 * 1.0 + 2.0 * 1.0);
    }
}
