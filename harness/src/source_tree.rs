// The sources a harness binary is built from, hashed: `build.rs` includes this file to embed the hash of the tree
// it builds (`BVHLAB_SOURCE_HASH`), and `ab` hashes the working tree the same way to tell whether the running
// binary is a revision's build. (Plain comments: the file is also `include!`d.)

/// What decides the build, relative to the workspace root: the manifest, lock and toolchain files, and every file
/// in the workspace crates' folders (a `target` folder inside them excepted). Missing entries are skipped.
pub const SOURCES: [&str; 8] =
    ["Cargo.toml", "Cargo.lock", "rust-toolchain.toml", ".cargo", "tracer", "schema", "report", "harness"];

/// FNV-1a 64 over the relative path and contents of every file of [`SOURCES`] under `root`, in sorted order.
pub fn source_hash(root: &std::path::Path) -> u64 {
    fn eat(h: &mut u64, bytes: &[u8]) {
        for b in bytes {
            *h = (*h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn walk(root: &std::path::Path, rel: &std::path::Path, h: &mut u64) {
        let path = root.join(rel);
        let Ok(meta) = std::fs::metadata(&path) else { return };
        if meta.is_dir() {
            let Ok(entries) = std::fs::read_dir(&path) else { return };
            let mut names: Vec<std::ffi::OsString> = entries.filter_map(|e| e.ok().map(|e| e.file_name())).collect();
            names.sort();
            for name in names.into_iter().filter(|n| n != "target") {
                walk(root, &rel.join(name), h);
            }
        } else if let Ok(bytes) = std::fs::read(&path) {
            eat(h, rel.to_string_lossy().as_bytes());
            eat(h, &[0]);
            eat(h, &(bytes.len() as u64).to_le_bytes());
            eat(h, &bytes);
        }
    }
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for entry in SOURCES {
        walk(root, std::path::Path::new(entry), &mut h);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::source_hash;

    #[test]
    fn the_hash_follows_source_contents_and_names_but_not_target_folders() {
        let root = std::env::temp_dir().join(format!("bvhlab-source-hash-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(root.join("tracer/src")).unwrap();
        std::fs::create_dir_all(root.join("tracer/target")).unwrap();
        std::fs::write(root.join("Cargo.toml"), "[workspace]\n").unwrap();
        std::fs::write(root.join("tracer/src/lib.rs"), "pub fn f() {}\n").unwrap();
        let first = source_hash(&root);
        assert_eq!(source_hash(&root), first, "the same tree, the same hash");
        std::fs::write(root.join("tracer/target/artifact"), "build output").unwrap();
        std::fs::write(root.join("README.md"), "not a source").unwrap();
        assert_eq!(source_hash(&root), first, "target folders and other files are not sources");
        std::fs::write(root.join("tracer/src/lib.rs"), "pub fn g() {}\n").unwrap();
        let changed = source_hash(&root);
        assert_ne!(changed, first, "a changed source");
        std::fs::rename(root.join("tracer/src/lib.rs"), root.join("tracer/src/main.rs")).unwrap();
        assert_ne!(source_hash(&root), changed, "a renamed source");
        std::fs::remove_dir_all(&root).unwrap();
    }
}
