//! The data sets `harness fetch` knows: each a pinned package of a public registry, checked by its SHA-256.

/// The package client that downloads a data set's archive (and so how the archive unpacks).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Client {
    /// `apt-get download PACKAGE=VERSION`: a Debian package (an ar archive, unpacked by `dpkg-deb -x`).
    Apt,
    /// `python3 -m pip download --no-deps PACKAGE==VERSION`: a wheel (a zip, unpacked by `python3 -m zipfile`).
    Pip,
    /// `npm pack PACKAGE@VERSION`: an npm tarball (unpacked by `tar`).
    Npm,
}

/// How the mesh inside the unpacked archive is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// One Wavefront OBJ file.
    Obj,
    /// A folder of PLY files, merged in sorted file-name order.
    PlyFolder,
    /// An npm JS module with `positions` and `cells` arrays.
    JsArrays,
}

/// One fetchable data set.
#[derive(Clone, Copy, Debug)]
pub struct DataSet {
    /// The name `harness fetch` and configs use.
    pub name: &'static str,
    /// What it is, in a few words.
    pub title: &'static str,
    /// The client that downloads it.
    pub client: Client,
    /// The registry package.
    pub package: &'static str,
    /// Its pinned version.
    pub version: &'static str,
    /// The file the client writes.
    pub archive: &'static str,
    /// SHA-256 of that file, lower-case hex.
    pub sha256: &'static str,
    /// Path of the mesh inside the unpacked archive.
    pub inside: &'static str,
    /// How the mesh is stored there.
    pub format: Format,
    /// The license the package states for the data.
    pub license: &'static str,
    /// Triangles in the loaded mesh.
    pub triangles: usize,
}

const SIONNA_WHEEL: &str = "sionna_rt-2.2.0-py3-none-any.whl";
const SIONNA_SHA256: &str = "ffd5b5fea0fd3fee9d64a9e2b0ff1f2f4b4bfc010fa3d59d7479955fbdfc0e8e";
const SIONNA_LICENSE: &str = "Apache-2.0 (sionna-rt; the city data's origin is not stated in the package)";

/// A city scene of the sionna-rt wheel.
const fn sionna(name: &'static str, title: &'static str, inside: &'static str, triangles: usize) -> DataSet {
    DataSet {
        name,
        title,
        client: Client::Pip,
        package: "sionna-rt",
        version: "2.2.0",
        archive: SIONNA_WHEEL,
        sha256: SIONNA_SHA256,
        inside,
        format: Format::PlyFolder,
        license: SIONNA_LICENSE,
        triangles,
    }
}

/// Every data set, by name.
pub const DATA_SETS: [DataSet; 7] = [
    DataSet {
        name: "bunny",
        title: "the Stanford bunny",
        client: Client::Apt,
        package: "glmark2-data",
        version: "2023.01+dfsg-1",
        archive: "glmark2-data_2023.01+dfsg-1_all.deb",
        sha256: "14a62322c6131ac9d846f428f06056a1de85caded38c77cb497b73e9ec316bd9",
        inside: "usr/share/glmark2/models/bunny.obj",
        format: Format::Obj,
        license: "GPL-3+ (glmark2-data's files; the bunny is from the Stanford 3D Scanning Repository)",
        triangles: 69_666,
    },
    sionna("san-francisco", "San Francisco city blocks", "sionna/rt/scenes/san_francisco/meshes", 268_041),
    sionna("munich", "Munich city centre", "sionna/rt/scenes/munich/meshes", 38_936),
    sionna("florence", "Florence city centre", "sionna/rt/scenes/florence/meshes", 35_373),
    sionna("etoile", "Place de l'Étoile, Paris", "sionna/rt/scenes/etoile/meshes", 13_098),
    DataSet {
        name: "bunny-small",
        title: "a small Stanford bunny",
        client: Client::Npm,
        package: "bunny",
        version: "1.0.1",
        archive: "bunny-1.0.1.tgz",
        sha256: "381e02c74b98cf18814d7bec794726ef70b9c67e037273e82054d0043f6ae303",
        inside: "package/index.js",
        format: Format::JsArrays,
        license: "public domain (npm bunny)",
        triangles: 3_674,
    },
    DataSet {
        name: "teapot",
        title: "the Utah teapot",
        client: Client::Npm,
        package: "teapot",
        version: "1.0.0",
        archive: "teapot-1.0.0.tgz",
        sha256: "ebe7143533ff1a35ea25738b43112d36fd9ae072652bde9b2144057e7218890f",
        inside: "package/teapot.js",
        format: Format::JsArrays,
        license: "public domain (npm teapot)",
        triangles: 992,
    },
];

impl DataSet {
    /// The data set called `name`, or an error listing the known names.
    pub fn named(name: &str) -> Result<&'static DataSet, crate::error::Error> {
        DATA_SETS.iter().find(|d| d.name == name).ok_or_else(|| {
            let names: Vec<_> = DATA_SETS.iter().map(|d| d.name).collect();
            crate::error::Error::Input(format!("unknown data set {name:?} (allowed: {})", names.join(", ")))
        })
    }

    /// The client's command line that downloads the archive into the current folder.
    pub fn command(&self) -> Vec<String> {
        let (p, v) = (self.package, self.version);
        let words = match self.client {
            Client::Apt => vec!["apt-get", "download"],
            Client::Pip => vec!["python3", "-m", "pip", "download", "--no-deps", "--dest", "."],
            Client::Npm => vec!["npm", "pack"],
        };
        let spec = match self.client {
            Client::Apt => format!("{p}={v}"),
            Client::Pip => format!("{p}=={v}"),
            Client::Npm => format!("{p}@{v}"),
        };
        words.into_iter().map(String::from).chain([spec]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_hashes_are_sha256_hex() {
        for (i, d) in DATA_SETS.iter().enumerate() {
            assert!(DATA_SETS[..i].iter().all(|e| e.name != d.name), "{} twice", d.name);
            assert_eq!(d.sha256.len(), 64, "{}", d.name);
            assert!(d.sha256.bytes().all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b)), "{}", d.name);
            assert!(d.archive.contains(d.version), "{}: archive {} is not version {}", d.name, d.archive, d.version);
            assert!(d.triangles > 0 && !d.license.is_empty());
        }
    }

    #[test]
    fn unknown_names_list_the_known_ones() {
        let e = DataSet::named("sponza").unwrap_err().to_string();
        assert!(e.contains("\"sponza\"") && e.contains("bunny, san-francisco"), "{e}");
    }
}
