//! Every numeric key of every settings file under `scenarios/` set to each absurd value
//! of issue #38 (0, -1, NaN, inf, 1e-300, 1e300): `check` refuses the file as the
//! user's mistake, on one line naming that key, or accepts it, and then the file runs
//! to finite results. The keys are those of the resolved scenario (defaults filled
//! in), so a key the preset leaves to its default is tried too; of an array of
//! numbers the first and the last element are tried.
//!
//! The accepted variants are run by `.ci/every-key-runs.sh` (release build, about
//! 5 min; each must exit 0 with finite values in its summary.json), which reads them
//! from `FATHOM_EVERY_KEY_DUMP`.
//!
//! The check runs in process through the same function as `fathom check`
//! ([`check_scenario_text_in`]); PILS settings, checked by the binary's own code,
//! through `fathom check`. The slowest refusal is printed (tests never assert
//! timings; the release figure is in the note of issue #38).

use std::time::{Duration, Instant};

use fathom_sim::experiment::{Environment, Extras};
use fathom_sim::user_run::{check_scenario_text_in, one_line};
use fathom_sim::{SimError, error_chain};

use crate::support::{fathom, repo_root, scratch};

/// The values of the issue, written as TOML: integers where the key is an integer
/// (a float there is a type error, which must name the key as well).
const ABSURD: [&str; 6] = ["0", "-1", "nan", "inf", "1e-300", "1e300"];

/// One numeric leaf of a settings file: its dotted path (`a.b[2].c`) and where it
/// sits in the parsed table.
#[derive(Debug, Clone)]
struct Leaf {
    path: String,
    steps: Vec<Step>,
    integer: bool,
}

#[derive(Debug, Clone)]
enum Step {
    Key(String),
    Index(usize),
}

fn leaves(value: &toml::Value, path: &str, steps: &[Step], out: &mut Vec<Leaf>) {
    match value {
        toml::Value::Table(t) => {
            for (k, v) in t {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                let mut s = steps.to_vec();
                s.push(Step::Key(k.clone()));
                leaves(v, &p, &s, out);
            }
        }
        toml::Value::Array(a) => {
            let numbers = a
                .iter()
                .all(|v| matches!(v, toml::Value::Integer(_) | toml::Value::Float(_)));
            let picked: Vec<usize> = if numbers && a.len() > 1 {
                vec![0, a.len() - 1]
            } else {
                (0..a.len()).collect()
            };
            for i in picked {
                let mut s = steps.to_vec();
                s.push(Step::Index(i));
                leaves(&a[i], &format!("{path}[{i}]"), &s, out);
            }
        }
        toml::Value::Integer(_) | toml::Value::Float(_) => out.push(Leaf {
            path: path.to_string(),
            steps: steps.to_vec(),
            integer: matches!(value, toml::Value::Integer(_)),
        }),
        _ => {}
    }
}

/// `table` with the leaf at `steps` replaced by `new`.
fn replaced(table: &toml::Table, steps: &[Step], new: toml::Value) -> toml::Table {
    let mut root = toml::Value::Table(table.clone());
    let mut at = &mut root;
    for s in steps {
        at = match (s, at) {
            (Step::Key(k), toml::Value::Table(t)) => t.get_mut(k).expect("key of the walk"),
            (Step::Index(i), toml::Value::Array(a)) => &mut a[*i],
            _ => unreachable!("the steps come from the same table"),
        };
    }
    *at = new;
    match root {
        toml::Value::Table(t) => t,
        _ => unreachable!(),
    }
}

fn value_of(text: &str, integer: bool) -> toml::Value {
    match text {
        "0" | "-1" if integer => toml::Value::Integer(text.parse().unwrap()),
        _ => toml::Value::Float(text.parse().unwrap()),
    }
}

/// The key path with array indices removed (`a.b[2].c` -> `a.b.c`).
fn without_indices(path: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for c in path.chars() {
        match c {
            '[' => depth += 1,
            ']' => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out
}

/// Whether the error names `leaf`: its key path is the leaf's (array indices aside,
/// as TOML's own errors do not carry them), or its message names the leaf's key path
/// (a constraint between two keys blames one and names the other), or it blames a
/// key of the same table and names the leaf by its key there.
fn names(error: &SimError, line: &str, leaf: &Leaf) -> bool {
    let blamed = match error {
        SimError::Invalid { key_path, .. } => Some(key_path.as_str()),
        SimError::Toml { key_path, .. } => key_path.as_deref(),
        _ => None,
    };
    let wanted = without_indices(&leaf.path);
    let (table, name) = wanted.rsplit_once('.').unwrap_or(("", &wanted));
    let sibling = |b: &str| {
        let b = without_indices(b);
        b.rsplit_once('.').map_or("", |(t, _)| t) == table
    };
    blamed.is_some_and(|b| without_indices(b) == wanted)
        || without_indices(line).contains(&wanted)
        // a key of the same table, whose message names this one by its own name
        || (blamed.is_some_and(sibling) && line.contains(name))
}

/// The longest run of digits and points in `line` (a number written out in full).
fn longest_number(line: &str) -> usize {
    line.split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .map(str::len)
        .max()
        .unwrap_or(0)
}

/// What went wrong with one variant, for the failure list.
fn describe(file: &str, leaf: &Leaf, value: &str, what: &str) -> String {
    format!("{file}: {} = {value}: {what}", leaf.path)
}

struct Tally {
    variants: usize,
    refused: usize,
    accepted: Vec<(String, String, String)>,
    slowest: (Duration, String),
    failures: Vec<String>,
}

fn try_file(file: &str, text: &str, env: &Environment, tally: &mut Tally) {
    let registry = fathom_experiments::jobs();
    let checked = check_scenario_text_in(text, file, &registry, env.clone())
        .unwrap_or_else(|e| panic!("{file} as shipped: {}", error_chain(&e)));
    let table: toml::Table = toml::from_str(&checked.resolved_toml).unwrap();
    let mut found = Vec::new();
    leaves(&toml::Value::Table(table.clone()), "", &[], &mut found);
    assert!(!found.is_empty(), "{file}: no numeric key found");
    for leaf in &found {
        for value in ABSURD {
            tally.variants += 1;
            let variant = toml::to_string(&replaced(
                &table,
                &leaf.steps,
                value_of(value, leaf.integer),
            ))
            .unwrap();
            let start = Instant::now();
            let outcome = check_scenario_text_in(&variant, file, &registry, env.clone());
            let took = start.elapsed();
            match outcome {
                Err(e) => {
                    tally.refused += 1;
                    if took > tally.slowest.0 {
                        tally.slowest = (took, format!("{file}: {} = {value}", leaf.path));
                    }
                    let line = one_line(&error_chain(&e));
                    let problem = if !e.is_user_error() {
                        Some("exit 1")
                    } else if !names(&e, &line, leaf) {
                        Some("names another key")
                    } else if line.len() > 1024 || longest_number(&line) > 24 {
                        Some("over 1 kB or a number written out in full")
                    } else {
                        None
                    };
                    if let Some(problem) = problem {
                        let what = format!("{problem}: {line}");
                        tally.failures.push(describe(file, leaf, value, &what));
                    }
                }
                Ok(_) => tally.accepted.push((
                    file.to_string(),
                    format!("{} = {value}", leaf.path),
                    variant,
                )),
            }
        }
    }
}

/// The settings files under `scenarios/` with their `experiment` key.
fn all_settings_files() -> Vec<(String, String)> {
    let dir = repo_root().join("scenarios");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let name = format!("scenarios/{}", p.file_name().unwrap().to_string_lossy());
            (name, std::fs::read_to_string(&p).unwrap())
        })
        .collect()
}

fn is_pils(text: &str) -> bool {
    let t: toml::Table = toml::from_str(text).unwrap();
    t.get("experiment").and_then(|v| v.as_str()) == Some("pils")
}

/// The settings files but the PILS ones (which `fathom check` handles in the binary).
fn settings_files() -> Vec<(String, String)> {
    all_settings_files()
        .into_iter()
        .filter(|(_, text)| !is_pils(text))
        .collect()
}

#[test]
fn every_numeric_key_set_absurd_is_refused_naming_it_or_runs() {
    // with the paper's extras, so that the keys only they read are checked too
    let env = Environment {
        extras: Extras::Always,
        ..Environment::new(repo_root())
    };
    let mut tally = Tally {
        variants: 0,
        refused: 0,
        accepted: Vec::new(),
        slowest: (Duration::ZERO, String::new()),
        failures: Vec::new(),
    };
    for (file, text) in settings_files() {
        try_file(&file, &text, &env, &mut tally);
    }
    println!(
        "{} variants: {} refused (slowest check {:.0} ms: {}), {} accepted",
        tally.variants,
        tally.refused,
        tally.slowest.0.as_secs_f64() * 1e3,
        tally.slowest.1,
        tally.accepted.len()
    );
    // FATHOM_EVERY_KEY_DUMP=DIR writes each accepted variant there (to run them)
    let dump = std::env::var_os("FATHOM_EVERY_KEY_DUMP").map(std::path::PathBuf::from);
    for (i, (file, what, variant)) in tally.accepted.iter().enumerate() {
        println!("accepted: {file}: {what}");
        if let Some(dir) = &dump {
            std::fs::create_dir_all(dir).unwrap();
            let name = format!("{i:04}.toml");
            std::fs::write(dir.join(&name), format!("# {file}: {what}\n{variant}")).unwrap();
        }
    }
    assert!(
        tally.failures.is_empty(),
        "{} of {} variants are not refused as the user's mistake naming the key:\n{}",
        tally.failures.len(),
        tally.variants,
        tally.failures.join("\n")
    );
}

/// The PILS settings through `fathom check` (checked by the binary before any socket):
/// each numeric key as written set to each absurd value, in a copy of `scenarios/`
/// (the settings name the urban scenario beside them).
#[test]
fn every_numeric_pils_key_set_absurd_is_refused_naming_it_or_checks() {
    let dir = scratch("every-pils-key");
    let src = repo_root().join("scenarios");
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        if path.is_file() {
            std::fs::copy(&path, dir.join("scenarios").join(path.file_name().unwrap())).unwrap();
        }
    }
    let worlds = dir.join("scenarios/worlds");
    std::fs::create_dir_all(&worlds).unwrap();
    for entry in std::fs::read_dir(src.join("worlds")).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, worlds.join(path.file_name().unwrap())).unwrap();
    }
    let (mut variants, mut refused, mut failures) = (0, 0, Vec::new());
    for (file, text) in all_settings_files().into_iter().filter(|(_, t)| is_pils(t)) {
        let table: toml::Table = toml::from_str(&text).unwrap();
        let mut found = Vec::new();
        leaves(&toml::Value::Table(table.clone()), "", &[], &mut found);
        assert!(!found.is_empty(), "{file}: no numeric key found");
        for leaf in &found {
            for value in ABSURD {
                variants += 1;
                let variant = toml::to_string(&replaced(
                    &table,
                    &leaf.steps,
                    value_of(value, leaf.integer),
                ))
                .unwrap();
                std::fs::write(dir.join("scenarios/variant.toml"), &variant).unwrap();
                let ran = fathom(&dir, &["check", "--quiet", "scenarios/variant.toml"]);
                let line = ran.stderr.trim();
                let wanted = without_indices(&leaf.path);
                match ran.code {
                    0 => {}
                    2 if line.lines().count() == 1 && without_indices(line).contains(&wanted) => {
                        refused += 1;
                    }
                    code => failures.push(format!(
                        "{file}: {} = {value}: exit {code}: {line}",
                        leaf.path
                    )),
                }
            }
        }
    }
    println!("PILS: {variants} variants, {refused} refused");
    assert!(
        refused > 0,
        "no PILS variant was refused: the test tried nothing"
    );
    assert!(
        failures.is_empty(),
        "{} PILS variants are not refused as the user's mistake naming the key:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
