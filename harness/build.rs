//! Records the compiler version and the hash of the workspace's `Cargo.lock` for the provenance of every row, and
//! the hash of the sources it builds (`src/source_tree.rs`), by which `harness ab` knows this binary's revision.
//! Compiles the tinybvh shim (`src/peers/tinybvh/shim.cpp`) once per ISA level ([`tinybvh`]).

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
    tinybvh::build();
}

/// The tinybvh shim: `src/peers/tinybvh/shim.cpp` over the `tiny_bvh.h` that the `tinybvh-rs` package bundles,
/// compiled once per x86-64 ISA level into `libbvhlab_tinybvh.a` (see `src/peers/tinybvh/mod.rs`).
///
/// - The header is found through the lock file and cargo's own source folders ([`header_dir`]).
/// - Each variant `vN` is compiled with `-march=x86-64-vN -DTB_VARIANT=vN` (its symbols `tinybvh_vN_*`), then
///   partially linked with its section groups resolved (`ld -r --force-group-allocation`) and every symbol but
///   `tinybvh_vN_*` made local (`objcopy`), so no inline function or template instance of one variant (the
///   standard library's included) can stand in for another's at link time.
/// - Its static initializer (tinybvh's SIMD constants and tables, compiled for that ISA) must not run at program
///   start on a CPU without the ISA: `objcopy` renames its `.init_array` to `.data.rel.ro.tinybvh_vN_ctors`,
///   bounded by the symbols `tinybvh_vN_ctors_begin`/`_end`, which the Rust side calls once, after checking the
///   CPU, before the variant's first use. The object must have no other startup or exit code (checked).
/// - This script reruns whenever any workspace source changes (the source hash above), so the archive is cached
///   in `OUT_DIR` under a key of everything that decides it: the shim, the header, this script, the compiler's
///   version and flags, the optimization level and target; only a changed key recompiles (about 12 s of CPU per
///   variant, the three in parallel).
/// - Off x86-64 Linux nothing is compiled and the Rust side reports tinybvh unavailable (`cfg(bvhlab_tinybvh)`).
mod tinybvh {
    use std::path::{Path, PathBuf};
    use std::process::Command;

    /// The ISA levels compiled, lowest first.
    pub const VARIANTS: [&str; 3] = ["v2", "v3", "v4"];
    /// The package whose bundled header is compiled.
    const PACKAGE: &str = "tinybvh-rs";
    /// The library's name (`libbvhlab_tinybvh.a`).
    const LIB: &str = "bvhlab_tinybvh";

    pub fn build() {
        println!("cargo::rustc-check-cfg=cfg(bvhlab_tinybvh)");
        let env = |k: &str| std::env::var(k).unwrap_or_default();
        if env("CARGO_CFG_TARGET_ARCH") != "x86_64" || env("CARGO_CFG_TARGET_OS") != "linux" {
            return;
        }
        let manifest_dir = PathBuf::from(env("CARGO_MANIFEST_DIR"));
        let shim = manifest_dir.join("src/peers/tinybvh/shim.cpp");
        let header_dir = header_dir(&manifest_dir);
        let header = header_dir.join("tiny_bvh.h");
        println!("cargo:rerun-if-changed={}", shim.display());
        println!("cargo:rerun-if-changed={}", header.display());
        for var in ["CXX", "CXXFLAGS", "OBJCOPY"] {
            println!("cargo:rerun-if-env-changed={var}");
        }
        let out = PathBuf::from(env("OUT_DIR"));
        let base = || {
            let mut b = cc::Build::new();
            b.cpp(true).std("c++20").flag("-isystem").flag(header_dir.as_os_str());
            b
        };
        let compiler = base().get_compiler();
        let version = Command::new(compiler.path()).arg("--version").output().map(|o| o.stdout).unwrap_or_default();
        let mut key = Fnv::default();
        let script = read(&manifest_dir.join("build.rs"));
        for part in [&read(&shim)[..], &read(&header), &script, &version, VARIANTS.join(",").as_bytes()] {
            key.eat(part);
        }
        for arg in compiler.args() {
            key.eat(arg.as_encoded_bytes());
        }
        for var in ["OPT_LEVEL", "TARGET", "CXX", "CXXFLAGS", "OBJCOPY"] {
            key.eat(env(var).as_bytes());
        }
        let key = format!("{:016x}", key.0);
        let (library, stamp) = (out.join(format!("lib{LIB}.a")), out.join(format!("{LIB}.key")));
        let cached = library.exists() && std::fs::read_to_string(&stamp).is_ok_and(|k| k == key);
        if !cached {
            let objects: Vec<PathBuf> = std::thread::scope(|s| {
                let jobs: Vec<_> = VARIANTS
                    .iter()
                    .map(|&v| {
                        let (mut b, out, shim) = (base(), out.clone(), shim.clone());
                        s.spawn(move || variant(&mut b, &out, &shim, v))
                    })
                    .collect();
                jobs.into_iter().map(|j| j.join().expect("tinybvh variant build panicked")).collect()
            });
            let _ = std::fs::remove_file(&stamp);
            base().create_archive(LIB, &objects);
            std::fs::write(&stamp, &key).expect("write the tinybvh cache key");
        }
        cc::emit_link_directives(&base(), &library);
        println!("cargo:rustc-cfg=bvhlab_tinybvh");
    }

    /// Compiles variant `v` and returns its object with every symbol but `tinybvh_{v}_*` local.
    fn variant(b: &mut cc::Build, out: &Path, shim: &Path, v: &str) -> PathBuf {
        let dir = out.join(format!("tinybvh-{v}"));
        std::fs::create_dir_all(&dir).expect("create the variant's folder");
        b.file(shim).out_dir(&dir).define("TB_VARIANT", v).flag(format!("-march=x86-64-{v}"));
        let objects = b.compile_intermediates();
        let (joined, local) = (dir.join("joined.o"), out.join(format!("tinybvh_{v}.o")));
        let mut ld = b.get_compiler().to_command();
        ld.args(["-r", "-nostdlib", "-Wl,--force-group-allocation", "-o"]).arg(&joined).args(&objects);
        run(&mut ld);
        let sections = elf_sections(&joined);
        let startup = |n: &str| {
            [".ctors", ".dtors", ".preinit_array", ".init_array", ".fini_array"].iter().any(|p| n.starts_with(p))
        };
        let unexpected: Vec<&(String, u64)> =
            sections.iter().filter(|(n, _)| startup(n) && n != ".init_array").collect();
        assert!(unexpected.is_empty(), "tinybvh {v}: unexpected startup or exit sections {unexpected:?}");
        let ctors = sections.iter().find(|(n, _)| n == ".init_array").map_or(0, |(_, size)| *size);
        assert!(
            ctors > 0 && ctors % 8 == 0,
            "tinybvh {v}: expected an .init_array of function pointers, not {ctors} bytes"
        );
        let section = format!(".data.rel.ro.tinybvh_{v}_ctors");
        let objcopy = std::env::var("OBJCOPY").unwrap_or_else(|_| "objcopy".into());
        let mut localize = Command::new(objcopy);
        localize
            .arg("--wildcard")
            .arg(format!("--keep-global-symbol=tinybvh_{v}_*"))
            .arg(format!("--rename-section=.init_array={section}"))
            .arg(format!("--add-symbol=tinybvh_{v}_ctors_begin={section}:0,global,object"))
            .arg(format!("--add-symbol=tinybvh_{v}_ctors_end={section}:{ctors},global,object"))
            .arg(&joined)
            .arg(&local);
        run(&mut localize);
        let renamed = elf_sections(&local);
        assert!(
            !renamed.iter().any(|(n, _)| startup(n)) && renamed.iter().any(|(n, size)| *n == section && *size == ctors),
            "tinybvh {v}: the static initializer was not moved out of .init_array: {renamed:?}"
        );
        local
    }

    /// The names and sizes of the sections of a little-endian ELF64 object.
    fn elf_sections(path: &Path) -> Vec<(String, u64)> {
        let elf = read(path);
        let (u16_at, u32_at, u64_at) = (
            |o: usize| u16::from_le_bytes(elf[o..o + 2].try_into().unwrap()) as usize,
            |o: usize| u32::from_le_bytes(elf[o..o + 4].try_into().unwrap()) as usize,
            |o: usize| u64::from_le_bytes(elf[o..o + 8].try_into().unwrap()),
        );
        assert!(elf.starts_with(b"\x7fELF\x02\x01"), "{}: not a little-endian ELF64 object", path.display());
        let (shoff, shentsize, shnum, shstrndx) = (u64_at(0x28) as usize, u16_at(0x3a), u16_at(0x3c), u16_at(0x3e));
        let header = |i: usize| shoff + i * shentsize;
        let names = u64_at(header(shstrndx) + 0x18) as usize;
        (0..shnum)
            .map(|i| {
                let start = names + u32_at(header(i));
                let end = start + elf[start..].iter().position(|&b| b == 0).unwrap();
                (String::from_utf8_lossy(&elf[start..end]).into_owned(), u64_at(header(i) + 0x20))
            })
            .collect()
    }

    /// The folder of `tiny_bvh.h` in the `tinybvh-rs` package that cargo unpacked for this build: its version from
    /// the workspace's `Cargo.lock`, its folder under cargo's own sources (`$CARGO_HOME/registry/src/*/NAME-VERSION`).
    /// Cargo has downloaded and unpacked every dependency of this package before its build script runs, so this
    /// holds on a fresh registry and on a full one alike, offline too; no other package, and no network, is asked
    /// for. (`cargo metadata`, used before, resolves the whole workspace with its dev-dependencies, which a fresh
    /// registry lacks when only the harness was built.)
    fn header_dir(manifest_dir: &Path) -> PathBuf {
        let lock_path = manifest_dir.join("../Cargo.lock");
        let lock = String::from_utf8_lossy(&read(&lock_path)).into_owned();
        let versions = locked_versions(&lock, PACKAGE);
        let [version] = &versions[..] else {
            panic!("{}: expected one {PACKAGE} package, found versions {versions:?}", lock_path.display())
        };
        let home = std::env::var_os("CARGO_HOME").map(PathBuf::from).unwrap_or_else(|| {
            PathBuf::from(std::env::var_os("HOME").expect("HOME or CARGO_HOME is set")).join(".cargo")
        });
        let sources = home.join("registry/src");
        let mut found: Vec<PathBuf> = std::fs::read_dir(&sources)
            .into_iter()
            .flatten()
            .filter_map(|e| e.ok())
            .map(|index| index.path().join(format!("{PACKAGE}-{version}")))
            .filter(|dir| {
                let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap_or_default();
                dir.join("ffi/tinybvh/tiny_bvh.h").is_file()
                    && manifest.contains(&format!("name = \"{PACKAGE}\""))
                    && manifest.contains(&format!("version = \"{version}\""))
            })
            .collect();
        // One index folder per registry protocol may hold the same checksummed package: any of them will do.
        found.sort();
        match found.first() {
            Some(dir) => {
                println!("cargo:rerun-if-env-changed=CARGO_HOME");
                dir.join("ffi/tinybvh")
            }
            None => panic!(
                "{PACKAGE} {version} (Cargo.lock) is not unpacked under {}/*/{PACKAGE}-{version}: \
                 run `cargo fetch`, or set CARGO_HOME to the cargo home this build uses",
                sources.display()
            ),
        }
    }

    /// The versions of package `name` in the lock file `lock`.
    fn locked_versions(lock: &str, name: &str) -> Vec<String> {
        lock.split("[[package]]")
            .filter(|entry| entry.lines().any(|l| l.trim() == format!("name = \"{name}\"")))
            .filter_map(|entry| {
                let line = entry.lines().find(|l| l.trim_start().starts_with("version = "))?;
                Some(line.trim().trim_start_matches("version = ").trim_matches('"').to_string())
            })
            .collect()
    }

    fn read(path: &Path) -> Vec<u8> {
        std::fs::read(path).unwrap_or_else(|e| panic!("read {}: {e}", path.display()))
    }

    fn run(cmd: &mut Command) {
        let status = cmd.status().unwrap_or_else(|e| panic!("run {cmd:?}: {e}"));
        assert!(status.success(), "{cmd:?} failed: {status}");
    }

    /// FNV-1a 64, fed with length-prefixed parts.
    struct Fnv(u64);
    impl Default for Fnv {
        fn default() -> Self {
            Fnv(0xcbf2_9ce4_8422_2325)
        }
    }
    impl Fnv {
        fn eat(&mut self, bytes: &[u8]) {
            for b in (bytes.len() as u64).to_le_bytes().iter().chain(bytes) {
                self.0 = (self.0 ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
            }
        }
    }
}
