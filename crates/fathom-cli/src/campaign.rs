//! Campaign commands: `fathom run --shard`, `fathom merge` and `fathom campaign slurm`.

use std::path::PathBuf;

use anyhow::{Context, anyhow};
use clap::{Args, Subcommand};
use fathom_experiments::registry;
use fathom_sim::driver::campaign::{merge, read_manifest, run_assessed_shard, slurm_script};
use fathom_sim::error_chain;
use fathom_sim::experiment::{Environment, Job, Shard};
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
        progress: Some(run_hook(bar.clone())),
        env: Environment {
            limits: args.limits.limits()?,
            ..Environment::new(crate::current_dir()?)
        },
    };
    let (exp, assessed) = assess_scenario(&job, &registry).map_err(failure)?;
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
    if let Err(e) = assess_scenario(&job, &registry()) {
        let line = one_line(&error_chain(&e));
        return Err(Failure::Usage(if line.contains("--runs") {
            anyhow!(line)
        } else {
            anyhow!("with --runs {}: {line}", args.runs)
        }));
    }
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
        "wrote {}: {} shards of {} runs and a dependent merge; submit with `bash {}`\n",
        path.display(),
        args.shards,
        args.runs,
        path.display()
    ))
}
