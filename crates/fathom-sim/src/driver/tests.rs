//! Tests of the driver with small stand-in experiments: outputs written, failures
//! reported while the others still run, the collected report, bad options.

use std::path::{Path, PathBuf};

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::*;
use crate::experiment::{Analysis, Batch, DynExperiment, Environment, Experiment};
use fathom_report::output::{Claim, read_summary_json};
use fathom_report::plot::{LinePlot, Series};

#[derive(Debug, Clone, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct DummyScenario {
    experiment: String,
    runs: usize,
    base_seed: u64,
    #[serde(default)]
    statistics: crate::statistics::StatisticsParams,
}

crate::monte_carlo_scenario!(DummyScenario);

/// Draws one uniform number per run; `NAME` is a const parameter through the kind.
#[derive(Debug, Clone, Copy)]
struct Dummy<const K: u8>;

const fn name_of(k: u8) -> &'static str {
    match k {
        0 => "dummy",
        1 => "broken",
        2 => "second",
        _ => "Bad/Name",
    }
}

impl<const K: u8> Experiment for Dummy<K> {
    type Scenario = DummyScenario;
    type Checked = DummyScenario;
    type Prepared = DummyScenario;
    type Record = f64;
    type Kept = Self::Record;
    type Fold = ();
    const NAME: &'static str = name_of(K);
    const SEED_DOC: &'static str = "seed.txt";
    const DEFAULT_SCENARIO: &'static str = match K {
        1 => "scenarios/missing.toml",
        _ => "scenarios/dummy.toml",
    };
    const PRESET: &'static str = "experiment = \"dummy\"\nruns = 10\nbase_seed = 5\n";
    const ABOUT: &'static str = "a test experiment";

    fn check(&self, s: &DummyScenario, file: &str) -> Result<DummyScenario, SimError> {
        if s.runs < 2 {
            return Err(SimError::invalid(file, "runs", "needs at least 2"));
        }
        Ok(s.clone())
    }

    fn prepare(&self, c: DummyScenario, _env: &Environment) -> Result<DummyScenario, SimError> {
        Ok(c)
    }

    fn batches(&self, c: &DummyScenario) -> Vec<Batch> {
        vec![Batch::new(Self::NAME, c.runs)]
    }

    fn run(
        &self,
        _c: &DummyScenario,
        _batch: usize,
        _index: usize,
        rng: &mut ChaCha8Rng,
    ) -> Result<f64, SimError> {
        Ok(rng.random::<f64>())
    }

    fn fold(
        &self,
        _prepared: &DummyScenario,
        _batch: usize,
        _index: usize,
        record: Self::Record,
        _fold: &mut (),
    ) -> Self::Record {
        record
    }

    fn analyse(
        &self,
        c: &DummyScenario,
        records: Vec<Vec<f64>>,
        _folds: Vec<()>,
        out: &mut Analysis,
    ) -> Result<(), SimError> {
        let draws = &records[0];
        let mean = draws.iter().sum::<f64>() / c.runs as f64;
        out.unit("mean", "1");
        out.runs_row("U01", "mean", draws)?.paper = Some(0.5);
        out.claim(Claim::new(
            "mean_near_half",
            "mean is near 0.5",
            (mean - 0.5).abs() < 0.2,
            format!("{mean:.3}"),
        ));
        let plot = LinePlot::new("Draws", "run", "value").with_series(Series::new(
            "u",
            draws
                .iter()
                .enumerate()
                .map(|(i, &d)| (i as f64, d))
                .collect(),
        ));
        out.figure("draws.svg", &plot)?;
        out.report("### Decisions\n\nNone.");
        Ok(())
    }
}

fn reg() -> Vec<&'static dyn DynExperiment> {
    vec![&Dummy::<0>, &Dummy::<1>]
}

fn opts(tag: &str, only: Option<&str>) -> PaperOptions {
    let root: PathBuf = std::env::temp_dir()
        .join("fathom-sim-tests")
        .join("paper")
        .join(tag);
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(root.join("scenarios")).unwrap();
    std::fs::write(
        root.join("scenarios/dummy.toml"),
        "experiment = \"dummy\"\nruns = 10\nbase_seed = 5\n",
    )
    .unwrap();
    PaperOptions {
        only: only.map(str::to_string),
        runs: Some(20),
        threads: Some(2),
        out_root: root.join("target/paper"),
        workspace_root: root,
        force: false,
    }
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap()
}

#[test]
fn runs_dummy_and_writes_all_outputs() {
    let o = opts("ok", Some("dummy"));
    // A stale file of an earlier run (listed in its run_info.json) is removed.
    std::fs::create_dir_all(o.out_root.join("dummy")).unwrap();
    std::fs::write(o.out_root.join("dummy/old.svg"), "<svg/>").unwrap();
    std::fs::write(
        o.out_root.join("dummy/run_info.json"),
        r#"{"fathom_version": "0", "experiment": "dummy", "scenario": "s", "runs": null,
            "threads": null, "files": ["old.svg"]}"#,
    )
    .unwrap();
    let mut buf = Vec::new();
    let res = run_paper_to(&o, &reg(), &mut buf).unwrap();
    let printed = String::from_utf8(buf).unwrap();
    assert_eq!(res.experiments.len(), 1);
    let r = &res.experiments[0];
    // `--runs 20` replaced the scenario's 10, and the resolved scenario says so.
    assert_eq!(r.summary.runs, 20);
    assert!(r.resolved_toml.contains("runs = 20"), "{}", r.resolved_toml);
    assert_eq!(r.figures, vec![o.out_root.join("dummy/draws.svg")]);
    assert!(printed.contains("== dummy (seed.txt) =="), "{printed}");
    assert!(printed.contains("[holds] mean_near_half"), "{printed}");
    let back = read_summary_json(o.out_root.join("dummy/summary.json")).unwrap();
    assert_eq!(back, r.summary);
    let rep = read(&o.out_root.join("dummy/report.md"));
    assert!(
        rep.contains("| method | metric | unit | paper | reproduced | 95% CI |"),
        "{rep}"
    );
    assert!(rep.contains("- [draws.svg](draws.svg)"), "{rep}");
    assert!(rep.contains("### Decisions"), "{rep}");
    let all = read(&res.report_path);
    assert!(all.contains("## dummy"), "{all}");
    assert!(all.contains("#### Decisions"), "{all}");
    assert!(all.contains("- [draws.svg](dummy/draws.svg)"), "{all}");
    assert!(all.contains("| not run |"), "{all}");
    assert!(!o.out_root.join("dummy/old.svg").exists());
}

#[test]
fn same_numbers_for_one_and_two_threads() {
    let mut a = opts("threads1", Some("dummy"));
    a.threads = Some(1);
    let mut b = opts("threads2", Some("dummy"));
    b.threads = Some(2);
    let ra = run_paper_to(&a, &reg(), &mut Vec::new()).unwrap();
    let rb = run_paper_to(&b, &reg(), &mut Vec::new()).unwrap();
    assert_eq!(ra.experiments[0].summary, rb.experiments[0].summary);
}

#[test]
fn unknown_only_lists_known_names() {
    let e = run_paper_to(&opts("unknown", Some("fusion")), &reg(), &mut Vec::new()).unwrap_err();
    let s = e.to_string();
    assert!(s.contains("unknown experiment `fusion`"), "{s}");
    assert!(s.contains("dummy, broken"), "{s}");
}

#[test]
fn failures_are_reported_and_others_still_run() {
    let o = opts("fail", None);
    let mut buf = Vec::new();
    let e = run_paper_to(&o, &reg(), &mut buf).unwrap_err();
    let chain = error_chain(&e);
    assert!(
        chain.starts_with("experiment `broken` failed: cannot read"),
        "{chain}"
    );
    assert!(chain.contains("missing.toml"), "{chain}");
    assert!(o.out_root.join("dummy/summary.json").exists());
    let all = read(&o.out_root.join("REPORT.md"));
    assert!(
        all.contains("**Failed:** experiment `broken` failed"),
        "{all}"
    );
    assert!(all.contains("| failed |"), "{all}");
}

#[test]
fn earlier_results_stay_in_collected_report() {
    let o = opts("earlier", Some("dummy"));
    run_paper_to(&o, &reg(), &mut Vec::new()).unwrap();
    // A second, different selection keeps dummy's section from disk.
    let reg2: Vec<&'static dyn DynExperiment> = vec![&Dummy::<0>, &Dummy::<2>];
    let e = run_paper_to(
        &PaperOptions {
            only: Some("second".into()),
            ..o.clone()
        },
        &reg2,
        &mut Vec::new(),
    );
    // `second` reads dummy.toml, whose `experiment` key names `dummy`.
    assert!(e.is_err());
    let all = read(&o.out_root.join("REPORT.md"));
    assert!(all.contains("results from an earlier run"), "{all}");
    assert!(all.contains("| earlier run |"), "{all}");
}

#[test]
fn bad_options_and_registry_are_rejected() {
    let mut o = opts("badopts", None);
    o.runs = Some(0);
    assert!(run_paper_to(&o, &reg(), &mut Vec::new()).is_err());
    let mut o = opts("badopts2", None);
    o.threads = Some(0);
    assert!(run_paper_to(&o, &reg(), &mut Vec::new()).is_err());
    let dup: Vec<&'static dyn DynExperiment> = vec![&Dummy::<0>, &Dummy::<0>];
    assert!(run_paper_to(&opts("dup", None), &dup, &mut Vec::new()).is_err());
    let bad: Vec<&'static dyn DynExperiment> = vec![&Dummy::<3>];
    assert!(run_paper_to(&opts("badname", None), &bad, &mut Vec::new()).is_err());
}

#[test]
fn empty_registry_writes_report() {
    let o = opts("empty", None);
    let r = run_paper_to(&o, &[], &mut Vec::new()).unwrap();
    assert!(r.experiments.is_empty());
    let all = read(&r.report_path);
    assert!(all.contains("No experiments are registered."));
}

#[test]
fn seed_override_reaches_every_run_and_the_summary() {
    let o = opts("seed", None);
    let text = read(&o.workspace_root.join("scenarios/dummy.toml"));
    let job = |seed| Job {
        text: &text,
        file: "dummy.toml",
        runs: None,
        seed,
        threads: Some(2),
        progress: None,
        env: Environment::new(o.workspace_root.clone()),
    };
    let exp: &dyn DynExperiment = &Dummy::<0>;
    let a = exp.execute(&job(None)).unwrap();
    let b = exp.execute(&job(Some(77))).unwrap();
    assert_eq!((a.summary.base_seed, b.summary.base_seed), (5, 77));
    assert_ne!(a.summary.rows[0].value, b.summary.rows[0].value);
    assert!(
        b.resolved.toml.contains("base_seed = 77"),
        "{}",
        b.resolved.toml
    );
}

/// The labels [`ScenarioDoc::parse`](crate::scenario::ScenarioDoc::parse) saw on this
/// thread while `f` ran.
fn parses_during(f: impl FnOnce()) -> Vec<String> {
    crate::scenario::PARSES.with(|p| p.borrow_mut().clear());
    f();
    crate::scenario::PARSES.with(|p| p.take())
}

#[test]
fn a_run_a_check_and_a_shard_parse_the_scenario_text_once() {
    use crate::user_run::{RunOptions, check_scenario_text, run_scenario_text};
    let root = std::env::temp_dir()
        .join("fathom-sim-tests")
        .join(format!("parse-once-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let text = "experiment = \"dummy\"\nruns = 4\nbase_seed = 9\n";
    let options = RunOptions {
        scenario: "dummy.toml".into(),
        out_dir: Some(root.join("run")),
        runs: Some(3),
        threads: Some(1),
        seed: None,
        base_dir: root.clone(),
        force: false,
        limits: crate::cost::Limits::default(),
        extras: Default::default(),
        scene_page: true,
    };
    let mine = |seen: &[String]| seen.iter().filter(|l| *l == "dummy.toml").count();
    // The preset is parsed too (the setup comparison), never the user's text again.
    let seen = parses_during(|| {
        run_scenario_text(text, "dummy.toml", &options, &reg(), None).unwrap();
    });
    assert_eq!(mine(&seen), 1, "{seen:?}");
    assert!(
        seen.iter().all(|l| l == "dummy.toml" || l == "preset"),
        "{seen:?}"
    );
    let seen = parses_during(|| {
        check_scenario_text(text, "dummy.toml", &reg()).unwrap();
    });
    assert_eq!(mine(&seen), 1, "{seen:?}");
    assert!(
        seen.iter().all(|l| l == "dummy.toml" || l == "preset"),
        "{seen:?}"
    );
    let seen = parses_during(|| {
        let job = crate::user_run::job_of(text, "dummy.toml", &options, None);
        let (exp, a) = crate::user_run::assess_scenario(&job, &reg()).unwrap();
        let shard = crate::experiment::Shard { index: 0, count: 2 };
        super::campaign::run_assessed_shard(exp, a, &job, shard, &root.join("shard"), false)
            .unwrap();
    });
    assert_eq!(mine(&seen), 1, "{seen:?}");
    assert!(
        seen.iter().all(|l| l == "dummy.toml" || l == "preset"),
        "{seen:?}"
    );
    // Negative control: the convenience `resolve` after an assessment parses again, and
    // the counter sees it.
    let seen = parses_during(|| {
        let job = crate::user_run::job_of(text, "dummy.toml", &options, None);
        let (exp, _) = crate::user_run::assess_scenario(&job, &reg()).unwrap();
        exp.resolve(text, "dummy.toml", None, None).unwrap();
    });
    assert_eq!(mine(&seen), 2, "{seen:?}");
}
