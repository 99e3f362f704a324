//! Where a replay's data folder is: the `[data] dir` of its settings, absolute or
//! looked up inside a base directory (the workspace root for `cargo xtask paper`, the
//! current directory for `fathom run`) and beside each of its ancestors.

use std::path::{Path, PathBuf};

/// The data folder `dir` inside `base` or beside one of its ancestors, the nearest
/// first (an absolute `dir` is used as it is), if it exists.
pub fn find_data_dir(base: &Path, dir: &str) -> Option<PathBuf> {
    let rel = Path::new(dir);
    if rel.is_absolute() {
        return rel.is_dir().then(|| rel.to_path_buf());
    }
    base.ancestors().map(|a| a.join(rel)).find(|p| p.is_dir())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_dir_is_found_inside_the_root_or_beside_an_ancestor_nearest_first() {
        let base = std::env::temp_dir()
            .join("fathom-replay-tests")
            .join(format!("data-dir-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        let root = base.join("a").join("repo");
        std::fs::create_dir_all(&root).unwrap();
        assert_eq!(find_data_dir(&root, "outside/data/x"), None);
        std::fs::create_dir_all(base.join("outside/data/x")).unwrap();
        assert_eq!(
            find_data_dir(&root, "outside/data/x"),
            Some(base.join("outside/data/x"))
        );
        // Inside the root (a user's `data/` next to their scenario) counts, and wins
        // over the same name further up.
        std::fs::create_dir_all(root.join("inside")).unwrap();
        assert_eq!(find_data_dir(&root, "inside"), Some(root.join("inside")));
        std::fs::create_dir_all(root.join("outside/data/x")).unwrap();
        assert_eq!(
            find_data_dir(&root, "outside/data/x"),
            Some(root.join("outside/data/x"))
        );
        let abs = base.join("outside/data/x");
        assert_eq!(find_data_dir(&root, abs.to_str().unwrap()), Some(abs));
    }
}
