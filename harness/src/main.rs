//! The `harness` binary: see the library's [`harness::main`].

fn main() -> std::process::ExitCode {
    harness::main()
}
