//! End-to-end tests of one's own logs through the real `fathom` binary: example logs
//! of both kinds are generated (`fathom log example`), checked and replayed with and
//! without ground truth; corrupted copies (NaN, time going backwards, a missing or an
//! unknown column, a missing folder) exit with code 2 and one line naming the file,
//! line and column; the CMU Plaza data converted into the layout replays to the
//! `replay plaza` numbers (the repository's `data/plaza1`); every replay (`plaza`,
//! `range-beacon`, `ins-dvl`) writes the outputs of `fathom run`.

use std::path::Path;

use fathom_report::output::{Summary, read_summary_json};

use crate::support::{fathom, read, repo_root, scratch, usage_error};

fn ok(dir: &Path, args: &[&str]) -> String {
    let r = fathom(dir, args);
    assert_eq!(r.code, 0, "{args:?}: {}", r.stderr);
    r.stdout
}

/// The unit and value cells of the console row `method` / `metric` (the table of
/// `fathom run`: `method | metric | unit | value`), if printed.
fn console_row(console: &str, method: &str, metric: &str) -> Option<(String, String)> {
    console.lines().find_map(|l| {
        let cells: Vec<&str> = l.split('|').map(str::trim).collect();
        (cells.len() >= 4 && cells[0] == method && cells[1] == metric)
            .then(|| (cells[2].to_string(), cells[3].to_string()))
    })
}

/// The shared `summary.json` of the output folder `dir`.
fn summary(dir: &Path) -> Summary {
    read_summary_json(dir.join("summary.json")).expect("summary.json in the shared format")
}

#[test]
fn example_logs_replay_with_and_without_truth() {
    let root = scratch("own-logs-replay");
    // The default example (300 s): it says how many range outliers it injected.
    let wrote = ok(&root, &["log", "example", "range-beacon", "--out", "rb"]);
    let injected: f64 = wrote
        .split(" range outliers of +")
        .next()
        .and_then(|head| head.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no outlier count in: {wrote}"));
    assert!(injected > 0.0, "{wrote}");
    ok(
        &root,
        &[
            "log",
            "example",
            "range-beacon",
            "--out",
            "rb-nt",
            "--duration",
            "120",
            "--no-truth",
        ],
    );
    ok(
        &root,
        &[
            "log",
            "example",
            "ins-dvl",
            "--out",
            "ins",
            "--duration",
            "60",
        ],
    );
    ok(
        &root,
        &[
            "log",
            "example",
            "ins-dvl",
            "--out",
            "ins-nt",
            "--duration",
            "60",
            "--no-truth",
        ],
    );
    assert!(ok(&root, &["log", "check", "rb"]).contains("valid range-beacon log"));
    assert!(ok(&root, &["log", "check", "ins-nt"]).contains("truth: no"));
    // Writing over an existing log is refused.
    usage_error(
        &root,
        &["log", "example", "ins-dvl", "--out", "ins"],
        &["exists already"],
    );

    let out = ok(&root, &["replay", "range-beacon", "rb", "--out", "o-rb"]);
    // The console is `fathom run`'s table: the error rows in metres, the NIS rows.
    assert_eq!(
        console_row(&out, "AS", "mean").map(|c| c.0),
        Some("m".into()),
        "{out}"
    );
    assert!(
        console_row(&out, "AS", "nis_ranges_mean").is_some(),
        "{out}"
    );
    let report = read(&root.join("o-rb"), "report.md");
    assert!(
        report.contains("Position error against `truth.csv` (3D, m)"),
        "{report}"
    );
    // The filters beat dead reckoning on the example (the heading's random walk lets
    // dead reckoning drift) and reject exactly the injected outliers.
    let s = summary(&root.join("o-rb"));
    assert_eq!(s.experiment, "range-beacon");
    assert_eq!(s.extra["error"], "3D");
    let mean = |name: &str| s.row(name, "mean").expect("mean row").value;
    for m in ["AS", "SC", "SI"] {
        assert!(
            mean(m) < mean("DR"),
            "{m}: {} vs DR {}",
            mean(m),
            mean("DR")
        );
        assert_eq!(s.row(m, "rejected").unwrap().value, injected, "{m}");
    }
    // Simulated with the noise of the built-in settings: every filter is consistent.
    assert!(!s.claims.is_empty());
    for c in &s.claims {
        assert!(c.holds, "{}: {}", c.id, c.detail);
    }
    let est = read(&root.join("o-rb"), "estimates.csv");
    assert!(est.starts_with("time[s],true_north[m],true_east[m],true_down[m],DR_north[m]"));

    let out = ok(
        &root,
        &["replay", "range-beacon", "rb-nt", "--out", "o-rb-nt"],
    );
    // Without truth: no error rows, the NIS rows of the ranges.
    assert!(
        console_row(&out, "AS", "mean").is_none()
            && console_row(&out, "AS", "nis_ranges_mean").is_some(),
        "{out}"
    );
    let s = summary(&root.join("o-rb-nt"));
    assert!(s.rows.iter().all(|r| r.metric != "rmse"), "{:?}", s.rows);
    assert_eq!(s.extra["with_truth"], false);
    let report = read(&root.join("o-rb-nt"), "report.md");
    assert!(
        report.contains("no `truth.csv`") && !report.contains("Position error"),
        "{report}"
    );
    assert!(
        read(&root.join("o-rb-nt"), "innovations.csv")
            .lines()
            .count()
            > 100
    );

    let out = ok(&root, &["replay", "ins-dvl", "ins", "--out", "o-ins"]);
    for m in ["PINS", "INS-DVL", "VKF", "ESKF"] {
        assert!(out.contains(m), "{out}");
    }
    assert!(read(&root.join("o-ins"), "report.md").contains("Horizontal position error"));
    let out = ok(&root, &["replay", "ins-dvl", "ins-nt", "--out", "o-ins-nt"]);
    assert!(
        console_row(&out, "VKF", "nis_dvl_velocity_mean").is_some()
            && console_row(&out, "VKF", "mean").is_none(),
        "{out}"
    );

    // Methods and their tuning come from a settings file; a bad one names the key and
    // lists the valid filters.
    let settings = std::fs::read_to_string(repo_root().join("scenarios/ins-dvl.toml")).unwrap();
    let cut = settings[..settings.find("[[methods]]").unwrap()].to_string()
        + "[[methods]]\nname = \"mine\"\nfilter = \"eskf\"\n";
    std::fs::write(root.join("one.toml"), &cut).unwrap();
    let out = ok(
        &root,
        &[
            "replay", "ins-dvl", "ins", "--config", "one.toml", "--out", "o1",
        ],
    );
    assert!(out.contains("mine") && !out.contains("PINS"), "{out}");
    std::fs::write(root.join("bad.toml"), cut.replace("\"eskf\"", "\"ukf\"")).unwrap();
    usage_error(
        &root,
        &["replay", "ins-dvl", "ins", "--config", "bad.toml"],
        &["bad.toml", "methods[0].filter", "ukf", "eskf"],
    );
    // A log of the other kind.
    usage_error(
        &root,
        &["replay", "ins-dvl", "rb"],
        &["log.toml", "not an `ins-dvl` log"],
    );
}

#[test]
fn corrupted_logs_name_file_line_and_column() {
    let root = scratch("own-logs-bad");
    ok(
        &root,
        &[
            "log",
            "example",
            "range-beacon",
            "--out",
            "good",
            "--duration",
            "30",
        ],
    );
    let ranges = read(&root.join("good"), "ranges.csv");
    let copy = |name: &str, file: &str, text: &str| {
        let dir = root.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        for f in std::fs::read_dir(root.join("good")).unwrap() {
            let f = f.unwrap();
            std::fs::copy(f.path(), dir.join(f.file_name())).unwrap();
        }
        std::fs::write(dir.join(file), text).unwrap();
    };
    let mut lines: Vec<String> = ranges.lines().map(String::from).collect();
    assert_eq!(lines[0], "time[s],beacon,range[m]");
    // Line 4 of the file: a NaN range.
    let mut nan = lines.clone();
    let cells: Vec<&str> = nan[3].split(',').collect();
    nan[3] = format!("{},{},NaN", cells[0], cells[1]);
    copy("nan", "ranges.csv", &(nan.join("\n") + "\n"));
    // Line 6: a time before line 5's.
    let t5: f64 = lines[4].split(',').next().unwrap().parse().unwrap();
    let rest6: Vec<&str> = lines[5].split(',').collect();
    lines[5] = format!("{},{},{}", t5 - 1.0, rest6[1], rest6[2]);
    copy("time", "ranges.csv", &(lines.join("\n") + "\n"));
    copy("missing", "ranges.csv", "time[s],range[m]\n1,2\n");
    copy("unknown", "ranges.csv", "time[s],beacon,range[m],snr[dB]\n");
    copy("stray", "range.csv", "time[s],beacon,range[m]\n");
    let cases: [(&str, &[&str]); 6] = [
        (
            "nan",
            &[
                "ranges.csv` line 4, column 3 (`range[m]`)",
                "`NaN` is not a finite number",
            ],
        ),
        (
            "time",
            &[
                "ranges.csv` line 6, column 1 (`time[s]`)",
                "before the previous row's",
            ],
        ),
        (
            "missing",
            &["ranges.csv` line 1", "missing column `beacon`"],
        ),
        (
            "unknown",
            &["ranges.csv` line 1, column 4", "unknown column `snr`"],
        ),
        ("stray", &["range.csv", "its files are"]),
        ("no-such-log", &["no-such-log", "does not exist"]),
    ];
    for (dir, want) in cases {
        usage_error(&root, &["replay", "range-beacon", dir], want);
        usage_error(&root, &["log", "check", dir], want);
    }
    // Nothing was written for a refused log.
    assert!(!root.join("fathom-out/range-beacon-replay").exists());
    // Negative control: the untouched copy replays.
    ok(&root, &["replay", "range-beacon", "good"]);
}

#[test]
fn missing_plaza_folder_is_an_error_not_an_empty_report() {
    let root = scratch("own-logs-plaza-missing");
    let text = std::fs::read_to_string(repo_root().join("scenarios/plaza.toml"))
        .unwrap()
        .replace("dir = \"data/plaza1\"", "dir = \"no/such/plaza\"");
    std::fs::write(root.join("p.toml"), text).unwrap();
    usage_error(&root, &["run", "p.toml", "--out", "o"], &["no/such/plaza"]);
    usage_error(
        &root,
        &["replay", "plaza", "no/such/plaza"],
        &["no/such/plaza"],
    );
    usage_error(
        &root,
        &["log", "from-plaza", "no/such/plaza", "--out", "x"],
        &["no/such/plaza"],
    );
}

#[test]
fn plaza_through_the_layout_gives_the_plaza_numbers() {
    let plaza = repo_root().join("data/plaza1");
    let root = scratch("own-logs-plaza");
    let p = plaza.display().to_string();
    ok(&root, &["log", "from-plaza", &p, "--out", "p-csv"]);
    let config = repo_root().join("scenarios/range-beacon-plaza.toml");
    let own = ok(
        &root,
        &[
            "replay",
            "range-beacon",
            "p-csv",
            "--config",
            config.to_str().unwrap(),
            "--out",
            "o1",
        ],
    );
    let native = ok(&root, &["replay", "plaza", &p, "--out", "o2"]);
    // The same rows (method, mean, std, max, rmse) for every method of the converted
    // log, in the one `summary.json` format both commands write.
    let (a, b) = (summary(&root.join("o1")), summary(&root.join("o2")));
    let mut compared = 0;
    for row in a
        .rows
        .iter()
        .filter(|r| ["mean", "std", "max", "rmse"].contains(&r.metric.as_str()))
    {
        let other = b.row(&row.method, &row.metric).unwrap_or_else(|| {
            panic!(
                "{} {} not in `replay plaza`:\n{native}",
                row.method, row.metric
            )
        });
        let tol = 1e-9 * row.value.abs().max(1e-3);
        assert!(
            (row.value - other.value).abs() <= tol,
            "{} {}: own {} vs native {}\nown:\n{own}\nnative:\n{native}",
            row.method,
            row.metric,
            row.value,
            other.value
        );
        compared += 1;
    }
    assert!(compared >= 16, "{compared} rows compared:\n{own}");
}

/// The own-log replays write through the same safe output folder as `fathom run`: a
/// folder holding the user's file is refused (exit 2, one line naming `--out`, the
/// file and `--force`) and kept; `--force` writes fathom's files beside it; a refused
/// log leaves no temporary folder behind.
#[test]
fn own_log_replay_keeps_a_users_file_in_out() {
    let root = scratch("own-logs-out");
    ok(
        &root,
        &[
            "log",
            "example",
            "range-beacon",
            "--out",
            "rb",
            "--duration",
            "60",
        ],
    );
    std::fs::create_dir_all(root.join("o")).unwrap();
    std::fs::write(root.join("o/notes.md"), "my own notes").unwrap();
    usage_error(
        &root,
        &["replay", "range-beacon", "rb", "--out", "o"],
        &["--out", "notes.md", "--force"],
    );
    let names = |d: &str| -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(root.join(d))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    assert_eq!(names("o"), ["notes.md"]);
    ok(
        &root,
        &["replay", "range-beacon", "rb", "--out", "o", "--force"],
    );
    assert_eq!(read(&root, "o/notes.md"), "my own notes");
    let files = names("o");
    for f in ["report.md", "summary.json", "run_info.json", "notes.md"] {
        assert!(files.iter().any(|x| x == f), "{f} not in {files:?}");
    }
    let info: serde_json::Value =
        serde_json::from_str(&read(&root, "o/run_info.json")).expect("run_info.json");
    assert_eq!(info["command"], "replay", "{info}");
    let listed = info["files"].as_array().expect("files");
    assert!(listed.iter().any(|f| f == "summary.json"), "{info}");
    assert!(!listed.iter().any(|f| f == "notes.md"), "{info}");
    // A second replay without --force is refused again; the user's file survives.
    usage_error(
        &root,
        &["replay", "ins-dvl", "rb", "--out", "o"],
        &["notes.md"],
    );
    assert_eq!(read(&root, "o/notes.md"), "my own notes");
    // A log refused after the claim leaves nothing beside `--out`.
    usage_error(
        &root,
        &["replay", "range-beacon", "no-such-log", "--out", "o2"],
        &["no-such-log"],
    );
    let stray: Vec<String> = names(".")
        .into_iter()
        .filter(|n| n.starts_with(".o2") || n == "o2")
        .collect();
    assert!(stray.is_empty(), "{stray:?}");
}

/// The rows of the results table of `report.md` (`| method | metric | unit | ... |`,
/// the first table after the header, one line per row of `summary.json`).
fn report_rows(report: &str) -> Vec<Vec<String>> {
    report
        .lines()
        .skip_while(|l| !l.starts_with("| method | metric | unit |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            l.trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_string())
                .collect()
        })
        .collect()
}

/// Every replay (`plaza` on the repository's data, `range-beacon` and `ins-dvl` on
/// example logs) writes what `fathom run` writes, through the driver: `summary.json`
/// in the one shared format (every row with a unit in `report.md` and on the
/// console), `report.md` linking the figures, `run_info.json` with command `replay`,
/// the settings as given and resolved, and the figures of every replay: the paths
/// against the truth, the error with 3σ, the innovations and the NIS.
#[test]
fn every_replay_writes_the_outputs_of_a_run() {
    let root = scratch("own-logs-outputs");
    ok(
        &root,
        &[
            "log",
            "example",
            "range-beacon",
            "--out",
            "rb",
            "--duration",
            "60",
        ],
    );
    ok(
        &root,
        &[
            "log",
            "example",
            "ins-dvl",
            "--out",
            "ins",
            "--duration",
            "60",
        ],
    );
    let plaza = repo_root().join("data/plaza1").display().to_string();
    let common = ["estimate_vs_truth.svg", "error_3sigma.svg", "nis.svg"];
    let cases: [(&str, &str, &str, &[&str]); 3] = [
        ("range-beacon", "rb", "o-rb", &["innovations.svg"]),
        (
            "ins-dvl",
            "ins",
            "o-ins",
            &[
                "innovations_north.svg",
                "innovations_east.svg",
                "innovations_down.svg",
            ],
        ),
        ("plaza", &plaza, "o-plaza", &["innovations.svg"]),
    ];
    for (kind, data, out, innovations) in cases {
        let console = ok(&root, &["replay", kind, data, "--out", out]);
        let dir = root.join(out);
        let s = summary(&dir);
        assert_eq!(s.experiment, kind);
        assert!(!s.rows.is_empty(), "{kind}");
        // Every row has a unit, in the report's table and on the console.
        let report = read(&dir, "report.md");
        let rows = report_rows(&report);
        assert_eq!(rows.len(), s.rows.len(), "{kind}:\n{report}");
        for (cells, row) in rows.iter().zip(&s.rows) {
            assert_eq!((&cells[0], &cells[1]), (&row.method, &row.metric), "{kind}");
            assert_ne!(
                cells[2], "-",
                "{kind}: {} / {} has no unit",
                row.method, row.metric
            );
            let (unit, _) = console_row(&console, &row.method, &row.metric)
                .unwrap_or_else(|| panic!("{kind}: {} / {} not printed", row.method, row.metric));
            assert_eq!(unit, cells[2], "{kind}");
        }
        assert!(
            report.contains("one deterministic replay (no Monte Carlo runs, no seed)"),
            "{kind}:\n{report}"
        );
        let info: serde_json::Value =
            serde_json::from_str(&read(&dir, "run_info.json")).expect("run_info.json");
        assert_eq!(info["command"], "replay", "{kind}: {info}");
        assert_eq!(info["experiment"], kind, "{kind}: {info}");
        let listed: Vec<&str> = info["files"]
            .as_array()
            .expect("files")
            .iter()
            .filter_map(|f| f.as_str())
            .collect();
        for f in common.iter().chain(innovations).chain(&[
            "summary.json",
            "report.md",
            "scenario.toml",
            "scenario.resolved.toml",
            "estimates.csv",
        ]) {
            assert!(listed.contains(f), "{kind}: {f} not in {listed:?}");
            assert!(dir.join(f).is_file(), "{kind}: {f} missing");
            if f.ends_with(".svg") {
                assert!(
                    read(&dir, f).trim_start().starts_with("<svg"),
                    "{kind}: {f}"
                );
                assert!(
                    report.contains(&format!("- [{f}]({f})")),
                    "{kind}: {f} not linked"
                );
            }
        }
    }
    // The settings written beside the outputs replay again with `fathom run`, to the
    // same rows.
    let again = ok(&root, &["run", "o-rb/scenario.toml", "--out", "o-rb-again"]);
    assert!(console_row(&again, "AS", "rmse").is_some(), "{again}");
    assert_eq!(
        summary(&root.join("o-rb-again")).rows,
        summary(&root.join("o-rb")).rows
    );
}

/// The example logs the repository keeps in `data/logs` (which the replay presets read)
/// are exactly what their commands write (`data/logs/README.md`): regenerated into a
/// scratch copy of the repository's layout and compared file by file.
#[test]
fn the_repository_logs_are_what_the_commands_write() {
    let root = scratch("own-logs-repository");
    let plaza = root.join("data/plaza1");
    std::fs::create_dir_all(&plaza).unwrap();
    for f in ["Plaza1_DR.txt", "Plaza1_TD.txt", "Plaza1_.mat"] {
        std::fs::copy(repo_root().join("data/plaza1").join(f), plaza.join(f)).unwrap();
    }
    std::fs::create_dir_all(root.join("data/ulog")).unwrap();
    std::fs::copy(
        repo_root().join("data/ulog/sitl_groundtruth.ulg"),
        root.join("data/ulog/sitl_groundtruth.ulg"),
    )
    .unwrap();
    let commands: [(&str, &[&str]); 4] = [
        (
            "range-beacon-example",
            &[
                "log",
                "example",
                "range-beacon",
                "--out",
                "data/logs/range-beacon-example",
            ],
        ),
        (
            "ins-dvl-example",
            &[
                "log",
                "example",
                "ins-dvl",
                "--duration",
                "60",
                "--out",
                "data/logs/ins-dvl-example",
            ],
        ),
        (
            "plaza1-range-beacon",
            &[
                "log",
                "from-plaza",
                "data/plaza1",
                "--out",
                "data/logs/plaza1-range-beacon",
            ],
        ),
        (
            "gnss-ins-sitl",
            &[
                "log",
                "from-ulog",
                "data/ulog/sitl_groundtruth.ulg",
                "--out",
                "data/logs/gnss-ins-sitl",
            ],
        ),
    ];
    for (name, args) in commands {
        ok(&root, args);
        let kept = repo_root().join("data/logs").join(name);
        let made = root.join("data/logs").join(name);
        let files = |d: &Path| -> Vec<String> {
            let mut v: Vec<String> = std::fs::read_dir(d)
                .unwrap()
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        assert_eq!(files(&kept), files(&made), "{name}: file set");
        for f in files(&made) {
            assert!(
                std::fs::read(kept.join(&f)).unwrap() == std::fs::read(made.join(&f)).unwrap(),
                "data/logs/{name}/{f} differs from what `fathom {}` writes: write it again \
                 with that command (data/logs/README.md)",
                args.join(" ")
            );
        }
    }
    // And a fresh clone's replays read them without a folder.
    for (kind, log) in [
        ("range-beacon", "range-beacon-example"),
        ("ins-dvl", "ins-dvl-example"),
        ("gnss-ins", "gnss-ins-sitl"),
    ] {
        let r = fathom(&root, &["replay", kind]);
        assert_eq!(r.code, 0, "{kind}: {r:?}");
        assert!(
            r.stdout.contains(&format!("data/logs/{log}")),
            "{}",
            r.stdout
        );
    }
}
