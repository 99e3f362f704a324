//! `fathom pils compare`, the realtime-vs-lockstep study: every run flown in lockstep
//! and in real time, both processes per session; the per-run errors, the paired
//! difference with its 95 % CI (`fathom_pils::compare`) and the figures
//! (`fathom_pils::figures`) written into the study's folder.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, anyhow};
use fathom_pils::compare::{Comparison, RunPair, title};
use fathom_pils::faults::FaultParams;
use fathom_pils::session::Prepared;
use fathom_pils::settings::{Pacing, Settings};

use crate::Failure;
use crate::pils_session::{both, claim, commit, prepare, run_err, write_named};

/// `fathom pils compare`: run `run .. run + runs` of the file, each in lockstep on
/// a clean link (its result does not depend on the link's faults, which only cost
/// time in lockstep) and in real time with the file's faults, both processes per
/// session; writes `runs.csv`, `report.md`, `comparison.json`, `summary.json`, the
/// figures and every session's own outputs (`run<R>_<pacing>/`).
///
/// # Errors
/// [`Failure::Usage`] for bad settings or `--out`; [`Failure::Run`] when a session
/// fails (what was recorded is kept).
pub(crate) fn compare(
    scenario: &Path,
    s: &Settings,
    runs: usize,
    out: &Path,
    force: bool,
) -> Result<String, Failure> {
    let t0 = Instant::now();
    if !(2..=1000).contains(&runs) {
        return Err(Failure::Usage(anyhow!(
            "--runs {runs}: must be 2 to 1000 (a confidence interval needs a spread)"
        )));
    }
    // The first run is flown here to check the settings before the folder is claimed.
    let mut first = Some(prepare(s, scenario)?);
    let flown = first
        .as_ref()
        .map(|p| format!("{}/{}", p.flight.scene_name(), p.flight.method.name()))
        .unwrap_or_default();
    let dir = claim(out, force)?;
    let result = study(s, runs, dir.dir(), &mut first, &flown);
    commit(dir, scenario, s, Some(runs), t0)?;
    let c = result?;
    Ok(c.markdown(&title(s, &flown)) + &format!("\noutputs in {}\n", out.display()))
}

/// The sessions and the outputs of the study (into `dir`).
fn study(
    s: &Settings,
    runs: usize,
    dir: &Path,
    first: &mut Option<Prepared>,
    flown: &str,
) -> Result<Comparison, Failure> {
    // The sessions' settings name the scenario by its absolute path (they are
    // written into the sessions' folders).
    let scenario_abs = std::path::absolute(&s.scenario_path)
        .context("the scenario's path")
        .map_err(Failure::Run)?;
    let mut pairs = Vec::with_capacity(runs);
    let mut example: Vec<(&'static str, Vec<(f64, f64)>)> = Vec::new();
    let mut latencies_ms = Vec::new();
    for i in 0..runs as u64 {
        let run = s.file.run + i;
        let mut base = s.clone();
        base.file.run = run;
        base.file.scenario = scenario_abs.display().to_string();
        let p = match first.take() {
            Some(p) => p,
            None => Prepared::new(&base).map_err(|e| Failure::Run(anyhow!("run {run}: {e}")))?,
        };
        let mut reports = Vec::with_capacity(2);
        for (label, pacing) in [
            ("lockstep", Pacing::Lockstep),
            ("realtime", Pacing::Realtime),
        ] {
            let mut settings = base.clone();
            settings.file.link.pacing = pacing;
            if pacing == Pacing::Lockstep {
                settings.file.link.faults = FaultParams::NONE;
            }
            let sdir = dir.join(format!("run{run:03}_{label}"));
            let text = toml::to_string(&settings.file)
                .context("settings as TOML")
                .map_err(Failure::Run)?;
            write_named(&sdir, &[("scenario.toml", text)])?;
            let (r, _) = both(&sdir.join("scenario.toml"), &settings, &p, &sdir);
            let r = r?;
            if let Some(e) = &r.error {
                return Err(Failure::Run(anyhow!(
                    "run {run} {label}: {e} (what was recorded is in {})",
                    sdir.display()
                )));
            }
            if i == 0
                && let Some(series) = &r.series
                && let Some((_, pts)) = series.error_3d.first()
            {
                example.push((label, pts.clone()));
            }
            if pacing == Pacing::Realtime
                && let Some(series) = &r.series
            {
                latencies_ms.extend(series.latencies_s.iter().map(|v| v * 1e3));
            }
            eprintln!(
                "run {run} {label}: {} solutions ({} late), rmse_3d {:.3} m, {:.1} s",
                r.report.solutions,
                r.report.late_solutions,
                r.report.pils.map_or(f64::NAN, |e| e.rmse_3d),
                r.report.wall_s
            );
            reports.push(r.report);
        }
        let (l, rt) = (&reports[0], &reports[1]);
        let (Some(le), Some(re)) = (l.pils, rt.pils) else {
            return Err(Failure::Run(anyhow!(
                "run {run}: a session got no solution"
            )));
        };
        pairs.push(RunPair {
            run,
            lockstep: le,
            realtime: re,
            lockstep_equal_offline: l.equal_to_offline_quantized == Some(true),
            steps: rt.steps_total,
            realtime_solutions: rt.solutions,
            realtime_answers: rt.latency.map_or(0, |q| q.count),
            realtime_late: rt.late_solutions,
            realtime_latency_ms: rt.latency.map_or([f64::NAN; 2], |q| [q.p50_ms, q.p95_ms]),
        });
    }
    let c = Comparison::new(pairs, s.seed).map_err(run_err)?;
    write_named(dir, &c.files(s, flown).map_err(run_err)?)?;
    let figures =
        fathom_pils::figures::study_figures(&c, &example, &latencies_ms).map_err(run_err)?;
    write_named(dir, &figures)?;
    Ok(c)
}
