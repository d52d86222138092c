//! `harness fetch`: download a data set once with its package client, check the archive's SHA-256, unpack it,
//! load it, and write its manifest; `--list` shows every data set.

use std::path::Path;
use std::process::Command;

use sha2::{Digest, Sha256};

use super::cache::{self, MANIFEST, Manifest, UNPACKED};
use super::registry::{Client, DATA_SETS, DataSet};
use crate::error::Error;

/// Prints every data set: name, triangles, package, license.
pub fn list() {
    say!("{:<14} {:>9}  {:<32} license", "name", "triangles", "package");
    for d in &DATA_SETS {
        say!("{:<14} {:>9}  {:<32} {}", d.name, d.triangles, format!("{} {}", d.package, d.version), d.license);
    }
}

/// Fetches `set` into its folder under `root`, unless its manifest is already there.
pub fn fetch(root: &Path, set: &DataSet) -> Result<Manifest, Error> {
    let dir = root.join(set.name);
    if let Some(m) = cache::manifest(root, set)? {
        say!("{}: already there ({}, {} triangles): nothing to fetch", set.name, dir.display(), m.triangles);
        return Ok(m);
    }
    std::fs::create_dir_all(&dir).map_err(|e| Error::Input(format!("{}: cannot create: {e}", dir.display())))?;
    let archive = dir.join(set.archive);
    if !archive.is_file() {
        run(&set.command(), &dir)?;
    }
    check_sha256(&archive, set)?;
    let unpacked = dir.join(UNPACKED);
    if unpacked.exists() {
        std::fs::remove_dir_all(&unpacked)
            .map_err(|e| Error::Run(format!("{}: cannot remove: {e}", unpacked.display())))?;
    }
    std::fs::create_dir_all(&unpacked)
        .map_err(|e| Error::Run(format!("{}: cannot create: {e}", unpacked.display())))?;
    run(&unpack_command(set.client, &archive, &unpacked), &dir)?;
    let mesh = cache::read_mesh(&dir, set)?;
    if mesh.triangle_count() != set.triangles {
        return Err(Error::Run(format!(
            "{}: {} triangles loaded from {}, the registry says {}",
            set.name,
            mesh.triangle_count(),
            set.inside,
            set.triangles
        )));
    }
    let manifest = Manifest {
        name: set.name.into(),
        package: set.package.into(),
        version: set.version.into(),
        command: set.command().join(" "),
        archive: set.archive.into(),
        sha256: set.sha256.into(),
        inside: set.inside.into(),
        license: set.license.into(),
        triangles: mesh.triangle_count(),
        fingerprint: format!("{:016x}", mesh.fingerprint()),
    };
    let path = dir.join(MANIFEST);
    let text = serde_json::to_string_pretty(&manifest).map_err(|e| Error::Run(e.to_string()))?;
    std::fs::write(&path, text + "\n").map_err(|e| Error::Run(format!("{}: cannot write: {e}", path.display())))?;
    say!(
        "{}: {} {} (SHA-256 {}): {} triangles, fingerprint {} in {}",
        set.name,
        set.package,
        set.version,
        set.sha256,
        manifest.triangles,
        manifest.fingerprint,
        dir.display()
    );
    Ok(manifest)
}

/// Refuses an archive whose SHA-256 is not the pinned one.
fn check_sha256(archive: &Path, set: &DataSet) -> Result<(), Error> {
    let bytes = std::fs::read(archive).map_err(|e| Error::Run(format!("{}: cannot read: {e}", archive.display())))?;
    let have = format!("{:x}", Sha256::digest(&bytes));
    if have != set.sha256 {
        return Err(Error::Input(format!(
            "{}: SHA-256 {have}, but {} {} is pinned at {} (remove the file and fetch again)",
            archive.display(),
            set.package,
            set.version,
            set.sha256
        )));
    }
    Ok(())
}

/// The command that unpacks `archive` into `into`.
fn unpack_command(client: Client, archive: &Path, into: &Path) -> Vec<String> {
    let (a, i) = (archive.display().to_string(), into.display().to_string());
    let words = match client {
        Client::Apt => vec!["dpkg-deb", "-x", &a, &i],
        Client::Pip => vec!["python3", "-m", "zipfile", "-e", &a, &i],
        Client::Npm => vec!["tar", "-xzf", &a, "-C", &i],
    };
    words.into_iter().map(String::from).collect()
}

/// Runs `words` in `dir`; a missing program or a failure is one line naming the command.
fn run(words: &[String], dir: &Path) -> Result<(), Error> {
    let line = words.join(" ");
    let status = Command::new(&words[0]).args(&words[1..]).current_dir(dir).status().map_err(|e| {
        let hint = if words[0] == "dpkg-deb" {
            " (a .deb is an ar archive: `ar x` it and unpack its data.tar.xz with `tar -xJf` by hand)"
        } else {
            ""
        };
        Error::Run(format!("`{line}`: cannot run {}: {e}{hint}", words[0]))
    })?;
    if !status.success() {
        return Err(Error::Run(format!("`{line}` in {} failed ({status})", dir.display())));
    }
    Ok(())
}
