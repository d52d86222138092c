//! The two phase functions around a structure's build and trace that `harness instructions` counts.

/// The build phase of a timed run, a function of its own that `harness instructions` counts under callgrind
/// (`--toggle-collect=*bvhlab_phase_build*`: callgrind toggles collection per thread on entering and leaving it,
/// so it runs in the thread that builds). Never inlined, and the result passes `black_box` so the call is no
/// tail call: both keep the function a call callgrind sees enter and leave.
#[inline(never)]
pub fn bvhlab_phase_build<R>(f: impl FnOnce() -> R) -> R {
    std::hint::black_box(f())
}

/// The trace phase (the job: a ray set, or a render without PNG encoding): see [`bvhlab_phase_build`].
#[inline(never)]
pub fn bvhlab_phase_trace<R>(f: impl FnOnce() -> R) -> R {
    std::hint::black_box(f())
}
