//! What every command shares: a reader that has gone ends a printing command quietly.

use std::process::Stdio;

use crate::common::{harness, stderr, temp};

/// Every command that prints to a reader that has gone (`harness list | head -1`) ends quietly with exit 0.
#[test]
fn a_closed_stdout_ends_every_printing_command_quietly() {
    let dir = temp("closed-stdout");
    let config = dir.join("tiny.toml");
    std::fs::write(&config, "name = \"tiny\"\n[sweep]\nobjects = 10\nwidth = 16\nheight = 8\n").unwrap();
    let config = config.to_str().unwrap();
    for args in [vec!["list"], vec!["validate", config], vec!["--help"], vec!["list", "--help"]] {
        // The read end is closed before the harness starts, so its first write fails with a broken pipe.
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = harness().args(&args).stdout(writer).stderr(Stdio::piped()).output().unwrap();
        assert_eq!(out.status.code(), Some(0), "harness {args:?} with a closed stdout: {}", stderr(&out));
        assert!(!stderr(&out).contains("panicked"), "harness {args:?}: {}", stderr(&out));
    }
}
