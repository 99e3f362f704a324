//! The `plaza` experiment: range-beacon localization on real data, the CMU Plaza1 log
//! (see `shared/data/plaza1/README.md`), with dead reckoning, AS / SC / SI and
//! ablations ([`crate::replay::plaza`]).
//!
//! The data is not part of the repository. The folder named by `[data] dir` in
//! `scenarios/plaza.toml` (default `shared/data/plaza1`) is looked up inside the
//! workspace root (or the current directory for `fathom run`) and beside each of its
//! ancestors, so a checkout next to `shared/`
//! finds `../shared/data/plaza1`. When it is absent the experiment is **skipped**: it
//! prints a message, returns a summary without rows (`runs = 0`) and a report saying
//! why, and `cargo xtask paper` does not fail.

use std::path::{Path, PathBuf};

use crate::SimError;
use crate::data::plaza::PlazaLog;
use crate::experiment::{Experiment, ExperimentContext, ExperimentOutput};
use crate::output::Summary;
use crate::replay::plaza::{parse_settings, replay};
use crate::replay::plaza_output::{EXPERIMENT_NAME, SEED_DOC, write_outputs};

/// Registry entry of the `plaza` experiment.
pub const EXPERIMENT: Experiment = Experiment {
    name: EXPERIMENT_NAME,
    seed_doc: SEED_DOC,
    default_scenario: "scenarios/plaza.toml",
    run,
};

/// The data folder `dir` inside `workspace_root` (for `fathom run`, the current
/// directory) or beside one of its ancestors, the nearest first (an absolute `dir` is
/// used as it is), if it exists.
pub fn find_data_dir(workspace_root: &Path, dir: &str) -> Option<PathBuf> {
    let rel = Path::new(dir);
    if rel.is_absolute() {
        return rel.is_dir().then(|| rel.to_path_buf());
    }
    workspace_root
        .ancestors()
        .map(|a| a.join(rel))
        .find(|p| p.is_dir())
}

fn run(ctx: &ExperimentContext) -> Result<ExperimentOutput, SimError> {
    let text = std::fs::read_to_string(&ctx.scenario_path)
        .map_err(|e| SimError::io("read", &ctx.scenario_path, e))?;
    let settings = parse_settings(&text, &ctx.scenario_label)?;
    let Some(dir) = find_data_dir(&ctx.workspace_root, &settings.data_dir) else {
        let msg = format!(
            "data folder `{}` not found in `{}` or beside any of its ancestors",
            settings.data_dir,
            ctx.workspace_root.display()
        );
        eprintln!("plaza: skipped: {msg}");
        return Ok(ExperimentOutput {
            summary: Summary::new(EXPERIMENT_NAME, SEED_DOC, 0, 0),
            report_section: format!(
                "**Skipped:** {msg}. The Plaza data is not part of the repository; put the \
                 data set's three files (`*_DR.txt`, `*_TD.txt`, `*_.mat`) in that folder, \
                 or run `fathom replay plaza <dir>` on any folder holding them."
            ),
        });
    };
    let log = PlazaLog::read_dir(&dir, settings.range_order).map_err(|e| {
        SimError::model(format!("reading the Plaza data in `{}`", dir.display()), e)
    })?;
    let result = replay(&log, &settings)?;
    let out = write_outputs(&result, &ctx.out_dir)?;
    Ok(ExperimentOutput {
        summary: out.summary,
        report_section: format!(
            "Real data, one deterministic replay (no Monte Carlo: `runs` = 1, no CIs, no \
             paper numbers). Data folder: `{}`.\n\n{}",
            dir.display(),
            out.report_section
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_dir_is_found_inside_the_root_or_beside_an_ancestor_nearest_first() {
        let base = std::env::temp_dir()
            .join("fathom-sim-tests")
            .join(format!("plaza-find-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        let root = base.join("a").join("repo");
        std::fs::create_dir_all(&root).unwrap();
        assert_eq!(find_data_dir(&root, "shared/data/x"), None);
        std::fs::create_dir_all(base.join("shared/data/x")).unwrap();
        assert_eq!(
            find_data_dir(&root, "shared/data/x"),
            Some(base.join("shared/data/x"))
        );
        // Inside the root (a user's `data/` next to their scenario) counts, and wins
        // over the same name further up.
        std::fs::create_dir_all(root.join("inside")).unwrap();
        assert_eq!(find_data_dir(&root, "inside"), Some(root.join("inside")));
        std::fs::create_dir_all(root.join("shared/data/x")).unwrap();
        assert_eq!(
            find_data_dir(&root, "shared/data/x"),
            Some(root.join("shared/data/x"))
        );
        let abs = base.join("shared/data/x");
        assert_eq!(find_data_dir(&root, abs.to_str().unwrap()), Some(abs));
    }
}
