//! The `fusion` analysis: per-method metrics over runs (Tables 2 and 3), the EFF
//! feedback's effect on the INS integrator, the sensitivity sweeps, the claims with
//! paired CIs. The figures and the report are drawn afterwards from [`Analysed`].

use fathom_stats::{mean_and_ci95, paired_mean_ci};
use rand_chacha::ChaCha8Rng;

use super::Prepared;
use super::scenario::FusionSetup;
use super::sim::{self, Method, MethodMetrics, Reading, RunConfig, RunOutput, method_metrics};
use fathom_report::output::Claim;
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;
use fathom_traj::FusionMission;

/// Table 2 (3D) and Table 3 (2D): `(mean_3d, std_3d, mean_2d, std_2d)`.
pub(super) fn paper_values(m: Method) -> Option<[f64; 4]> {
    match m {
        Method::Mf => Some([3.67, 1.01, 3.57, 1.23]),
        Method::T2t => Some([1.83, 1.53, 2.70, 1.48]),
        Method::Eff => Some([1.38, 0.32, 1.07, 0.29]),
        _ => None,
    }
}

/// The metrics of `summary.json` (per method).
pub const METRICS: [&str; 5] = ["mean_3d", "std_3d", "mean_2d", "std_2d", "turn_ratio_3d"];

fn metric_of(m: &MethodMetrics, name: &str) -> f64 {
    match name {
        "mean_3d" => m.mean_3d,
        "std_3d" => m.std_3d,
        "mean_2d" => m.mean_2d,
        "std_2d" => m.std_2d,
        "turn_ratio_3d" => m.turn_ratio_3d,
        "max_3d" => m.max_3d,
        _ => m.final_3d,
    }
}

/// One run's metrics per method (index of [`Method::ALL`]) and its error series.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct RunResult {
    /// Per-method metrics (`None` for methods not computed).
    pub metrics: Vec<Option<MethodMetrics>>,
    /// The run's error series.
    pub output: RunOutput,
}

/// Simulates one run and computes the metrics of `methods`.
///
/// # Errors
/// As [`sim::simulate_run`] and [`sim::method_metrics`].
pub fn run_once(
    setup: &FusionSetup,
    cfg: &RunConfig,
    mission: &FusionMission,
    methods: &[Method],
    keep_paths: bool,
    rng: &mut ChaCha8Rng,
) -> Result<RunResult, SimError> {
    let output = sim::simulate_run(cfg, mission.trajectory(), methods, keep_paths, rng)?;
    let mut metrics = vec![None; Method::ALL.len()];
    for &m in methods {
        let i = m.index();
        metrics[i] = Some(method_metrics(
            &output.times,
            &output.err_3d[i],
            &output.err_2d[i],
            mission.course_changes(),
            setup.turn_half_window,
        )?);
    }
    Ok(RunResult { metrics, output })
}

/// Values of `metric` of `method` over runs.
pub fn values(results: &[RunResult], method: Method, metric: &str) -> Vec<f64> {
    results
        .iter()
        .filter_map(|r| r.metrics[method.index()].as_ref())
        .map(|m| metric_of(m, metric))
        .collect()
}

/// Paired difference `a - b` of a metric over runs: mean and 95 % CI.
pub(super) fn paired(
    results: &[RunResult],
    a: Method,
    b: Method,
    metric: &str,
) -> Result<(f64, [f64; 2]), SimError> {
    let d = paired_mean_ci(&values(results, a, metric), &values(results, b, metric))?;
    Ok((d.mean, d.bounds()))
}

/// Methods computed in the sensitivity sweep (the paper's three, the ablations and
/// the DVL reference; the extra fusion rules are left out to keep the run short).
pub(super) const SWEEP_METHODS: [Method; 6] = [
    Method::Mf,
    Method::T2t,
    Method::Eff,
    Method::EffNoFeedback,
    Method::EffNoEqualization,
    Method::DvlDr,
];

/// One sweep: per value, per method, mean 3D error and its CI.
pub(super) struct SweepResult {
    /// The tuning reading of the sweep's runs.
    pub(super) reading: Reading,
    pub(super) key: &'static str,
    pub(super) label: &'static str,
    pub(super) values: Vec<f64>,
    /// `[value][method in SWEEP_METHODS] -> (mean, ci)`.
    pub(super) means: Vec<Vec<(f64, [f64; 2])>>,
}

fn values_of_mean(results: &[RunResult], m: Method) -> Vec<f64> {
    values(results, m, "mean_3d")
}

/// The two sensitivity sweeps: the scenario key and the axis label of each.
pub(super) const SWEEPS: [(&str, &str); 2] = [
    ("dvl_vel_noise_mps", "DVL velocity noise std (m/s)"),
    ("filter_v_dvl", "filters' v_DVL"),
];

/// The sweep results from the sweep batches' records (one batch per sweep point, in
/// the order of [`Prepared::sweep_points`]): per reading, the sweeps of `SWEEPS`.
fn sweep_results(p: &Prepared, records: &[Vec<RunResult>]) -> Result<Vec<SweepResult>, SimError> {
    let readings = [p.setup.run.tuning.reading, p.other.tuning.reading];
    let mut out: Vec<SweepResult> = readings
        .iter()
        .flat_map(|&reading| {
            SWEEPS.iter().map(move |&(key, label)| SweepResult {
                reading,
                key,
                label,
                values: Vec::new(),
                means: Vec::new(),
            })
        })
        .collect();
    for (point, results) in p.sweep_points.iter().zip(records) {
        let row = SWEEP_METHODS
            .iter()
            .map(|&m| mean_and_ci95(&values_of_mean(results, m)))
            .collect::<Result<Vec<_>, _>>()?;
        let sw = &mut out[point.reading * SWEEPS.len() + point.sweep];
        sw.values.push(point.value);
        sw.means.push(row);
    }
    Ok(out)
}

/// One reading's main batch and sweeps, for the report.
pub(super) struct ReadingRuns<'a> {
    /// The reading.
    pub(super) reading: Reading,
    /// Its run configuration.
    pub(super) cfg: &'a RunConfig,
    /// Its main batch.
    pub(super) results: &'a [RunResult],
    /// Its sweeps.
    pub(super) sweeps: Vec<&'a SweepResult>,
}

/// The method name of a summary row under `reading`: the contract name for the
/// scenario's reading, `NAME [reading]` for the other one.
pub(super) fn row_method(m: Method, reading: Reading, primary: Reading) -> String {
    if reading == primary {
        m.name().to_string()
    } else {
        format!("{} [{}]", m.name(), reading.name())
    }
}

/// The unit of each metric of the rows.
pub(super) const UNITS: [(&str, &str); 7] = [
    ("mean_3d", "m"),
    ("std_3d", "m"),
    ("mean_2d", "m"),
    ("std_2d", "m"),
    ("turn_ratio_3d", "1"),
    ("ins_integrator_mean_err", "m"),
    ("ins_integrator_max_err", "m"),
];

/// What the figures and the report are drawn from: the main batch of both readings
/// (run 0 of the main batch is the detail run: it keeps its paths) and the sweeps.
pub(super) struct Analysed {
    /// The scenario's reading's main batch.
    pub(super) results: Vec<RunResult>,
    /// The other reading's main batch.
    pub(super) other: Vec<RunResult>,
    /// Every sweep of both readings.
    pub(super) sweeps: Vec<SweepResult>,
}

impl Analysed {
    /// Both readings' runs and sweeps, the scenario's reading first.
    pub(super) fn readings<'a>(&'a self, p: &'a Prepared) -> [ReadingRuns<'a>; 2] {
        let primary = p.setup.run.tuning.reading;
        [
            ReadingRuns {
                reading: primary,
                cfg: &p.setup.run,
                results: &self.results,
                sweeps: self
                    .sweeps
                    .iter()
                    .filter(|s| s.reading == primary)
                    .collect(),
            },
            ReadingRuns {
                reading: p.other.tuning.reading,
                cfg: &p.other,
                results: &self.other,
                sweeps: self
                    .sweeps
                    .iter()
                    .filter(|s| s.reading != primary)
                    .collect(),
            },
        ]
    }
}

/// The sweeps as JSON (`summary.json` extra key `sensitivity`): per reading, per
/// sweep, the values and each method's mean 3D error.
fn sweeps_json(sweeps: &[&SweepResult]) -> serde_json::Value {
    let mut out = serde_json::Map::new();
    for s in sweeps {
        let mut per_method = serde_json::Map::new();
        for (j, m) in SWEEP_METHODS.iter().enumerate() {
            let means: Vec<f64> = s.means.iter().map(|row| row[j].0).collect();
            per_method.insert(m.name().into(), serde_json::json!(means));
        }
        let entry = out
            .entry(s.reading.name())
            .or_insert_with(|| serde_json::json!({}));
        if let Some(obj) = entry.as_object_mut() {
            obj.insert(
                s.key.into(),
                serde_json::json!({"values": s.values, "mean_3d": per_method}),
            );
        }
    }
    serde_json::Value::Object(out)
}

/// Computes the rows, the claims and the extra keys.
pub(super) fn analyse(
    p: &Prepared,
    mut records: Vec<Vec<RunResult>>,
    out: &mut Analysis,
) -> Result<Analysed, SimError> {
    let (setup, mission) = (&p.setup, &p.mission);
    let sweeps = sweep_results(p, &records[super::FIRST_SWEEP..])?;
    let other = std::mem::take(&mut records[super::OTHER]);
    let results = std::mem::take(&mut records[0]);
    let primary = setup.run.tuning.reading;
    for (metric, unit) in UNITS {
        out.unit(metric, unit);
    }
    for (reading, runs) in [(primary, &results), (p.other.tuning.reading, &other)] {
        for m in Method::ALL {
            let paper = paper_values(m);
            for (k, metric) in METRICS.iter().enumerate() {
                out.runs_row(
                    &row_method(m, reading, primary),
                    metric,
                    &values(runs, m, metric),
                )?
                .paper = paper.and_then(|p| p.get(k).copied());
            }
        }
    }
    // The INS integrator under EFF feedback (what the acceptance test bounds).
    let ins_fb_mean: Vec<f64> = results
        .iter()
        .map(|r| {
            let s = &r.output.ins_err_with_feedback;
            s.iter().sum::<f64>() / s.len().max(1) as f64
        })
        .collect();
    let ins_fb_max: Vec<f64> = results
        .iter()
        .map(|r| {
            r.output
                .ins_err_with_feedback
                .iter()
                .copied()
                .fold(0.0, f64::max)
        })
        .collect();
    out.runs_row("EFF", "ins_integrator_mean_err", &ins_fb_mean)?;
    out.runs_row("EFF", "ins_integrator_max_err", &ins_fb_max)?;

    for c in claims(setup, &results)? {
        out.claim(c);
    }
    out.extra(
        "course_changes_s",
        serde_json::json!(mission.course_changes()),
    );
    let sweep_refs: Vec<&SweepResult> = sweeps.iter().collect();
    out.extra("sensitivity", sweeps_json(&sweep_refs));
    out.extra("primary_reading", serde_json::json!(primary.name()));
    Ok(Analysed {
        results,
        other,
        sweeps,
    })
}

/// Whether `a` beats every method in `others` on `metric` (paired 95 % CI of the
/// difference entirely below zero), with the numbers.
fn beats_all(
    setup: &FusionSetup,
    results: &[RunResult],
    a: Method,
    others: &[Method],
    metric: &str,
) -> Result<(bool, String), SimError> {
    let mut holds = true;
    let mut parts = vec![format!(
        "{} {:.4}",
        a.name(),
        mean_and_ci95(&values(results, a, metric))?.0
    )];
    for &b in others {
        let (mb, _) = mean_and_ci95(&values(results, b, metric))?;
        let (d, [lo, hi]) = paired(results, a, b, metric)?;
        holds &= hi < -setup.min_relative_improvement * mb;
        parts.push(format!(
            "{} {:.4} ({} - {} = {:+.2e} m, paired 95 % CI [{:+.2e}, {:+.2e}])",
            b.name(),
            mb,
            a.name(),
            b.name(),
            d,
            lo,
            hi
        ));
    }
    Ok((holds, parts.join("; ")))
}

fn with_threshold(setup: &FusionSetup, detail: String) -> String {
    format!(
        "{detail}; holds when every paired CI lies below -{} x the competitor's value",
        setup.min_relative_improvement
    )
}

pub(super) fn claims(setup: &FusionSetup, results: &[RunResult]) -> Result<Vec<Claim>, SimError> {
    let others = [Method::Mf, Method::T2t];
    let mut out = Vec::new();
    for (id, metric, text) in [
        (
            "eff_best_3d_mean",
            "mean_3d",
            "EFF has the lowest 3D mean distance error (Table 2)",
        ),
        (
            "eff_best_3d_std",
            "std_3d",
            "EFF has the lowest 3D error std (Table 2)",
        ),
        (
            "eff_best_2d_mean",
            "mean_2d",
            "EFF has the lowest 2D mean distance error (Table 3)",
        ),
        (
            "eff_best_2d_std",
            "std_2d",
            "EFF has the lowest 2D error std (Table 3)",
        ),
    ] {
        let (holds, detail) = beats_all(setup, results, Method::Eff, &others, metric)?;
        out.push(Claim::new(id, text, holds, with_threshold(setup, detail)));
    }
    let (holds, detail) = beats_all(setup, results, Method::T2t, &[Method::Mf], "mean_3d")?;
    out.push(Claim::new(
        "t2t_beats_mf_3d_mean",
        "T2T has a lower 3D mean distance error than MF (Table 2)",
        holds,
        with_threshold(setup, detail),
    ));
    let lim = setup.turn_ratio_limit;
    let ratio = |m: Method| mean_and_ci95(&values(results, m, "turn_ratio_3d"));
    let (re, re_ci) = ratio(Method::Eff)?;
    let (rm, rm_ci) = ratio(Method::Mf)?;
    let (rt, rt_ci) = ratio(Method::T2t)?;
    let holds = re <= lim && rm > lim && rt > lim;
    out.push(Claim::new(
        "eff_robust_at_turns",
        format!(
            "EFF is robust at course changes (turn ratio <= {lim}) while MF and T2T spike (ratio > {lim})"
        ),
        holds,
        format!(
            "turn_ratio_3d (mean error within +/- {} s of a course change / elsewhere): EFF {:.3} [{:.3}, {:.3}], MF {:.3} [{:.3}, {:.3}], T2T {:.3} [{:.3}, {:.3}]",
            setup.turn_half_window, re, re_ci[0], re_ci[1], rm, rm_ci[0], rm_ci[1], rt, rt_ci[0], rt_ci[1]
        ),
    ));
    Ok(out)
}
