//! The runner (`fathom_sim`) against the registered experiments: every preset checks,
//! resolves and round-trips; the paper-or-variant setup; the `experiment` key's errors.

use std::path::{Path, PathBuf};

use fathom_sim::SimError;
use fathom_sim::cost::Limits;
use fathom_sim::driver::Setup;
use fathom_sim::user_run::{RunOptions, check_scenario, check_scenario_text, run_scenario};

use crate::registry;

#[test]
fn presets_are_the_paper_setup_up_to_runs_and_seeds() {
    for exp in registry() {
        let r = exp.resolve(exp.preset(), "p", None, None).unwrap();
        assert_eq!(Setup::of(exp, &r.toml), Setup::Paper, "{}", exp.name());
        if r.base_seed.is_some() {
            let r = exp.resolve(exp.preset(), "p", Some(3), Some(99)).unwrap();
            assert_eq!(Setup::of(exp, &r.toml), Setup::Paper, "{}", exp.name());
        }
    }
}

#[test]
fn a_variant_names_exactly_the_keys_it_changes() {
    let reg = registry();
    let beacons = reg.iter().find(|e| e.name() == "beacons").unwrap();
    let text = beacons
        .preset()
        .replace("outlier_count = 276", "outlier_count = 200")
        .replacen("[15.0, 15.0, 0.0], [-15.0", "[15.0, 15.0, 0.0], [-16.0", 1);
    let r = beacons.resolve(&text, "v", None, None).unwrap();
    let setup = r.setup.clone();
    assert_eq!(
        setup,
        Setup::Variant(vec![
            "beacons.positions".into(),
            "noise.outlier_count".into()
        ])
    );
    assert_eq!(setup.keys_text(1), "`beacons.positions`, 1 more");
    // A case's value is named with its index.
    let text = beacons
        .preset()
        .replacen("corr_sigma_m = 0.2", "corr_sigma_m = 0.3", 1);
    let r = beacons.resolve(&text, "v", None, None).unwrap();
    match r.setup.clone() {
        Setup::Variant(keys) => {
            assert_eq!(keys.len(), 1, "{keys:?}");
            assert!(keys[0].starts_with("cases[") && keys[0].ends_with("].corr_sigma_m"));
        }
        Setup::Paper => panic!("not detected"),
    }
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn every_preset_checks_and_round_trips() {
    let reg = registry();
    for exp in &reg {
        let c = check_scenario(&root().join(exp.default_scenario()), &reg).unwrap();
        assert_eq!(c.experiment, exp.name());
        assert!(c.keys > 5, "{}: {} keys", exp.name(), c.keys);
        // The resolved TOML is itself a valid scenario.
        let again = check_scenario_text(&c.resolved_toml, "resolved", &reg).unwrap();
        assert_eq!(again.resolved_toml, c.resolved_toml);
    }
}

#[test]
fn every_seeded_preset_resolves_with_a_new_seed_and_run_count() {
    let reg = registry();
    for exp in &reg {
        let text = std::fs::read_to_string(root().join(exp.default_scenario())).unwrap();
        match exp.resolve(&text, "preset", Some(7), Some(123_456)) {
            Ok(r) => {
                assert_eq!((r.runs, r.base_seed), (Some(7), Some(123_456)));
                // Still a valid scenario of the same experiment, now with both.
                let again = exp.resolve(&r.toml, "resolved", None, None).unwrap();
                assert_eq!(again, r);
            }
            Err(e) => {
                assert_eq!(exp.name(), "plaza", "only plaza is deterministic: {e}");
                assert!(e.to_string().contains("--seed"), "{e}");
            }
        }
    }
}

#[test]
fn seed_on_a_deterministic_experiment_and_huge_seeds_are_usage_errors() {
    let out = std::env::temp_dir().join(format!("fathom-sim-seed-{}", std::process::id()));
    let options = RunOptions {
        scenario: root().join("scenarios/plaza.toml"),
        out_dir: Some(out.clone()),
        runs: None,
        threads: None,
        seed: Some(5),
        base_dir: root(),
        force: false,
        limits: Limits::default(),
        extras: Default::default(),
        scene_page: true,
    };
    let reg = registry();
    let e = run_scenario(&options, &reg).unwrap_err();
    assert!(matches!(e, SimError::InvalidArgument { .. }), "{e}");
    let s = e.to_string();
    assert!(s.contains("--seed") && s.contains("deterministic"), "{s}");
    // Refused before anything is written.
    assert!(!out.exists());
    let huge = RunOptions {
        scenario: root().join("scenarios/beacons.toml"),
        seed: Some(u64::MAX),
        ..options
    };
    let s = run_scenario(&huge, &reg).unwrap_err().to_string();
    assert!(s.contains("--seed") && s.contains("at most"), "{s}");
    assert!(!out.exists());
}

#[test]
fn experiment_key_errors() {
    let reg = registry();
    let e = check_scenario_text("runs = 3\n", "a.toml", &reg).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("a.toml: key `experiment`: missing"),
        "{e}"
    );
    let e = check_scenario_text("experiment = \"x\"\n", "a.toml", &reg).unwrap_err();
    assert!(e.to_string().contains("unknown experiment \"x\""), "{e}");
    let e = check_scenario_text("experiment = 3\n", "a.toml", &reg).unwrap_err();
    assert!(e.to_string().contains("must be a string"), "{e}");
}

#[test]
fn an_assessed_table_is_the_resolved_text_parsed_back() {
    // The setup comparison and `fathom check`'s counts read the typed scenario as a table
    // instead of parsing the resolved text again: the two must be the same table, for
    // every preset and every scenario file of the repository.
    let reg = registry();
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("scenarios"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    let mut compared = 0;
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let label = path.display().to_string();
        let job = fathom_sim::experiment::Job {
            text: &text,
            file: &label,
            runs: Some(3),
            seed: None,
            threads: None,
            progress: None,
            env: fathom_sim::experiment::Environment::new(root()),
        };
        // Replay settings files are not scenarios of a registered experiment.
        let Ok((exp, a)) = fathom_sim::user_run::assess_scenario(&job, &reg) else {
            continue;
        };
        let parsed: toml::Table = a.resolved.toml.parse().unwrap();
        assert_eq!(a.table, parsed, "{label}");
        assert_eq!(
            Setup::of_table(exp, &a.table),
            Setup::of(exp, &a.resolved.toml),
            "{label}"
        );
        compared += 1;
    }
    assert!(compared >= reg.len(), "{compared} scenario files compared");
}
