//! What a configuration starts once per process, before any timed phase (the `setup_s` phase).

use std::any::Any;

use schema::Settings;

use crate::error::Error;

/// The rayon pool of the configured threads that builds and traces run in, and what the backend started
/// ([`super::Backend::start`]: Embree's library and device).
pub struct Setup {
    pool: rayon::ThreadPool,
    started: Option<Box<dyn Any + Send + Sync>>,
    /// Wall time of starting all of it.
    pub setup_s: f64,
}

impl Setup {
    /// Starts what `settings` needs, timed.
    pub fn start(settings: &Settings) -> Result<Setup, Error> {
        let t = std::time::Instant::now();
        let threads = settings.strategy().threads.max(1);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| Error::Run(format!("cannot start a pool of {threads} threads: {e}")))?;
        // Every worker thread started before the clock stops.
        pool.broadcast(|_| ());
        let started = super::of(settings.accel).start(settings)?;
        Ok(Setup { pool, started, setup_s: t.elapsed().as_secs_f64() })
    }

    /// Runs `f` in the pool (builds and traces run here, so the tracer's executor reuses the pool).
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        self.pool.install(f)
    }

    /// What the backend started, as the type it started.
    pub fn started<T: 'static>(&self) -> Option<&T> {
        self.started.as_ref().and_then(|s| s.downcast_ref())
    }
}
