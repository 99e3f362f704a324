//! A user's world file (Wavefront OBJ or STL) read into a [`TriMesh`] in local NED
//! metres, with the checks every job that takes one applies (the `urban` experiment's
//! `[scenarios.world] file` and the `gnss-ins` replay's `--world`): a regular file,
//! within the import's size limit, ending in `.obj` or `.stl`, with at least one
//! triangle. Errors name the settings key and the file.

use std::path::Path;

use fathom_core::echo::{echo_file, echo_path};
use fathom_map::{ImportSettings, TriMesh, obj::read_obj, stl::read_stl};
use fathom_sim::SimError;

/// Reads the world file `path` (relative paths from `base_dir`) with `settings`;
/// returns the mesh and a line saying what was read. `file` and `key` name the
/// settings file and key in errors.
///
/// # Errors
/// [`SimError::Invalid`] naming `key`: a file that cannot be read, is not a regular
/// file, exceeds `settings.max_bytes`, has another extension, does not parse (the
/// line or face named) or has no faces.
pub fn read_mesh_file(
    file: &str,
    key: &str,
    path: &str,
    base_dir: &Path,
    settings: &ImportSettings,
) -> Result<(TriMesh, String), SimError> {
    let bad = |reason: String| SimError::invalid(file, key, reason);
    let full = if Path::new(path).is_absolute() {
        Path::new(path).to_path_buf()
    } else {
        base_dir.join(path)
    };
    let ext = full
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let shown = echo_file(path);
    // Only a regular file is opened: opening a FIFO would block, a device would be
    // read to the import limit.
    let meta = std::fs::metadata(&full)
        .map_err(|e| bad(format!("cannot read `{}`: {e}", echo_path(&full))))?;
    if !meta.is_file() {
        return Err(bad(format!("`{shown}` is not a regular file")));
    }
    if meta.len() > settings.max_bytes {
        return Err(bad(format!(
            "`{shown}`: {}",
            fathom_map::MapError::TooLarge {
                bytes: meta.len(),
                limit: settings.max_bytes
            }
        )));
    }
    let reader = std::fs::File::open(&full)
        .map_err(|e| bad(format!("cannot read `{}`: {e}", echo_path(&full))))?;
    let parsed = match ext.as_str() {
        "obj" => read_obj(reader, settings),
        "stl" => read_stl(reader, settings),
        _ => {
            return Err(bad(format!(
                "`{shown}`: the world file must end in .obj or .stl"
            )));
        }
    };
    let (mesh, report) = parsed.map_err(|e| bad(e.in_file(path).to_string()))?;
    if mesh.is_empty() {
        return Err(bad(format!(
            "`{shown}` has no faces ({} read, {} degenerate or duplicate): a world needs triangles",
            report.faces_read,
            report.mesh.degenerate_skipped + report.mesh.duplicate_skipped
        )));
    }
    let source = format!(
        "file `{path}`: {} triangles ({} faces read, {} degenerate and {} duplicate skipped)",
        mesh.len(),
        report.faces_read,
        report.mesh.degenerate_skipped,
        report.mesh.duplicate_skipped
    );
    Ok((mesh, source))
}
