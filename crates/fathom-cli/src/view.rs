//! `fathom view DIR`: the path of an output folder's 3D scene page, opened in a
//! browser where one is available.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::anyhow;
use clap::Args;

use crate::Failure;

/// The page's file name in an output folder.
pub const SCENE_PAGE: &str = "scene.html";

#[derive(Debug, Args)]
pub struct ViewArgs {
    /// An output folder of a run with a world (`fathom run` of an `urban` file,
    /// `fathom pils`), or the `scene.html` file itself.
    dir: PathBuf,
    /// Only print the path; do not start a browser.
    #[arg(long)]
    no_open: bool,
}

/// The scene page of `dir`: `dir/scene.html`, `dir/sim/scene.html` (a `fathom pils`
/// folder: the simulator side writes it), or `dir` itself when it is the page.
fn find_page(dir: &Path) -> Option<PathBuf> {
    if dir.is_file() {
        return Some(dir.to_path_buf());
    }
    [dir.join(SCENE_PAGE), dir.join("sim").join(SCENE_PAGE)]
        .into_iter()
        .find(|p| p.is_file())
}

/// A browser opener of this system, if any: `$BROWSER`, then `xdg-open` (Linux with
/// a desktop), `open` (macOS); `None` without a display on Linux.
fn opener() -> Option<String> {
    if let Ok(b) = std::env::var("BROWSER")
        && !b.trim().is_empty()
    {
        return Some(b);
    }
    if cfg!(target_os = "macos") {
        return Some("open".into());
    }
    if cfg!(windows) {
        return Some("explorer".into());
    }
    let display = ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|x| !x.is_empty()));
    display.then(|| "xdg-open".into())
}

/// `fathom view DIR`.
pub(crate) fn view_cmd(args: &ViewArgs) -> Result<String, Failure> {
    let page = find_page(&args.dir).ok_or_else(|| {
        Failure::Usage(anyhow!(
            "`{}` holds no {SCENE_PAGE} (runs with a world write it unless --no-scene)",
            args.dir.display()
        ))
    })?;
    let page = std::fs::canonicalize(&page).unwrap_or(page);
    let mut out = format!("{}\n", page.display());
    if !args.no_open
        && let Some(cmd) = opener()
    {
        // The browser runs on its own; a failure to start it is only reported.
        let started = Command::new(&cmd)
            .arg(&page)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn();
        if started.is_err() {
            out.push_str(&format!("(could not start `{cmd}`; open the file above)\n"));
        }
    }
    Ok(out)
}
