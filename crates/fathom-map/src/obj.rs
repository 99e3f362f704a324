//! Wavefront OBJ import with `tobj`: geometry and `usemtl` materials into a
//! [`TriMesh`] in local NED metres (see [`crate::import`] for the frame settings).
//!
//! The text is scanned once before `tobj` parses it, to give errors a line number:
//! a `usemtl` name the material table does not map, a face with no material while
//! there is no default material, a vertex that is not finite or lies beyond
//! [`crate::mesh::MAX_COORD`] after conversion, and a face index that names
//! no element defined before it (which `tobj` does not check and can overflow on). When `tobj` itself rejects
//! the file (a malformed number, a face index out of range, ...), the line is found by
//! bisection: the shortest prefix of the file that `tobj` rejects ends at the culprit
//! (only on the error path). `tobj` looks `usemtl` names up among the materials of a
//! `mtllib`; this crate opens no file, so the reader hands `tobj` a material library
//! made of the names the scan found, and real `mtllib` lines are ignored (only the
//! names matter). Polygons are triangulated as fans; points and lines are ignored.

use std::io::{Cursor, Read};
use std::path::Path;

use fathom_core::Material;
use tobj::{LoadError, LoadOptions};

use crate::import::read_bounded;
use crate::mesh::MAX_COORD;
use crate::{ImportReport, ImportSettings, MapError, MeshBuilder, TriMesh};

/// The material library name handed to `tobj` for the scanned `usemtl` names.
const SCANNED_MTLLIB: &str = "fathom-scanned-usemtl-names.mtl";

const OPTIONS: LoadOptions = LoadOptions {
    single_index: false,
    triangulate: true,
    ignore_points: true,
    ignore_lines: true,
};

/// Reads an OBJ file from `reader` (at most `settings.max_bytes`).
///
/// # Errors
/// As [`parse_obj`], and [`MapError::Io`] / [`MapError::TooLarge`] from reading.
pub fn read_obj(
    reader: impl Read,
    settings: &ImportSettings,
) -> Result<(TriMesh, ImportReport), MapError> {
    settings.check()?;
    let bytes = read_bounded(reader, settings.max_bytes)?;
    parse_obj(&bytes, settings)
}

/// Parses the bytes of an OBJ file.
///
/// # Errors
/// [`MapError::ObjLine`] naming the line (not UTF-8, malformed, non-finite or too
/// large vertex, face index out of range), [`MapError::UnknownMaterial`],
/// [`MapError::MissingMaterial`], [`MapError::TooLarge`],
/// [`MapError::InvalidParameter`] (settings), [`MapError::TooManyElements`].
pub fn parse_obj(
    bytes: &[u8],
    settings: &ImportSettings,
) -> Result<(TriMesh, ImportReport), MapError> {
    settings.check()?;
    if bytes.len() as u64 > settings.max_bytes {
        return Err(MapError::TooLarge {
            bytes: bytes.len() as u64,
            limit: settings.max_bytes,
        });
    }
    let text = std::str::from_utf8(bytes).map_err(|e| MapError::ObjLine {
        line: 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count(),
        reason: "not valid UTF-8".into(),
    })?;
    let scan = scan(text, settings)?;

    let names = scan.material_names.clone();
    let library = move |p: &Path| -> tobj::MTLLoadResult {
        if p != Path::new(SCANNED_MTLLIB) {
            return Err(LoadError::OpenFileFailed);
        }
        let mats = names
            .iter()
            .map(|n| tobj::Material {
                name: n.clone(),
                ..tobj::Material::default()
            })
            .collect();
        let map = names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.clone(), i))
            .collect();
        Ok((mats, map))
    };
    let header = format!("mtllib {SCANNED_MTLLIB}\n");
    let load = |body: &str| {
        let mut input = Cursor::new(header.as_bytes()).chain(body.as_bytes());
        tobj::load_obj_buf(&mut input, &OPTIONS, &library)
    };
    let models = match load(text) {
        Ok((models, _)) => models,
        Err(e) => return Err(locate(text, &load, e)),
    };

    let mut builder = MeshBuilder::new();
    for model in &models {
        let mesh = &model.mesh;
        let material = match mesh.material_id {
            Some(id) => material_of(&scan.material_names, id, settings)?,
            None => settings.default_material.ok_or(MapError::Obj {
                reason: "faces without a material and no default material".into(),
            })?,
        };
        let base = builder_vertices(&mut builder, &mesh.positions, settings);
        for t in mesh.indices.chunks_exact(3) {
            builder.triangle(base + t[0], base + t[1], base + t[2], material);
        }
    }
    let (mesh, report) = builder.build()?;
    Ok((
        mesh,
        ImportReport {
            faces_read: scan.faces,
            polygons_triangulated: scan.polygons,
            ignored_elements: scan.ignored,
            mesh: report,
        },
    ))
}

fn material_of(
    names: &[String],
    id: usize,
    settings: &ImportSettings,
) -> Result<Material, MapError> {
    names
        .get(id)
        .and_then(|n| settings.materials.get(n))
        .ok_or_else(|| MapError::Obj {
            reason: format!("material index {id} not among the scanned `usemtl` names"),
        })
}

/// Adds the positions (file axes and units) as NED vertices; returns the first index.
fn builder_vertices(
    builder: &mut MeshBuilder,
    positions: &[f64],
    settings: &ImportSettings,
) -> u32 {
    let mut first = None;
    for p in positions.chunks_exact(3) {
        let i = builder.vertex(settings.to_ned(&[p[0], p[1], p[2]]));
        first.get_or_insert(i);
    }
    first.unwrap_or(0)
}

/// What the line scan found.
struct Scan {
    /// Distinct `usemtl` names in order of first use, as written.
    material_names: Vec<String>,
    faces: usize,
    polygons: usize,
    ignored: usize,
}

/// The lines as `tobj` sees them (split at `\n`, a trailing `\r` removed), 1-based.
fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
}

fn scan(text: &str, settings: &ImportSettings) -> Result<Scan, MapError> {
    let mut s = Scan {
        material_names: Vec::new(),
        faces: 0,
        polygons: 0,
        ignored: 0,
    };
    let mut current: Option<Material> = None;
    // elements defined so far: positions, texture coordinates, normals
    let mut counts = [0usize; 3];
    for (line, l) in lines(text) {
        let mut words = l.split_whitespace();
        match words.next() {
            Some("v") => {
                check_vertex(line, words, settings)?;
                counts[0] += 1;
            }
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some("usemtl") => {
                let name = l.split_once(' ').map_or("", |x| x.1).trim();
                if name.is_empty() {
                    continue; // tobj reports it
                }
                let Some(m) = settings.materials.get(name) else {
                    return Err(MapError::UnknownMaterial {
                        name: name.to_owned(),
                        line,
                    });
                };
                current = Some(m);
                if !s.material_names.iter().any(|n| n == name) {
                    s.material_names.push(name.to_owned());
                }
            }
            Some("f") => {
                let corners = check_face_indices(line, words.clone(), &counts)?;
                if corners < 3 {
                    s.ignored += 1;
                    continue;
                }
                s.faces += 1;
                if corners > 3 {
                    s.polygons += 1;
                }
                if current.is_none() && settings.default_material.is_none() {
                    return Err(MapError::MissingMaterial { line });
                }
            }
            Some("l") => {
                check_face_indices(line, words, &counts)?;
                s.ignored += 1;
            }
            Some("p") => s.ignored += 1,
            _ => {}
        }
    }
    Ok(s)
}

/// The `v/vt/vn` indices of a face (or line) element: each present index must name an
/// element defined before it (`1..=n`, or `-n..=-1` counting back), else an error.
/// `tobj` resolves these indices without that check and can overflow on them (found
/// by fuzzing: `fuzz/regressions/map_obj/`). Returns the number of corners; tokens
/// that are not integers are left to `tobj`.
fn check_face_indices<'a>(
    line: usize,
    words: impl Iterator<Item = &'a str>,
    counts: &[usize; 3],
) -> Result<usize, MapError> {
    const KIND: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let mut corners = 0;
    for word in words {
        corners += 1;
        for (k, part) in word.split('/').enumerate().take(3) {
            let Ok(x) = part.parse::<i64>() else {
                continue;
            };
            let n = counts[k] as i64;
            if !((1..=n).contains(&x) || (-n..=-1).contains(&x)) {
                return Err(MapError::ObjLine {
                    line,
                    reason: format!(
                        "{} index {x} out of range ({n} defined before this line)",
                        KIND[k]
                    ),
                });
            }
        }
    }
    Ok(corners)
}

/// A `v x y z [w]` line whose numbers parse must give a finite NED point within
/// `MAX_COORD` (lines that do not parse are left to `tobj`).
fn check_vertex<'a>(
    line: usize,
    mut words: impl Iterator<Item = &'a str>,
    settings: &ImportSettings,
) -> Result<(), MapError> {
    let mut p = [0.0; 3];
    for c in &mut p {
        match words.next().map(str::parse::<f64>) {
            Some(Ok(x)) => *c = x,
            _ => return Ok(()),
        }
    }
    let rest: Vec<&str> = words.collect();
    if rest.len() == 1
        && let Ok(w) = rest[0].parse::<f64>()
        && w != 0.0
    {
        p = p.map(|c| c / w);
    }
    let ned = settings.to_ned(&p);
    if let Some(bad) = ned.iter().find(|c| c.is_nan() || c.abs() > MAX_COORD) {
        return Err(MapError::ObjLine {
            line,
            reason: format!(
                "vertex coordinate {bad} (NED, m) is not finite or beyond +-{MAX_COORD} m"
            ),
        });
    }
    Ok(())
}

/// The line of a `tobj` error: the end of the shortest prefix `load` rejects.
/// The first line (1-based) whose syntax tobj cannot read: a vertex line with a
/// token that is not a number, or a face, line or point element with an index that
/// is not a nonzero whole number. A guess for [`locate`], checked there.
fn suspect_line(text: &str) -> Option<usize> {
    let number = |t: &str| t.parse::<f64>().is_ok();
    let index = |t: &str| t.parse::<i64>().is_ok_and(|i| i != 0);
    let element = |t: &str| {
        let mut parts = t.split('/');
        parts.next().is_some_and(index) && parts.all(|p| p.is_empty() || index(p))
    };
    text.lines()
        .position(|line| {
            let mut tokens = line.split_whitespace();
            match tokens.next() {
                Some("v" | "vn" | "vt") => !tokens.all(number),
                Some("f" | "l" | "p") => !tokens.all(element),
                _ => false,
            }
        })
        .map(|i| i + 1)
}

fn locate<T>(text: &str, load: &impl Fn(&str) -> Result<T, LoadError>, err: LoadError) -> MapError {
    // byte offset of the end of each line (including its '\n')
    let mut ends: Vec<usize> = text.match_indices('\n').map(|(i, _)| i + 1).collect();
    if ends.last() != Some(&text.len()) {
        ends.push(text.len());
    }
    // A line that looks malformed is the answer when the prefix up to it fails and the
    // one before it loads: two parses instead of a bisection's ~log2(lines) (a 35 MB
    // file with a bad last line took 7 s to refuse).
    if let Some(line) = suspect_line(text).filter(|&l| l <= ends.len())
        && load(&text[..ends[line - 1]]).is_err()
        && (line == 1 || load(&text[..ends[line - 2]]).is_ok())
    {
        return MapError::ObjLine {
            line,
            reason: err.to_string(),
        };
    }
    let (mut lo, mut hi) = (0usize, ends.len()); // prefix of `hi` lines fails
    while lo + 1 < hi {
        let mid = lo + (hi - lo) / 2;
        if load(&text[..ends[mid - 1]]).is_err() {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    if hi >= 1 && load(&text[..ends[hi - 1]]).is_err() {
        MapError::ObjLine {
            line: hi,
            reason: err.to_string(),
        }
    } else {
        MapError::Obj {
            reason: err.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn suspect_lines_are_the_malformed_ones() {
        assert_eq!(suspect_line("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), None);
        assert_eq!(suspect_line("v 0 0 0\nv 1 x 0\n"), Some(2));
        assert_eq!(
            suspect_line("# c\nf 1/2/3 2//4 -1\nf 1 2 garbage\n"),
            Some(3)
        );
        assert_eq!(suspect_line("f 0 1 2\n"), Some(1));
    }

    const CUBE_WITH_GLASS: &str = "\
# unit square wall and a glass quad
mtllib ignored.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
f 1 2 5
usemtl Glass
f 1 2 3 4
";

    fn ned() -> ImportSettings {
        ImportSettings {
            axes: crate::AxisConvention::Ned,
            ..ImportSettings::default()
        }
    }

    #[test]
    fn reads_geometry_materials_and_counts() {
        let (mesh, r) = parse_obj(CUBE_WITH_GLASS.as_bytes(), &ned()).unwrap();
        assert_eq!(mesh.len(), 3);
        assert_eq!(
            mesh.materials(),
            &[Material::Opaque, Material::Glass, Material::Glass]
        );
        assert_eq!((r.faces_read, r.polygons_triangulated), (2, 1));
        assert_eq!(r.mesh.triangles_kept, 3);
        // ENU: the file's (x, y, z) = (east, north, up)
        let (enu, _) = parse_obj(CUBE_WITH_GLASS.as_bytes(), &ImportSettings::default()).unwrap();
        let (lo, hi) = enu.bounds().unwrap();
        assert_relative_eq!(lo, nalgebra::Vector3::new(0.0, 0.0, -1.0));
        assert_relative_eq!(hi, nalgebra::Vector3::new(1.0, 1.0, 0.0));
    }

    fn err(text: &str, settings: &ImportSettings) -> String {
        parse_obj(text.as_bytes(), settings)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn malformed_files_name_the_line() {
        let s = ned();
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\nf 1 2 9\n", &s),
            "OBJ line 5: vertex index 9 out of range (4 defined before this line)"
        );
        // relative and texture indices that reach outside (tobj would overflow)
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-8 2/1 3/1\n", &s),
            "OBJ line 5: texture coordinate index -8 out of range (1 defined before this line)"
        );
        assert_eq!(
            err(
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//9223372036854775807 2 3\n",
                &s
            ),
            "OBJ line 4: normal index 9223372036854775807 out of range (0 defined before this line)"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nl 1 0\n", &s),
            "OBJ line 3: vertex index 0 out of range (2 defined before this line)"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n", &s),
            "OBJ line 2: position parse error"
        );
        assert!(
            err("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n", &s).starts_with("OBJ line 2: vertex")
        );
        assert!(err("v 0 0 0\nv 1 0 inf\n", &s).starts_with("OBJ line 2:"));
        assert!(err("v 0 0 0\nv 2e9 0 0\n", &s).contains("beyond"));
        assert_eq!(
            err("v 0 0 0\nusemtl steel\n", &s),
            "OBJ line 2: unknown material `steel` (map it in the import settings' material table)"
        );
        let strict = ImportSettings {
            default_material: None,
            ..ned()
        };
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", &strict),
            "OBJ line 4: face without a material (no `usemtl` before it and no default material)"
        );
        assert_eq!(
            parse_obj(b"v 0 0 0\nv 1\xff 0 0\n", &s)
                .unwrap_err()
                .to_string(),
            "OBJ line 2: not valid UTF-8"
        );
        // truncated in the middle of a vertex line, a bad face
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1", &s),
            "OBJ line 3: position parse error"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", &s),
            "OBJ line 4: face parse error"
        );
    }

    #[test]
    fn custom_names_and_empty_files() {
        let mut s = ned();
        s.materials.insert("steel", Material::Other(7));
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl STEEL\nf 1 2 3\n";
        let (mesh, _) = parse_obj(text.as_bytes(), &s).unwrap();
        assert_eq!(mesh.materials(), &[Material::Other(7)]);
        let (empty, r) = parse_obj(b"", &s).unwrap();
        assert!(empty.is_empty() && r.faces_read == 0);
        let (_, r) = parse_obj(b"v 0 0 0\nv 1 0 0\nl 1 2\np 1\n", &s).unwrap();
        assert_eq!(r.ignored_elements, 2);
    }
}
