//! Campaigns beyond one machine: a shard runs the run indices `K` of `M` of every batch
//! and writes the runs' records and a manifest; `merge` checks that the manifests of a
//! set of shards agree and cover every run once, reads the records back in run order
//! and writes the same outputs as a single-process run.
//!
//! A shard's folder holds `manifest.json` and one record file per batch,
//! `records-<batch>.jsonl` (one line per run: the run index, a tab, the record as
//! JSON). Run `i` of a batch draws from its own stream `run_rng(base_seed, i)`, so its
//! record does not depend on the shard layout, and the merged analysis folds the
//! records in run order: the outputs are byte-identical to one process running all
//! runs.

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::{ExperimentResult, OutDir, RunInfo, write_executed};
use crate::SimError;
use crate::experiment::{
    Assessed, Batch, DynExperiment, FoundRecord, Job, RecordSink, RecordSource, Shard,
    differing_keys,
};
use fathom_core::echo::{echo, echo_path};
use fathom_report::output::write_text;

/// Version of the shard folder layout (2: the manifest holds the scenario as given).
pub const FORMAT: u32 = 2;

/// One batch of a shard: its label, its size, and the run indices the shard ran.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardBatch {
    /// The batch label.
    pub label: String,
    /// Runs of the whole batch.
    pub runs: usize,
    /// First run index of this shard.
    pub first: usize,
    /// One past the last run index of this shard.
    pub end: usize,
}

/// `manifest.json` of a shard.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// [`FORMAT`].
    pub format: u32,
    /// fathom version that ran the shard.
    pub fathom_version: String,
    /// The experiment.
    pub experiment: String,
    /// The scenario as given on the command line (labels the report).
    pub scenario_label: String,
    /// SHA-256 of `resolved_scenario`.
    pub scenario_sha256: String,
    /// The resolved scenario (runs and seed folded in): what every shard must share.
    pub resolved_scenario: String,
    /// The scenario file as given, written by the merge as `scenario.toml` (what a
    /// single run writes). Absent from older manifests, which [`FORMAT`] refuses.
    #[serde(default)]
    pub scenario_text: String,
    /// The base seed (`None`: a deterministic experiment).
    pub base_seed: Option<u64>,
    /// This shard.
    pub shard: Shard,
    /// Per batch, the run indices this shard ran.
    pub batches: Vec<ShardBatch>,
    /// Wall-clock time of the shard, s.
    pub elapsed_s: f64,
}

fn sha256_hex(text: &str) -> String {
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// "the scenario differs from `<first>`'s in `a.b`, `c`" (the keys, not the hashes):
/// the resolved scenarios of two shards compared key by key.
fn scenario_mismatch(m: &Manifest, first: &Manifest, first_dir: &Path) -> String {
    let parse = |t: &str| t.parse::<toml::Table>().ok();
    let keys = match (parse(&m.resolved_scenario), parse(&first.resolved_scenario)) {
        (Some(a), Some(b)) => differing_keys(&a, &b),
        _ => Vec::new(),
    };
    let what = if keys.is_empty() {
        "its text (no key differs: comments or layout)".to_string()
    } else {
        let shown: Vec<String> = keys
            .iter()
            .take(10)
            .map(|k| format!("`{}`", echo(k)))
            .collect();
        let more = keys.len().saturating_sub(shown.len());
        let more = if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        };
        format!("{}{more}", shown.join(", "))
    };
    format!(
        "its resolved scenario differs from that of `{}` in {what}: the shards must run \
         the same scenario (with the same --runs and --seed)",
        echo_path(first_dir)
    )
}

fn records_file(dir: &Path, batch: usize) -> PathBuf {
    dir.join(format!("records-{batch}.jsonl"))
}

/// Writes each batch's records into its own file.
struct FileSink {
    dir: PathBuf,
    current: Option<(usize, BufWriter<File>)>,
    batches: Vec<ShardBatch>,
}

impl FileSink {
    fn flush(&mut self) -> Result<(), SimError> {
        if let Some((b, mut w)) = self.current.take() {
            let path = records_file(&self.dir, b);
            w.flush().map_err(|e| SimError::io("write", &path, e))?;
        }
        Ok(())
    }
}

impl RecordSink for FileSink {
    fn begin_batch(
        &mut self,
        batch: usize,
        info: &Batch,
        range: Range<usize>,
    ) -> Result<(), SimError> {
        self.flush()?;
        let path = records_file(&self.dir, batch);
        let file = File::create(&path).map_err(|e| SimError::io("create", &path, e))?;
        self.current = Some((batch, BufWriter::new(file)));
        self.batches.push(ShardBatch {
            label: info.label.clone(),
            runs: info.runs,
            first: range.start,
            end: range.end,
        });
        Ok(())
    }

    fn record(&mut self, batch: usize, index: usize, json: &str) -> Result<(), SimError> {
        let path = records_file(&self.dir, batch);
        match &mut self.current {
            Some((b, w)) if *b == batch => {
                writeln!(w, "{index}\t{json}").map_err(|e| SimError::io("write", &path, e))
            }
            _ => Err(SimError::invalid_argument(
                "shard records",
                format!("record of batch {batch} outside its batch"),
            )),
        }
    }
}

/// Runs shard `shard` of `exp` on `job` into the folder `dir`: the record files and
/// `manifest.json`, written like every output folder ([`fathom_report::outdir`]: a folder
/// holding files fathom did not write is refused unless `force`, and an earlier
/// shard's folder is replaced only once the new records are complete).
///
/// # Errors
/// A bad shard, the scenario's errors, a refused folder, the experiment's errors, I/O
/// errors.
pub fn run_shard(
    exp: &dyn DynExperiment,
    job: &Job<'_>,
    shard: Shard,
    dir: &Path,
    force: bool,
) -> Result<Manifest, SimError> {
    check_shard(shard)?;
    run_assessed_shard(exp, exp.assess(job)?, job, shard, dir, force)
}

/// `K/M` with `0 <= K < M`.
///
/// # Errors
/// [`SimError::InvalidArgument`] naming `--shard`.
pub fn check_shard(shard: Shard) -> Result<(), SimError> {
    if shard.count == 0 || shard.index >= shard.count {
        return Err(SimError::invalid_argument(
            "--shard",
            format!("K/M needs 0 <= K < M, got {}/{}", shard.index, shard.count),
        ));
    }
    Ok(())
}

/// [`run_shard`] of a job already assessed (the scenario is not parsed again).
///
/// # Errors
/// As [`run_shard`].
pub fn run_assessed_shard(
    exp: &dyn DynExperiment,
    assessed: Assessed<'_>,
    job: &Job<'_>,
    shard: Shard,
    dir: &Path,
    force: bool,
) -> Result<Manifest, SimError> {
    check_shard(shard)?;
    let claim = OutDir::claim(dir, force)?;
    let start = Instant::now();
    let mut sink = FileSink {
        dir: claim.dir().to_path_buf(),
        current: None,
        batches: Vec::new(),
    };
    let plan = assessed.execute_shard(shard, &mut sink)?;
    sink.flush()?;
    let manifest = Manifest {
        format: FORMAT,
        fathom_version: env!("CARGO_PKG_VERSION").to_string(),
        experiment: exp.name().to_string(),
        scenario_label: job.file.to_string(),
        scenario_sha256: sha256_hex(&plan.resolved.toml),
        resolved_scenario: plan.resolved.toml.clone(),
        scenario_text: job.text.to_string(),
        base_seed: plan.resolved.base_seed,
        shard,
        batches: sink.batches,
        elapsed_s: start.elapsed().as_secs_f64(),
    };
    let json = serde_json::to_string_pretty(&manifest).map_err(|e| SimError::Json {
        path: dir.join("manifest.json"),
        source: e,
    })?;
    write_text(claim.dir().join("manifest.json"), &(json + "\n"))?;
    claim.commit(RunInfo {
        fathom_version: manifest.fathom_version.clone(),
        command: "shard".into(),
        experiment: manifest.experiment.clone(),
        scenario: job.file.to_string(),
        runs: job.runs,
        threads: job.threads,
        seed: job.seed,
        base_seed: manifest.base_seed,
        elapsed_s: manifest.elapsed_s,
        files: Vec::new(),
    })?;
    Ok(manifest)
}

/// Reads a shard's manifest.
///
/// # Errors
/// I/O or JSON errors naming the file; a manifest that is not one (truncated, a
/// field missing or of the wrong type) is the user's file ([`SimError::Input`]).
pub fn read_manifest(dir: &Path) -> Result<Manifest, SimError> {
    let path = dir.join("manifest.json");
    let text = std::fs::read_to_string(&path).map_err(|e| SimError::io("read", &path, e))?;
    serde_json::from_str(&text)
        .map_err(|e| SimError::Input(Box::new(SimError::Json { path, source: e })))
}

/// The shards' manifests checked against each other: same experiment, scenario,
/// version, seed and batches, and every run of every batch in exactly one shard.
/// Returns, per batch, the shard folders in run order.
fn check_manifests(shards: &[(PathBuf, Manifest)]) -> Result<Vec<Vec<PathBuf>>, SimError> {
    let Some((first_dir, first)) = shards.first() else {
        return Err(SimError::invalid_argument(
            "merge",
            "no shard folders given",
        ));
    };
    let bad = |dir: &Path, what: String| {
        SimError::invalid_argument(format!("shard `{}`", echo_path(dir)), what)
    };
    for (dir, m) in shards {
        if m.format != FORMAT {
            return Err(bad(
                dir,
                format!("layout version {}, expected {FORMAT}", m.format),
            ));
        }
        // The records were made with the scenario the hash was taken of: an edited
        // `resolved_scenario` would analyse them under other settings.
        let actual = sha256_hex(&m.resolved_scenario);
        if actual != m.scenario_sha256 {
            return Err(bad(
                dir,
                format!(
                    "manifest.json: `scenario_sha256` {} is not the SHA-256 of its \
                     `resolved_scenario` ({actual}): the manifest was edited after the run",
                    echo(&m.scenario_sha256)
                ),
            ));
        }
        if m.experiment == first.experiment && m.scenario_sha256 != first.scenario_sha256 {
            return Err(bad(dir, scenario_mismatch(m, first, first_dir)));
        }
        for (field, a, b) in [
            ("experiment", &m.experiment, &first.experiment),
            ("fathom version", &m.fathom_version, &first.fathom_version),
        ] {
            if a != b {
                return Err(bad(
                    dir,
                    format!(
                        "{field} `{}` differs from `{}` of `{}`",
                        echo(a),
                        echo(b),
                        echo_path(first_dir)
                    ),
                ));
            }
        }
        if m.base_seed != first.base_seed {
            return Err(bad(dir, "base seed differs from the other shards'".into()));
        }
        let shape = |m: &Manifest| -> Vec<(String, usize)> {
            m.batches
                .iter()
                .map(|b| (b.label.clone(), b.runs))
                .collect()
        };
        if shape(m) != shape(first) {
            return Err(bad(dir, "batches differ from the other shards'".into()));
        }
    }
    let mut order = Vec::with_capacity(first.batches.len());
    for (b, batch) in first.batches.iter().enumerate() {
        let mut parts: Vec<(&PathBuf, &ShardBatch)> =
            shards.iter().map(|(d, m)| (d, &m.batches[b])).collect();
        parts.sort_by_key(|(_, p)| (p.first, p.end));
        let mut next = 0;
        let mut dirs = Vec::new();
        for (dir, p) in parts {
            if p.first == p.end {
                continue;
            }
            if p.first < next {
                return Err(bad(
                    dir,
                    format!(
                        "runs {}..{} of batch `{}` are also in another shard (duplicated shard?)",
                        p.first, p.end, batch.label
                    ),
                ));
            }
            if p.first > next {
                return Err(SimError::invalid_argument(
                    "merge",
                    format!(
                        "runs {next}..{} of batch `{}` are in no shard (missing shard?)",
                        p.first, batch.label
                    ),
                ));
            }
            next = p.end;
            dirs.push(dir.clone());
        }
        if next != batch.runs {
            return Err(SimError::invalid_argument(
                "merge",
                format!(
                    "runs {next}..{} of batch `{}` are in no shard (missing shard?)",
                    batch.runs, batch.label
                ),
            ));
        }
        order.push(dirs);
    }
    Ok(order)
}

/// `path` made absolute and with its symbolic links resolved as far as it exists
/// (an output folder may not exist yet).
fn resolved_path(path: &Path) -> PathBuf {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut existing = absolute.as_path();
    let mut rest = Vec::new();
    while let Some(parent) = existing.parent() {
        if let Ok(real) = existing.canonicalize() {
            return rest.iter().rev().fold(real, |p, name| p.join(name));
        }
        if let Some(name) = existing.file_name() {
            rest.push(name.to_owned());
        }
        existing = parent;
    }
    absolute
}

/// Refuses an output folder that is a shard folder, lies inside one or holds one: the
/// merge's output folder is replaced, and with it the shard's records.
fn check_out_apart(dirs: &[PathBuf], out_dir: &Path) -> Result<(), SimError> {
    let out = resolved_path(out_dir);
    for dir in dirs {
        let shard = resolved_path(dir);
        if out.starts_with(&shard) || shard.starts_with(&out) {
            return Err(SimError::invalid_argument(
                "--out",
                format!(
                    "`{}` {} the shard folder `{}`; write the merge elsewhere",
                    echo_path(out_dir),
                    if out == shard {
                        "is"
                    } else if out.starts_with(&shard) {
                        "is inside"
                    } else {
                        "holds"
                    },
                    echo_path(dir)
                ),
            ));
        }
    }
    Ok(())
}

/// Reads the record files of each batch from its shards, in run order.
struct FileSource {
    order: Vec<Vec<PathBuf>>,
    batch: usize,
    part: usize,
    reader: Option<(PathBuf, usize, std::io::Lines<BufReader<File>>)>,
}

impl RecordSource for FileSource {
    fn next(&mut self, batch: usize) -> Result<Option<FoundRecord>, SimError> {
        if batch != self.batch {
            self.batch = batch;
            self.part = 0;
            self.reader = None;
        }
        loop {
            if self.reader.is_none() {
                let Some(dir) = self.order.get(batch).and_then(|d| d.get(self.part)) else {
                    return Ok(None);
                };
                let path = records_file(dir, batch);
                let file = File::open(&path).map_err(|e| SimError::io("read", &path, e))?;
                self.reader = Some((path, 0, BufReader::new(file).lines()));
            }
            let Some((path, line_no, lines)) = &mut self.reader else {
                return Ok(None);
            };
            match lines.next() {
                None => {
                    self.reader = None;
                    self.part += 1;
                }
                Some(line) => {
                    *line_no += 1;
                    let line = line.map_err(|e| SimError::io("read", path.clone(), e))?;
                    let origin = format!("{}:{line_no}", path.display());
                    let (index, json) = line
                        .split_once('\t')
                        .and_then(|(i, j)| i.parse::<usize>().ok().map(|i| (i, j)))
                        .ok_or_else(|| {
                            SimError::invalid_argument(
                                format!("record file {origin}"),
                                "corrupted line (expected: run index, tab, JSON)",
                            )
                        })?;
                    return Ok(Some(FoundRecord {
                        index,
                        json: json.to_string(),
                        origin,
                    }));
                }
            }
        }
    }
}

/// Merges the shard folders `dirs` into the outputs of one run written to `out_dir`
/// (the same files as a single-process run: summary.json, report.md, figures, CSV),
/// written like every output folder ([`fathom_report::outdir`]): a folder holding files fathom
/// did not write is refused unless `force`, and nothing is replaced before the merge
/// is complete.
///
/// # Errors
/// Manifests that disagree, a run missing or duplicated, a corrupted record file (each
/// naming the shard or the file and line), a refused output folder, the experiment's
/// errors, I/O errors.
pub fn merge(
    registry: &[&'static dyn DynExperiment],
    dirs: &[PathBuf],
    threads: Option<usize>,
    base_dir: &Path,
    out_dir: &Path,
    force: bool,
) -> Result<(ExperimentResult, Manifest), SimError> {
    let mut shards = Vec::with_capacity(dirs.len());
    for d in dirs {
        shards.push((d.clone(), read_manifest(d)?));
    }
    check_out_apart(dirs, out_dir)?;
    let order = check_manifests(&shards)?;
    let first = shards[0].1.clone();
    let exp = registry
        .iter()
        .copied()
        .find(|e| e.name() == first.experiment)
        .ok_or_else(|| {
            SimError::invalid_argument(
                "merge",
                format!("experiment `{}` is not registered", first.experiment),
            )
        })?;
    let job = Job {
        text: &first.resolved_scenario,
        file: &first.scenario_label,
        runs: None,
        seed: None,
        threads,
        progress: None,
        env: crate::experiment::Environment::new(base_dir),
    };
    let assessed = exp.assess(&job)?;
    let claim = OutDir::claim(out_dir, force)?;
    let setup = assessed.resolved.setup.clone();
    let start = Instant::now();
    let mut source = FileSource {
        order,
        batch: 0,
        part: 0,
        reader: None,
    };
    let executed = assessed.execute_from(&mut source)?;
    let elapsed = start.elapsed();
    let mut result = write_executed(
        exp,
        &executed,
        &first.scenario_label,
        &setup,
        claim.dir(),
        elapsed,
    )?;
    // The scenario files of a single run (`execute_assessed_to`): the merged folder
    // holds the same set of files.
    write_text(claim.dir().join("scenario.toml"), &first.scenario_text)?;
    write_text(
        claim.dir().join("scenario.resolved.toml"),
        &(super::resolved_header(exp.name()) + &result.resolved_toml),
    )?;
    result.relocate(&claim);
    claim.commit(RunInfo {
        fathom_version: env!("CARGO_PKG_VERSION").to_string(),
        command: "merge".into(),
        experiment: first.experiment.clone(),
        scenario: first.scenario_label.clone(),
        runs: executed.resolved.runs,
        threads,
        seed: None,
        base_seed: first.base_seed,
        elapsed_s: elapsed.as_secs_f64(),
        files: Vec::new(),
    })?;
    result.files = executed.analysis.files;
    Ok((result, first))
}

/// The Slurm batch script of a campaign: a job array of `shards` tasks, each running
/// `fathom run <scenario> --runs <runs> --shard $SLURM_ARRAY_TASK_ID/<shards>` into its
/// own folder under `dir`, and a merge job that starts after every task succeeded.
pub fn slurm_script(scenario: &str, runs: usize, shards: usize, dir: &str) -> String {
    let last = shards.saturating_sub(1);
    format!(
        "#!/usr/bin/env bash\n\
         # A fathom campaign on Slurm: {shards} shards of {runs} Monte Carlo runs, then the merge.\n\
         # Submit with: bash {dir}/campaign.sh   (written by `fathom campaign slurm`)\n\
         set -euo pipefail\n\
         FATHOM=${{FATHOM:-fathom}}\n\
         mkdir -p {dir}/logs\n\
         array=$(sbatch --parsable --array=0-{last} --job-name=fathom-shard \\\n\
         \x20   --output={dir}/logs/shard-%a.out \\\n\
         \x20   --wrap=\"$FATHOM run {scenario} --runs {runs} --shard \\$SLURM_ARRAY_TASK_ID/{shards} --out {dir}/shard-\\$SLURM_ARRAY_TASK_ID\")\n\
         merge=$(sbatch --parsable --dependency=afterok:$array --job-name=fathom-merge \\\n\
         \x20   --output={dir}/logs/merge.out \\\n\
         \x20   --wrap=\"$FATHOM merge {dir}/shard-* --out {dir}/merged\")\n\
         echo \"submitted shards $array and merge $merge\"\n"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_every_run_once() {
        for (runs, count) in [(40, 4), (40, 3), (7, 3), (2, 5), (0, 2)] {
            let mut next = 0;
            for index in 0..count {
                let r = Shard { index, count }.range(runs);
                assert_eq!(r.start, next, "{runs} runs, {count} shards");
                next = r.end;
            }
            assert_eq!(next, runs);
        }
    }

    #[test]
    fn slurm_script_names_the_array_and_the_dependent_merge() {
        let s = slurm_script("b.toml", 40, 4, "out/c");
        assert!(s.contains("--array=0-3"), "{s}");
        assert!(s.contains("--shard \\$SLURM_ARRAY_TASK_ID/4"), "{s}");
        assert!(s.contains("--dependency=afterok:$array"), "{s}");
        assert!(s.contains("merge out/c/shard-* --out out/c/merged"), "{s}");
    }
}
