//! Bring-your-own scene: a CSV of spheres, parsed from text (the caller reads the file).
//!
//! Format, one sphere per line, fields separated by commas, spaces around fields ignored:
//!
//! ```text
//! # comments start with '#'; blank lines are skipped
//! x,y,z,r                                              <- optional header (any line starting with "x,")
//! 0.0, 1.0, -5.0, 1.0                                  <- 4 columns: matte light grey
//! 2.0, 1.0, -6.0, 0.5, 0.9, 0.2, 0.2                   <- 7 columns: + red, green, blue in [0, 1]
//! -2.0, 1.0, -6.0, 0.5, 0.9, 0.9, 0.9, 0.5, 32, 0.8    <- 10 columns: + specular, shininess, reflectivity
//! ```
//!
//! Coordinates are finite numbers, `r > 0`, colors, `specular` and `reflectivity` in `[0, 1]`, and
//! `shininess` an integer in `1..=1000`. The camera, lights and ground are placed around the spheres'
//! bounds: ground under the lowest sphere, camera in front (+z) looking at the center.

use std::fmt;

use glam::Vec3;

use super::{Camera, Ground, Material, PointLight, Scene};
use crate::geometry::Sphere;

/// Column names, in file order.
pub const COLUMNS: [&str; 10] = ["x", "y", "z", "r", "red", "green", "blue", "specular", "shininess", "reflectivity"];

/// Why a sphere file was rejected: where, and what was expected there.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SphereFileError {
    /// 1-based line number (0 when the file as a whole is at fault).
    pub line: usize,
    /// 1-based column, when one field is at fault.
    pub column: Option<usize>,
    /// What the line or field should hold.
    pub expected: String,
    /// What it held.
    pub found: String,
}

impl fmt::Display for SphereFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.column {
            Some(c) => write!(
                f,
                "line {}, column {} ({}): expected {}, found {:?}",
                self.line,
                c,
                COLUMNS[c - 1],
                self.expected,
                self.found
            ),
            None if self.line == 0 => write!(f, "expected {}, found {}", self.expected, self.found),
            None => write!(f, "line {}: expected {}, found {}", self.line, self.expected, self.found),
        }
    }
}

impl std::error::Error for SphereFileError {}

fn field(
    line: usize,
    column: usize,
    text: &str,
    expected: &str,
    ok: impl Fn(f64) -> bool,
) -> Result<f64, SphereFileError> {
    let err =
        || SphereFileError { line, column: Some(column), expected: expected.to_string(), found: text.to_string() };
    let v: f64 = text.parse().map_err(|_| err())?;
    if v.is_finite() && ok(v) { Ok(v) } else { Err(err()) }
}

fn parse_line(line: usize, text: &str) -> Result<(Sphere, Material), SphereFileError> {
    let fields: Vec<&str> = text.split(',').map(str::trim).collect();
    if ![4, 7, 10].contains(&fields.len()) {
        return Err(SphereFileError {
            line,
            column: None,
            expected: "4, 7 or 10 comma-separated columns (x,y,z,r[,red,green,blue[,specular,shininess,reflectivity]])"
                .into(),
            found: format!("{} columns", fields.len()),
        });
    }
    let any = |_: f64| true;
    let unit = |v: f64| (0.0..=1.0).contains(&v);
    let mut v = [0.0f64; 10];
    for (i, f) in fields.iter().enumerate() {
        v[i] = match i {
            0..=2 => field(line, i + 1, f, "a finite number", any)?,
            3 => field(line, i + 1, f, "a positive number", |r| r > 0.0)?,
            8 => field(line, i + 1, f, "an integer in 1..=1000", |s| s.fract() == 0.0 && (1.0..=1000.0).contains(&s))?,
            _ => field(line, i + 1, f, "a number in [0, 1]", unit)?,
        };
    }
    let sphere = Sphere::new(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32), v[3] as f32);
    let albedo = if fields.len() >= 7 { Vec3::new(v[4] as f32, v[5] as f32, v[6] as f32) } else { Vec3::splat(0.8) };
    let material = if fields.len() == 10 {
        Material { albedo, specular: v[7] as f32, shininess: v[8] as i32, reflectivity: v[9] as f32 }
    } else {
        Material::matte(albedo)
    };
    Ok((sphere, material))
}

/// Parses a sphere file's text into a scene framed around its spheres.
pub fn parse(text: &str) -> Result<Scene, SphereFileError> {
    let mut spheres = Vec::new();
    let mut materials = Vec::new();
    let mut seen_data = false;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if !seen_data && line.to_ascii_lowercase().replace(' ', "").starts_with("x,") {
            seen_data = true;
            continue;
        }
        seen_data = true;
        let (s, m) = parse_line(i + 1, line)?;
        spheres.push(s);
        materials.push(m);
    }
    if spheres.is_empty() {
        return Err(SphereFileError {
            line: 0,
            column: None,
            expected: "at least one sphere".into(),
            found: "none".into(),
        });
    }
    Ok(framed(spheres, materials))
}

/// A scene whose camera, lights and ground are placed around the spheres' bounds.
fn framed(spheres: Vec<Sphere>, materials: Vec<Material>) -> Scene {
    let b = spheres.iter().fold(crate::geometry::Aabb::EMPTY, |b, s| b.union(&s.bounds()));
    let center = b.center();
    let size = b.extent().length().max(1e-3);
    Scene {
        spheres,
        materials,
        lights: vec![
            PointLight { position: center + Vec3::new(-1.0, 2.0, 1.2) * size, intensity: 0.65 },
            PointLight { position: center + Vec3::new(1.2, 1.4, 0.4) * size, intensity: 0.45 },
        ],
        ambient: 0.08,
        ground: Some(Ground {
            height: b.min.y,
            square: size / 8.0,
            albedo: [Vec3::splat(0.75), Vec3::new(0.3, 0.3, 0.36)],
            reflectivity: 0.2,
        }),
        camera: Camera {
            position: center + Vec3::new(0.0, 0.35, 1.3) * size,
            look_at: center,
            up: Vec3::Y,
            vfov_degrees: 50.0,
            width: 640,
            height: 480,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_all_three_widths_comments_and_header() {
        let text = "# demo\nx,y,z,r\n0,1,-5,1\n\n2,1,-6,0.5,0.9,0.2,0.2\n-2, 1, -6, 0.5, 0.9, 0.9, 0.9, 0.5, 32, 0.8\n";
        let s = parse(text).unwrap();
        assert_eq!(s.spheres.len(), 3);
        assert_eq!(s.spheres[2], Sphere::new(Vec3::new(-2.0, 1.0, -6.0), 0.5));
        assert_eq!(s.materials[1].albedo, Vec3::new(0.9, 0.2, 0.2));
        assert_eq!(s.materials[2].shininess, 32);
        assert_eq!(s.materials[2].reflectivity, 0.8);
    }

    #[test]
    fn errors_name_line_column_and_expectation() {
        let e = parse("0,0,0,1\n1,2,abc,1\n").unwrap_err();
        assert_eq!((e.line, e.column), (2, Some(3)));
        assert_eq!(e.to_string(), "line 2, column 3 (z): expected a finite number, found \"abc\"");
        let e = parse("0,0,0,-1\n").unwrap_err();
        assert_eq!(e.to_string(), "line 1, column 4 (r): expected a positive number, found \"-1\"");
        let e = parse("# c\n0,0,0,1,2\n").unwrap_err();
        assert_eq!((e.line, e.column), (2, None));
        assert!(e.to_string().starts_with("line 2: expected 4, 7 or 10 comma-separated columns"), "{e}");
        let e = parse("0,0,0,1,0.5,0.5,1.5\n").unwrap_err();
        assert_eq!(e.column, Some(7));
        let e = parse("0,0,0,1,0.5,0.5,0.5,0.5,2.5,0\n").unwrap_err();
        assert_eq!(e.column, Some(9));
        let e = parse("0,0,inf,1\n").unwrap_err();
        assert_eq!(e.column, Some(3));
        assert_eq!(parse("# nothing\n").unwrap_err().to_string(), "expected at least one sphere, found none");
    }
}
