//! Output folders that never lose work: every front end (`fathom run`, `fathom replay`,
//! `fathom merge`, a campaign shard, `cargo xtask paper`) writes an experiment's outputs
//! through one [`OutDir`].
//!
//! 1. [`OutDir::claim`] runs *before* anything is computed. It takes a lock file beside
//!    the folder (`.<name>.lock`, an OS file lock, so it vanishes with a killed
//!    process), refuses a folder that another process holds, refuses a folder holding
//!    anything fathom did not write (unless `force`), and creates the fresh temporary
//!    folder `.<name>.partial-<pid>` beside it, which also proves that the place is
//!    writable. All of these are user errors ([`ReportError::InvalidArgument`] naming
//!    `--out`).
//! 2. The caller writes every output into [`OutDir::dir`].
//! 3. [`OutDir::commit`] writes [`RUN_INFO_FILE`] (which lists the files fathom wrote,
//!    so that a later run knows what it may replace) and moves the folder into place:
//!    the previous folder is renamed aside, the new one renamed in, the old one
//!    removed. Until then the previous results are untouched, so an error or an
//!    interruption while computing or writing leaves them as they were. With `force`
//!    and foreign files present, the folder is not swapped: fathom's new files are
//!    renamed in one by one (each rename atomic), fathom's old files that the new run
//!    did not write are removed, and the foreign files stay where they are.
//!
//! Leftovers of a killed process (`.<name>.partial-*`, `.<name>.old-*`) hold only
//! fathom's files; the next claim removes them (restoring `.<name>.old-*` when the
//! process died between the two renames of a commit).

use std::ffi::OsString;
use std::fs::File;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::ReportError;

/// The file that marks a folder as written by fathom and lists its files.
pub const RUN_INFO_FILE: &str = "run_info.json";

/// What fathom writes into [`RUN_INFO_FILE`] of every output folder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunInfo {
    /// `fathom` version (the workspace version of `fathom-sim`).
    pub fathom_version: String,
    /// The command that wrote the folder (`run`, `replay`, `merge`, `shard`, `paper`).
    #[serde(default)]
    pub command: String,
    /// The experiment run.
    pub experiment: String,
    /// The scenario file as given.
    pub scenario: String,
    /// `--runs` override, if any.
    pub runs: Option<usize>,
    /// `--threads`, if given.
    pub threads: Option<usize>,
    /// `--seed` override, if given.
    #[serde(default)]
    pub seed: Option<u64>,
    /// The base seed the runs actually used (the scenario's `base_seed`, or `--seed`);
    /// `None` for a deterministic experiment (no `base_seed`, e.g. `plaza`). The same
    /// value is in `scenario.resolved.toml` and `summary.json`.
    #[serde(default)]
    pub base_seed: Option<u64>,
    /// Wall-clock time of the experiment, s (kept here, not in `summary.json`, which
    /// is byte-identical for the same scenario and seed).
    #[serde(default)]
    pub elapsed_s: f64,
    /// Every file fathom wrote into the folder (sorted, this file excluded): what a
    /// later run may replace. Anything else in the folder is the user's.
    #[serde(default)]
    pub files: Vec<String>,
}

/// Extensions of the files an older fathom (before [`RunInfo::files`]) wrote.
const LEGACY_EXTENSIONS: [&str; 5] = ["svg", "csv", "json", "md", "toml"];

/// How many foreign entries a refusal names before "and N more".
const NAMED_FOREIGN: usize = 3;

fn out_error(out: &Path, reason: impl Into<String>) -> ReportError {
    ReportError::invalid_argument("--out", format!("`{}`: {}", out.display(), reason.into()))
}

/// The lock file beside an output folder, held for the life of an [`OutDir`].
#[derive(Debug)]
struct Lock {
    file: File,
    path: PathBuf,
}

impl Lock {
    /// Takes the lock at `path` or says which process holds it.
    fn take(path: &Path, out: &Path) -> Result<Lock, ReportError> {
        // A lock file removed by its previous holder between our open and our lock is
        // detected (different file) and opened again.
        for _ in 0..8 {
            let mut file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(path)
                .map_err(|e| out_error(out, format!("cannot create the lock file: {e}")))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    let holder = std::fs::read_to_string(path).unwrap_or_default();
                    let holder = holder.trim();
                    let who = if holder.is_empty() {
                        String::from("another fathom process")
                    } else {
                        format!("another fathom process ({holder})")
                    };
                    return Err(out_error(
                        out,
                        format!(
                            "{who} is writing into this folder; wait for it to finish or choose \
                             another --out"
                        ),
                    ));
                }
                Err(std::fs::TryLockError::Error(e)) => {
                    return Err(out_error(
                        out,
                        format!("cannot lock `{}`: {e}", path.display()),
                    ));
                }
            }
            if !same_file(&file, path) {
                continue;
            }
            let _ = file.set_len(0);
            let _ = write!(file, "pid {}", std::process::id());
            let _ = file.flush();
            return Ok(Lock {
                file,
                path: path.to_path_buf(),
            });
        }
        Err(out_error(
            out,
            "the lock file keeps changing; another fathom process is starting on this folder",
        ))
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        // Remove the file while still holding the lock, so a waiting process that
        // opened it sees a file that is no longer at the path and opens a new one.
        if same_file(&self.file, &self.path) {
            let _ = std::fs::remove_file(&self.path);
        }
        let _ = self.file.unlock();
    }
}

#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt as _;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_file: &File, path: &Path) -> bool {
    path.exists()
}

/// What an existing output folder holds.
#[derive(Debug, Default)]
struct Contents {
    /// Entries fathom wrote (per its [`RUN_INFO_FILE`], or an older fathom's layout).
    own: Vec<OsString>,
    /// Everything else (the user's).
    foreign: Vec<OsString>,
}

/// Sorts the entries of the existing folder `out` into fathom's and the user's.
fn contents(out: &Path) -> Result<Contents, ReportError> {
    let entries =
        std::fs::read_dir(out).map_err(|e| out_error(out, format!("cannot list: {e}")))?;
    let mut names = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| out_error(out, format!("cannot list: {e}")))?;
        let is_file = entry.file_type().map(|t| t.is_file()).unwrap_or(false);
        names.push((entry.file_name(), is_file));
    }
    names.sort();
    let info = std::fs::read_to_string(out.join(RUN_INFO_FILE))
        .ok()
        .and_then(|t| serde_json::from_str::<RunInfo>(&t).ok());
    let listed = info.as_ref().filter(|i| !i.files.is_empty());
    // An older fathom wrote no file list: a folder with its `summary.json` and only
    // files of its extensions is taken as its output; anything else is the user's.
    let legacy = listed.is_none()
        && names.iter().any(|(n, f)| *f && n == "summary.json")
        && names.iter().all(|(n, f)| {
            *f && Path::new(n)
                .extension()
                .and_then(|x| x.to_str())
                .is_some_and(|x| LEGACY_EXTENSIONS.contains(&x))
        });
    let mut c = Contents::default();
    for (name, is_file) in names {
        // A folder fathom wrote (a PILS session's `sim/`, `nav/`) is its own when the
        // file list names it; an unlisted folder is the user's.
        let in_list = listed.is_some_and(|i| i.files.iter().any(|f| name == f.as_str()));
        let own = if is_file {
            name == RUN_INFO_FILE && info.is_some() || legacy || in_list
        } else {
            in_list
        };
        if own {
            c.own.push(name);
        } else {
            c.foreign.push(name);
        }
    }
    Ok(c)
}

fn listing(names: &[OsString]) -> String {
    let mut shown: Vec<String> = names
        .iter()
        .take(NAMED_FOREIGN)
        .map(|n| format!("`{}`", n.to_string_lossy()))
        .collect();
    if names.len() > NAMED_FOREIGN {
        shown.push(format!("{} more", names.len() - NAMED_FOREIGN));
    }
    shown.join(", ")
}

/// An output folder claimed for writing (see the module docs).
#[derive(Debug)]
pub struct OutDir {
    /// The folder as the user gave it (for messages and the result's paths).
    out: PathBuf,
    /// Its absolute path.
    target: PathBuf,
    /// The temporary folder beside it that receives the outputs.
    tmp: PathBuf,
    /// The user's entries in an existing folder, kept by a forced write.
    foreign: Vec<OsString>,
    /// Released after the commit (or on drop).
    lock: Option<Lock>,
    committed: bool,
}

impl OutDir {
    /// Claims `out` for writing (lock, ownership, writability); see the module docs.
    ///
    /// # Errors
    /// [`ReportError::InvalidArgument`] naming `--out`: a folder held by another process,
    /// holding files fathom did not write (without `force`), not a folder, the current
    /// directory or one of its ancestors, or not writable.
    pub fn claim(out: &Path, force: bool) -> Result<OutDir, ReportError> {
        let target = std::path::absolute(out)
            .map_err(|e| out_error(out, format!("cannot resolve the path: {e}")))?;
        let name = match target.file_name() {
            Some(n)
                if target
                    .components()
                    .next_back()
                    .is_some_and(|c| matches!(c, std::path::Component::Normal(_))) =>
            {
                n.to_string_lossy().into_owned()
            }
            _ => return Err(out_error(out, "name a folder (not `.`, `..` or `/`)")),
        };
        let parent = target
            .parent()
            .map(Path::to_path_buf)
            .ok_or_else(|| out_error(out, "name a folder (not `/`)"))?;
        if let Ok(meta) = std::fs::symlink_metadata(&target) {
            if meta.file_type().is_symlink() {
                return Err(out_error(
                    out,
                    "is a symbolic link; give the folder it points to",
                ));
            }
            if !meta.is_dir() {
                return Err(out_error(out, "is a file, not a folder"));
            }
            let here = std::env::current_dir()
                .ok()
                .and_then(|d| d.canonicalize().ok());
            let there = target.canonicalize().ok();
            if let (Some(here), Some(there)) = (here, there)
                && here.starts_with(&there)
            {
                return Err(out_error(
                    out,
                    "is the current directory or contains it; choose a folder below it",
                ));
            }
        }
        std::fs::create_dir_all(&parent).map_err(|e| {
            out_error(
                out,
                format!("cannot create the folder `{}`: {e}", parent.display()),
            )
        })?;
        let lock = Lock::take(&parent.join(format!(".{name}.lock")), out)?;
        recover_leftovers(&parent, &name, &target)?;
        let mut foreign = Vec::new();
        if target.is_dir() {
            let c = contents(&target)?;
            if !c.foreign.is_empty() {
                if !force {
                    return Err(out_error(
                        out,
                        format!(
                            "holds files fathom did not write ({}); choose a new or empty \
                             folder, or add --force to replace only fathom's own files and keep \
                             these",
                            listing(&c.foreign)
                        ),
                    ));
                }
                probe(&target, out)?;
                foreign = c.foreign;
            }
        }
        let tmp = parent.join(format!(".{name}.partial-{}", std::process::id()));
        if tmp.exists() {
            std::fs::remove_dir_all(&tmp)
                .map_err(|e| out_error(out, format!("cannot remove `{}`: {e}", tmp.display())))?;
        }
        std::fs::create_dir(&tmp).map_err(|e| {
            out_error(
                out,
                format!(
                    "cannot create a folder beside it (`{}`): {e}",
                    tmp.display()
                ),
            )
        })?;
        let claimed = OutDir {
            out: out.to_path_buf(),
            target,
            tmp,
            foreign,
            lock: Some(lock),
            committed: false,
        };
        probe(&claimed.tmp, out)?;
        Ok(claimed)
    }

    /// The temporary folder to write the outputs into.
    pub fn dir(&self) -> &Path {
        &self.tmp
    }

    /// The folder as given by the user (where the outputs are after the commit).
    pub fn path(&self) -> &Path {
        &self.out
    }

    /// Writes [`RUN_INFO_FILE`] (with `info.files` set to the files in [`Self::dir`])
    /// and moves the outputs into place; returns the file list.
    ///
    /// # Errors
    /// I/O errors; a forced write whose new file has the name of one of the user's
    /// files (the user's file is kept, the new outputs stay in the temporary folder).
    pub fn commit(mut self, mut info: RunInfo) -> Result<Vec<String>, ReportError> {
        let mut files = Vec::new();
        let entries = std::fs::read_dir(&self.tmp)
            .map_err(|e| ReportError::io("list directory", &self.tmp, e))?;
        for entry in entries {
            let entry = entry.map_err(|e| ReportError::io("list directory", &self.tmp, e))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            if name != RUN_INFO_FILE {
                files.push(name);
            }
        }
        files.sort();
        info.files = files.clone();
        let json = serde_json::to_string_pretty(&info).map_err(|e| ReportError::Json {
            path: self.tmp.join(RUN_INFO_FILE),
            source: e,
        })?;
        crate::output::write_text(self.tmp.join(RUN_INFO_FILE), &(json + "\n"))?;
        if self.foreign.is_empty() || !self.target.is_dir() {
            self.swap()?;
        } else {
            self.merge_in(&files)?;
        }
        self.committed = true;
        self.lock.take();
        Ok(files)
    }

    /// The whole folder replaced by the new one.
    fn swap(&self) -> Result<(), ReportError> {
        let name = self
            .target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let old = self
            .tmp
            .with_file_name(format!(".{name}.old-{}", std::process::id()));
        let had_old = self.target.exists();
        if had_old {
            std::fs::rename(&self.target, &old)
                .map_err(|e| ReportError::io("move aside", &self.target, e))?;
        }
        if let Err(e) = std::fs::rename(&self.tmp, &self.target) {
            if had_old {
                let _ = std::fs::rename(&old, &self.target);
            }
            return Err(ReportError::io("move into place", &self.target, e));
        }
        if had_old {
            std::fs::remove_dir_all(&old).map_err(|e| ReportError::io("remove", &old, e))?;
        }
        Ok(())
    }

    /// The new files renamed into the existing folder one by one, the user's kept.
    fn merge_in(&self, files: &[String]) -> Result<(), ReportError> {
        if let Some(clash) = self
            .foreign
            .iter()
            .find(|f| files.iter().any(|n| *f == n.as_str()) || *f == RUN_INFO_FILE)
        {
            return Err(ReportError::Output {
                path: self.target.join(clash),
                reason: format!(
                    "not replacing your file with fathom's output of the same name; the new \
                     outputs are in `{}`",
                    self.tmp.display()
                ),
            });
        }
        let old = contents(&self.target)?;
        for name in files.iter().map(String::as_str).chain([RUN_INFO_FILE]) {
            let from = self.tmp.join(name);
            let to = self.target.join(name);
            std::fs::rename(&from, &to).map_err(|e| ReportError::io("move into place", &to, e))?;
        }
        for name in old.own {
            let keep = name == RUN_INFO_FILE || files.iter().any(|n| name == n.as_str());
            if !keep {
                let p = self.target.join(&name);
                std::fs::remove_file(&p).map_err(|e| ReportError::io("remove", &p, e))?;
            }
        }
        std::fs::remove_dir(&self.tmp).map_err(|e| ReportError::io("remove", &self.tmp, e))
    }

    /// The final path of `file` written into [`Self::dir`].
    pub fn final_path(&self, file: &Path) -> PathBuf {
        match file.strip_prefix(&self.tmp) {
            Ok(rel) => self.out.join(rel),
            Err(_) => file.to_path_buf(),
        }
    }
}

impl Drop for OutDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.tmp);
        }
    }
}

/// A file can be created in `dir`.
fn probe(dir: &Path, out: &Path) -> Result<(), ReportError> {
    let p = dir.join(format!(".fathom-probe-{}", std::process::id()));
    std::fs::write(&p, b"probe")
        .and_then(|()| std::fs::remove_file(&p))
        .map_err(|e| out_error(out, format!("cannot write into `{}`: {e}", dir.display())))
}

/// Removes the temporary folders of killed processes (the lock is held, so nobody
/// else writes them); restores the previous folder if a process died between the two
/// renames of a commit.
fn recover_leftovers(parent: &Path, name: &str, target: &Path) -> Result<(), ReportError> {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return Ok(());
    };
    let partial = format!(".{name}.partial-");
    let old = format!(".{name}.old-");
    let mut olds = Vec::new();
    for entry in entries.flatten() {
        let n = entry.file_name().to_string_lossy().into_owned();
        if n.starts_with(&partial) {
            let _ = std::fs::remove_dir_all(entry.path());
        } else if n.starts_with(&old) {
            olds.push(entry.path());
        }
    }
    for p in olds {
        if !target.exists() {
            std::fs::rename(&p, target).map_err(|e| ReportError::io("restore", target, e))?;
        } else {
            let _ = std::fs::remove_dir_all(&p);
        }
    }
    Ok(())
}

/// Writes `text` to `path` through a temporary file beside it and a rename, so the
/// file is either the old or the new one, never half-written.
///
/// # Errors
/// I/O errors.
pub fn write_file_atomically(path: &Path, text: &str) -> Result<(), ReportError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.partial-{}", std::process::id()));
    crate::output::write_text(&tmp, text)?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        ReportError::io("move into place", path, e)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir()
            .join("fathom-sim-tests")
            .join(format!("outdir-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn info() -> RunInfo {
        RunInfo {
            fathom_version: "t".into(),
            command: "test".into(),
            experiment: "e".into(),
            scenario: "s.toml".into(),
            runs: None,
            threads: None,
            seed: None,
            base_seed: None,
            elapsed_s: 0.0,
            files: Vec::new(),
        }
    }

    fn write(d: &Path, files: &[(&str, &str)]) -> Vec<String> {
        let o = OutDir::claim(d, false).unwrap();
        for (n, t) in files {
            std::fs::write(o.dir().join(n), t).unwrap();
        }
        o.commit(info()).unwrap()
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_rerun_replaces_fathoms_files_and_leaves_nothing_beside() {
        let root = scratch("rerun");
        let out = root.join("out");
        assert_eq!(
            write(&out, &[("a.svg", "1"), ("b.csv", "1")]),
            ["a.svg", "b.csv"]
        );
        write(&out, &[("a.svg", "2")]);
        assert_eq!(names(&out), ["a.svg", RUN_INFO_FILE]);
        assert_eq!(std::fs::read_to_string(out.join("a.svg")).unwrap(), "2");
        // No lock file, no temporary folder left beside it.
        assert_eq!(names(&root), ["out"]);
    }

    #[test]
    fn foreign_files_are_refused_and_kept_by_force() {
        let root = scratch("foreign");
        let out = root.join("out");
        write(&out, &[("a.svg", "1"), ("b.csv", "1")]);
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        let e = OutDir::claim(&out, false).unwrap_err().to_string();
        assert!(e.starts_with("invalid --out: `"), "{e}");
        assert!(e.contains("`notes.txt`") && e.contains("--force"), "{e}");
        let o = OutDir::claim(&out, true).unwrap();
        std::fs::write(o.dir().join("a.svg"), "2").unwrap();
        o.commit(info()).unwrap();
        assert_eq!(names(&out), ["a.svg", "notes.txt", RUN_INFO_FILE]);
        assert_eq!(
            std::fs::read_to_string(out.join("notes.txt")).unwrap(),
            "mine"
        );
        assert_eq!(std::fs::read_to_string(out.join("a.svg")).unwrap(), "2");
        // Still the user's: refused again without --force.
        assert!(OutDir::claim(&out, false).is_err());
        // A forced output that would overwrite the user's file is refused, the file kept.
        let o = OutDir::claim(&out, true).unwrap();
        std::fs::write(o.dir().join("notes.txt"), "fathom").unwrap();
        assert!(o.commit(info()).is_err());
        assert_eq!(
            std::fs::read_to_string(out.join("notes.txt")).unwrap(),
            "mine"
        );
    }

    /// A folder fathom wrote into its output (a PILS session's `sim/`) is replaced by the
    /// next run without --force; a folder of the user's is not (negative control).
    #[test]
    fn subfolders_fathom_wrote_are_its_own() {
        let root = scratch("subfolders");
        let out = root.join("out");
        let o = OutDir::claim(&out, false).unwrap();
        std::fs::create_dir_all(o.dir().join("sim")).unwrap();
        std::fs::write(o.dir().join("sim/a.csv"), "1").unwrap();
        o.commit(info()).unwrap();
        let o = OutDir::claim(&out, false).unwrap();
        std::fs::create_dir_all(o.dir().join("sim")).unwrap();
        std::fs::write(o.dir().join("sim/a.csv"), "2").unwrap();
        o.commit(info()).unwrap();
        assert_eq!(std::fs::read_to_string(out.join("sim/a.csv")).unwrap(), "2");
        std::fs::create_dir_all(out.join("mine")).unwrap();
        let e = OutDir::claim(&out, false).unwrap_err().to_string();
        assert!(e.contains("`mine`"), "{e}");
    }

    #[test]
    fn an_uncommitted_claim_leaves_the_previous_folder_intact() {
        let root = scratch("abort");
        let out = root.join("out");
        write(&out, &[("a.svg", "1")]);
        {
            let o = OutDir::claim(&out, false).unwrap();
            std::fs::write(o.dir().join("a.svg"), "half").unwrap();
            // Dropped without commit: an error while computing.
        }
        assert_eq!(std::fs::read_to_string(out.join("a.svg")).unwrap(), "1");
        assert_eq!(names(&root), ["out"]);
    }

    #[test]
    fn a_held_folder_is_refused() {
        let root = scratch("held");
        let out = root.join("out");
        let first = OutDir::claim(&out, false).unwrap();
        let e = OutDir::claim(&out, true).unwrap_err().to_string();
        assert!(e.contains("another fathom process (pid "), "{e}");
        drop(first);
        assert!(OutDir::claim(&out, false).is_ok());
    }

    #[test]
    fn leftovers_of_a_killed_process_are_cleaned_or_restored() {
        let root = scratch("leftovers");
        let out = root.join("out");
        write(&out, &[("a.svg", "1")]);
        // Killed between the two renames of a commit: the old folder aside, none in place.
        std::fs::rename(&out, root.join(".out.old-1")).unwrap();
        std::fs::create_dir(root.join(".out.partial-1")).unwrap();
        let o = OutDir::claim(&out, false).unwrap();
        assert_eq!(std::fs::read_to_string(out.join("a.svg")).unwrap(), "1");
        drop(o);
        assert_eq!(names(&root), ["out"]);
    }

    #[test]
    fn unusable_places_are_refused_before_anything_is_written() {
        let root = scratch("unusable");
        std::fs::write(root.join("file"), "x").unwrap();
        for bad in [root.join("file"), root.join("file/sub"), PathBuf::from("/")] {
            let e = OutDir::claim(&bad, true).unwrap_err();
            assert!(
                matches!(e, ReportError::InvalidArgument { ref what, .. } if what == "--out"),
                "{e}"
            );
        }
        assert_eq!(names(&root), ["file"]);
        // An older fathom's folder (no file list) is fathom's when it holds only its
        // kinds of files; a user's file makes it foreign.
        let legacy = root.join("legacy");
        std::fs::create_dir(&legacy).unwrap();
        std::fs::write(legacy.join("summary.json"), "{}").unwrap();
        std::fs::write(legacy.join("x.svg"), "").unwrap();
        drop(OutDir::claim(&legacy, false).unwrap());
        std::fs::write(legacy.join("notes.txt"), "").unwrap();
        assert!(OutDir::claim(&legacy, false).is_err());
    }
}
