//! Records the compiler version and the hash of the workspace's `Cargo.lock` for the provenance of every row, and
//! the hash of the sources it builds (`src/source_tree.rs`), by which `harness ab` knows this binary's revision.

include!("src/source_tree.rs");

fn main() {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = std::process::Command::new(rustc)
        .arg("--version")
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map_or_else(|| "unknown".to_string(), |s| s.trim().to_string());
    println!("cargo:rustc-env=BVHLAB_RUSTC_VERSION={version}");
    // FNV-1a 64 of Cargo.lock: shards merged into one result set must come from builds of one dependency set.
    let lock = std::path::Path::new(&std::env::var("CARGO_MANIFEST_DIR").unwrap()).join("../Cargo.lock");
    let hash = std::fs::read(&lock).map_or_else(
        |_| "unknown".to_string(),
        |bytes| {
            let h =
                bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3));
            format!("{h:016x}")
        },
    );
    println!("cargo:rustc-env=BVHLAB_CARGO_LOCK_HASH={hash}");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed={}", lock.display());
    println!("cargo:rerun-if-env-changed=RUSTC");
    let root = std::path::Path::new(&std::env::var("CARGO_MANIFEST_DIR").unwrap()).join("..");
    println!("cargo:rustc-env=BVHLAB_SOURCE_HASH={:016x}", source_hash(&root));
    // Cargo scans a folder for changes as a whole. (A missing path would rerun the script on every build.)
    for entry in SOURCES.iter().map(|e| root.join(e)).filter(|p| p.exists()) {
        println!("cargo:rerun-if-changed={}", entry.display());
    }
}
