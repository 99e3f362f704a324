//! Campaign commands: `fathom run --shard`, `fathom merge` and `fathom campaign slurm`.

use std::path::PathBuf;

use anyhow::{Context, anyhow};
use clap::{Args, Subcommand};
use fathom_experiments::registry;
use fathom_sim::cost;
use fathom_sim::driver::campaign::{merge, read_manifest, run_assessed_shard, slurm_script};
use fathom_sim::error_chain;
use fathom_sim::experiment::{Assessed, DynExperiment, Environment, Job, Shard};
use fathom_sim::user_run::{assess_scenario, check_command, one_line};

use crate::{Failure, RunArgs, failure, progress_bar, run_hook};

#[derive(Debug, Args)]
pub(crate) struct MergeArgs {
    /// Shard folders (each with `manifest.json`), in any order.
    #[arg(required = true)]
    pub(crate) dirs: Vec<PathBuf>,
    /// Output folder, replaced only once the merge is complete (default
    /// `fathom-out/<experiment>`, where a single run writes).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Worker threads of the analysis (results do not depend on it).
    #[arg(long, value_name = "T")]
    pub(crate) threads: Option<usize>,
    /// Write into a folder holding files fathom did not write (they are kept; only
    /// fathom's own files are replaced).
    #[arg(long)]
    pub(crate) force: bool,
}

#[derive(Debug, Subcommand)]
pub(crate) enum CampaignKind {
    /// A Slurm job array of shards and a merge job that depends on it.
    Slurm(SlurmArgs),
}

#[derive(Debug, Args)]
pub(crate) struct SlurmArgs {
    /// Scenario file.
    pub(crate) scenario: PathBuf,
    /// Monte Carlo runs of the campaign.
    #[arg(long, value_name = "N")]
    pub(crate) runs: usize,
    /// Number of shards (array tasks).
    #[arg(long, value_name = "M")]
    pub(crate) shards: usize,
    /// Campaign folder: the script, the shards' folders, logs and the merged outputs.
    #[arg(long, value_name = "DIR", default_value = "campaign")]
    pub(crate) dir: PathBuf,
}

pub(crate) fn run_shard_cmd(args: &RunArgs, shard: Shard) -> Result<String, Failure> {
    let registry = registry();
    let label = args.scenario.display().to_string();
    let text = std::fs::read_to_string(&args.scenario)
        .with_context(|| format!("cannot read `{label}`"))
        .map_err(Failure::Usage)?;
    let bar = progress_bar();
    let job = Job {
        text: &text,
        file: &label,
        runs: args.runs,
        seed: args.seed,
        threads: args.threads,
        progress: Some(run_hook(bar.clone(), true)),
        env: Environment {
            limits: args.limits.limits()?,
            // A shard's run 0 keeps what the merged page draws, unless --no-scene.
            scene_page: !args.no_scene,
            ..Environment::new(crate::current_dir()?)
        },
    };
    let (exp, assessed) = assess_scenario(&job, &registry).map_err(failure)?;
    // The estimate before anything runs: this shard's part of the scenario's cost.
    let main_runs = assessed.resolved.runs.unwrap_or(1).max(1);
    let part = shard.range(main_runs).len() as f64 / main_runs as f64;
    crate::say(&format!(
        "{} shard {}/{}: runs {:?} of {main_runs} in the main batch (the same share of \
         every batch); estimate for this shard: about {} on {} thread{}\n",
        exp.name(),
        shard.index,
        shard.count,
        shard.range(main_runs),
        cost::duration(assessed.cost.seconds() * part),
        assessed.cost.threads,
        if assessed.cost.threads == 1 { "" } else { "s" },
    ));
    let out = args.out.clone().unwrap_or_else(|| {
        crate::default_out(&format!(
            "{}-shard-{}-of-{}",
            exp.name(),
            shard.index,
            shard.count
        ))
    });
    let outcome = run_assessed_shard(exp, assessed, &job, shard, &out, args.force);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let m = outcome.map_err(failure)?;
    let mut text = format!(
        "{} shard {}/{}: {:.1} s, manifest {}\n",
        m.experiment,
        shard.index,
        shard.count,
        m.elapsed_s,
        out.join("manifest.json").display()
    );
    for b in &m.batches {
        text.push_str(&format!(
            "  {}: runs {}..{} of {}\n",
            b.label, b.first, b.end, b.runs
        ));
    }
    Ok(text)
}

pub(crate) fn merge_cmd(args: &MergeArgs) -> Result<String, Failure> {
    let base_dir = crate::current_dir()?;
    let out = match &args.out {
        Some(out) => out.clone(),
        None => {
            let first = args
                .dirs
                .first()
                .ok_or_else(|| Failure::Usage(anyhow!("fathom merge: give the shard folders")))?;
            crate::default_out(&read_manifest(first).map_err(failure)?.experiment)
        }
    };
    let (result, m) = merge(
        &registry(),
        &args.dirs,
        args.threads,
        &base_dir,
        &out,
        args.force,
    )
    .map_err(failure)?;
    Ok(format!(
        "merged {} shard folders of `{}` ({} runs): {} ({} figures, report.md, summary.json)\n",
        args.dirs.len(),
        m.experiment,
        result.summary.runs,
        result.out_dir.display(),
        result.figures.len()
    ))
}

pub(crate) fn campaign_cmd(kind: &CampaignKind) -> Result<String, Failure> {
    let CampaignKind::Slurm(args) = kind;
    if args.shards == 0 || args.runs == 0 {
        return Err(Failure::Usage(anyhow!(
            "--runs and --shards must be at least 1"
        )));
    }
    if args.runs < args.shards {
        return Err(Failure::Usage(anyhow!(
            "--runs {} is fewer than --shards {}: every shard needs at least one run",
            args.runs,
            args.shards
        )));
    }
    // The scenario must be valid before anything is submitted.
    let (code, line) = check_command(&args.scenario, &registry());
    if code != 0 {
        return Err(Failure::Usage(anyhow!(line)));
    }
    // ... and valid with the campaign's run count, as every shard will assess it.
    let text = std::fs::read_to_string(&args.scenario)
        .with_context(|| format!("cannot read `{}`", args.scenario.display()))
        .map_err(Failure::Usage)?;
    let label = args.scenario.display().to_string();
    let job = Job {
        text: &text,
        file: &label,
        runs: Some(args.runs),
        seed: None,
        threads: None,
        progress: None,
        env: Environment::new(crate::current_dir()?),
    };
    let registry = registry();
    let (exp, assessed) = assess_scenario(&job, &registry).map_err(|e| {
        let line = one_line(&error_chain(&e));
        Failure::Usage(if line.contains("--runs") {
            anyhow!(line)
        } else {
            anyhow!("with --runs {}: {line}", args.runs)
        })
    })?;
    let estimate = campaign_estimate(exp, assessed, &job, args)?;
    let dir = args.dir.display().to_string();
    let script = slurm_script(
        &args.scenario.display().to_string(),
        args.runs,
        args.shards,
        &dir,
    );
    std::fs::create_dir_all(&args.dir)
        .with_context(|| format!("cannot create `{dir}`"))
        .map_err(Failure::Usage)?;
    let path = args.dir.join("campaign.sh");
    std::fs::write(&path, script)
        .with_context(|| format!("cannot write `{}`", path.display()))
        .map_err(Failure::Usage)?;
    Ok(format!(
        "wrote {}: {} shards of {} runs and a dependent merge; submit with `bash {}`\n{estimate}",
        path.display(),
        args.shards,
        args.runs,
        path.display()
    ))
}

/// Runs in the sample shard that measures a campaign's time and disk per run.
const SAMPLE_RUNS: usize = 2;

/// The time and disk estimate of a campaign: the cost model's CPU time, and time and
/// disk per run measured on a small shard of the campaign itself (the first
/// `SAMPLE_RUNS` runs of every batch, written into a temporary folder and removed).
fn campaign_estimate(
    exp: &dyn DynExperiment,
    assessed: Assessed<'_>,
    job: &Job<'_>,
    args: &SlurmArgs,
) -> Result<String, Failure> {
    let threads = assessed.cost.threads;
    let model_cpu_s = assessed.cost.seconds() * threads as f64;
    let sample = Shard {
        index: 0,
        count: (args.runs / SAMPLE_RUNS).max(1),
    };
    let sample_runs = sample.range(args.runs).len().max(1);
    let dir = std::env::temp_dir().join(format!("fathom-campaign-sample-{}", std::process::id()));
    let measured = run_assessed_shard(exp, assessed, job, sample, &dir, false);
    let records_bytes = records_size(&dir);
    let manifest_bytes = std::fs::metadata(dir.join("manifest.json")).map_or(0, |m| m.len());
    let _ = std::fs::remove_dir_all(&dir);
    let m = measured.map_err(failure)?;
    let per_run_s = m.elapsed_s / sample_runs as f64;
    let per_run_bytes = records_bytes as f64 / sample_runs as f64;
    let runs = args.runs as f64;
    let disk = per_run_bytes * runs + manifest_bytes as f64 * args.shards as f64;
    Ok(format!(
        "estimate (a sample shard of {sample_runs} run{} measured here on {threads} thread{}): \
         {:.2} s per run, so about {} per shard and {} in all on such a node (cost model: \
         {} of CPU time); disk: {} per run, about {} for the shards' records, plus the \
         merged outputs (a single run's file set)\n",
        if sample_runs == 1 { "" } else { "s" },
        if threads == 1 { "" } else { "s" },
        per_run_s,
        cost::duration(per_run_s * runs / args.shards as f64),
        cost::duration(per_run_s * runs),
        cost::duration(model_cpu_s),
        cost::bytes(per_run_bytes),
        cost::bytes(disk),
    ))
}

/// Bytes of the files in a shard folder apart from its manifest.
fn records_size(dir: &std::path::Path) -> u64 {
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.file_name() != "manifest.json")
        .filter_map(|e| e.metadata().ok())
        .filter(|m| m.is_file())
        .map(|m| m.len())
        .sum()
}
