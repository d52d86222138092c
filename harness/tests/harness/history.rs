//! `harness history backfill`: a range of no commits or an unknown revision is refused with one line.

use crate::common::{harness, stderr, temp};

#[test]
fn a_backfill_of_no_commits_or_an_unknown_revision_is_one_line_exit_2_and_writes_nothing() {
    let dir = temp("backfill").join("history");
    for (range, says) in [("no-such-revision..HEAD", "is not a revision range"), ("HEAD..HEAD", "holds no commits")] {
        let o = harness().args(["history", "backfill", range, "--dir", dir.to_str().unwrap()]).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{range}: {}", stderr(&o));
        let err = stderr(&o);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(range) && err.contains(says), "{err}");
        assert!(!dir.exists(), "nothing written for {range}");
    }
}
