//! `fathom pils` figures and the realtime-vs-lockstep study (`fathom pils compare`):
//! the error of a session versus time next to the offline references, its solution
//! latency histogram, and, over runs, the per-run errors of both pacings with the
//! paired difference and its 95 % CI (`fathom_pils::compare`).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, anyhow};
use fathom_pils::compare::{Comparison, RunPair, unit};
use fathom_pils::faults::FaultParams;
use fathom_pils::session::{Prepared, SimSeries};
use fathom_pils::settings::{Pacing, Settings};
use fathom_report::output::{Row, Summary};
use fathom_report::plot::{Figure, Histogram, LinePlot, Series};

use crate::pils::{both, claim, commit, prepare};
use crate::{Failure, failure};

/// Latency histogram bins.
const LATENCY_BINS: usize = 40;

/// The figures of one simulator session: `error_3d.svg` (3-D position error versus
/// time, PILS and the offline references) and `latency.svg` (solution latency).
///
/// # Errors
/// [`Failure::Run`] when a figure cannot be drawn or written.
pub(crate) fn session_figures(series: &SimSeries, dir: &Path) -> Result<(), Failure> {
    let mut plot = LinePlot::new("3-D position error", "time (s)", "3-D error (m)");
    for (name, pts) in &series.error_3d {
        if !pts.is_empty() {
            plot.series.push(Series::new(*name, pts.clone()));
        }
    }
    if !plot.series.is_empty() {
        plot.write_svg(dir.join("error_3d.svg")).map_err(failure)?;
    }
    let ms: Vec<f64> = series
        .latencies_s
        .iter()
        .map(|s| s * 1e3)
        .filter(|v| v.is_finite())
        .collect();
    latency_histogram(&ms, "solution latency", &dir.join("latency.svg"))
}

/// The histogram of the latencies `ms` into `path` (nothing for none).
fn latency_histogram(ms: &[f64], title: &str, path: &Path) -> Result<(), Failure> {
    if ms.is_empty() {
        return Ok(());
    }
    let counts = fathom_stats::Histogram::new(ms, LATENCY_BINS).map_err(failure)?;
    Histogram::new(
        format!("{title} ({} solutions)", ms.len()),
        "latency (ms)",
        "count",
        counts.edges,
        counts.counts.iter().map(|&c| c as f64).collect(),
    )
    .write_svg(path)
    .map_err(failure)
}

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
    let dir = claim(out, force)?;
    let result = study(s, runs, dir.dir(), &mut first);
    commit(dir, scenario, s, Some(runs), t0)?;
    let c = result?;
    Ok(c.markdown(&title(s)) + &format!("\noutputs in {}\n", out.display()))
}

fn title(s: &Settings) -> String {
    let f = &s.file.link.faults;
    format!(
        "PILS {}: realtime (loss {:.0} %, latency {:.0} +- {:.0} ms) vs lockstep",
        s.method.name(),
        100.0 * f.loss,
        1e3 * f.latency_s,
        1e3 * f.jitter_s
    )
}

/// The sessions and the outputs of the study (into `dir`).
fn study(
    s: &Settings,
    runs: usize,
    dir: &Path,
    first: &mut Option<Prepared>,
) -> Result<Comparison, Failure> {
    let mut pairs = Vec::with_capacity(runs);
    let mut example: Vec<(&'static str, Vec<(f64, f64)>)> = Vec::new();
    let mut latencies_ms = Vec::new();
    for i in 0..runs as u64 {
        let run = s.file.run + i;
        let mut file = s.file.clone();
        file.run = run;
        let base = file
            .clone()
            .check()
            .map_err(|e| Failure::Usage(anyhow!("{e}")))?;
        let p = match first.take() {
            Some(p) => p,
            None => Prepared::new(&base).map_err(|e| Failure::Run(anyhow!("run {run}: {e}")))?,
        };
        let mut reports = Vec::with_capacity(2);
        for (label, pacing) in [
            ("lockstep", Pacing::Lockstep),
            ("realtime", Pacing::Realtime),
        ] {
            let mut f = file.clone();
            f.link.pacing = pacing;
            if pacing == Pacing::Lockstep {
                f.link.faults = FaultParams::NONE;
            }
            let sdir = dir.join(format!("run{run:03}_{label}"));
            std::fs::create_dir_all(&sdir)
                .with_context(|| format!("creating {}", sdir.display()))
                .map_err(Failure::Run)?;
            let path = sdir.join("scenario.toml");
            let text = toml::to_string(&f)
                .context("settings as TOML")
                .map_err(Failure::Run)?;
            std::fs::write(&path, text)
                .with_context(|| format!("writing {}", path.display()))
                .map_err(Failure::Run)?;
            let settings = f.check().map_err(|e| Failure::Usage(anyhow!("{e}")))?;
            let (r, _) = both(&path, &settings, &p, &sdir);
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
    let c = Comparison::new(pairs).map_err(|e| Failure::Run(anyhow!("{e}")))?;
    write_study(s, &c, dir, example, &latencies_ms)?;
    Ok(c)
}

fn write(dir: &Path, name: &str, text: &str) -> Result<(), Failure> {
    let p = dir.join(name);
    std::fs::write(&p, text)
        .with_context(|| format!("writing {}", p.display()))
        .map_err(Failure::Run)
}

fn write_study(
    s: &Settings,
    c: &Comparison,
    dir: &Path,
    example: Vec<(&'static str, Vec<(f64, f64)>)>,
    latencies_ms: &[f64],
) -> Result<(), Failure> {
    write(dir, "runs.csv", &c.runs_csv())?;
    write(dir, "report.md", &c.markdown(&title(s)))?;
    write(
        dir,
        "comparison.json",
        &serde_json::to_string_pretty(c)
            .context("JSON")
            .map_err(Failure::Run)?,
    )?;
    let mut summary = Summary::new(
        "pils",
        "004_a46751abbc309235.txt",
        c.runs.len(),
        s.file.seed,
    );
    let m = s.method.name();
    for mc in &c.metrics {
        for (label, v) in [
            ("lockstep", &mc.lockstep),
            ("realtime", &mc.realtime),
            ("realtime-lockstep", &mc.difference),
        ] {
            let [lo, hi] = v.bounds();
            summary.push_row(Row::new(format!("{label}/{m}"), mc.metric, v.mean).with_ci95(lo, hi));
        }
    }
    write(
        dir,
        "summary.json",
        &summary.to_json_pretty().map_err(failure)?,
    )?;
    // Per-run errors of both pacings.
    for metric in ["rmse_3d", "rmse_h", "rmse_yaw"] {
        let mut plot = LinePlot::new(
            format!("{metric} per run"),
            "run",
            format!("{metric} ({})", unit(metric)),
        );
        for label in ["lockstep", "realtime"] {
            let pts = c
                .runs
                .iter()
                .map(|r| {
                    let st = if label == "lockstep" {
                        &r.lockstep
                    } else {
                        &r.realtime
                    };
                    let v = st
                        .metrics()
                        .iter()
                        .find(|(n, _)| *n == metric)
                        .map_or(f64::NAN, |x| x.1);
                    (r.run as f64, v)
                })
                .collect();
            plot.series.push(Series::new(label, pts));
        }
        plot.write_svg(dir.join(format!("{metric}_per_run.svg")))
            .map_err(failure)?;
    }
    let mut plot = LinePlot::new(
        format!("3-D position error, run {}", c.runs[0].run),
        "time (s)",
        "3-D error (m)",
    );
    for (label, pts) in example {
        plot.series.push(Series::new(label, pts));
    }
    if !plot.series.is_empty() {
        plot.write_svg(dir.join("error_3d_lockstep_vs_realtime.svg"))
            .map_err(failure)?;
    }
    latency_histogram(
        latencies_ms,
        "realtime solution latency, all runs",
        &dir.join("latency_realtime.svg"),
    )
}
