//! End-to-end tests of the `urban` experiment (issue 20): the preset at 2 runs
//! through the paper driver (every row with a CI, the paper column on the paired rows
//! only, every claim, the figures and the report sections), a user's OBJ world with a
//! three-waypoint path through the real `fathom` binary (byte-identical summaries for
//! 1 and 2 threads, another seed changes them), and the user-world errors that must
//! be one-line usage errors (exit 2) naming the file and the problem.

use std::path::Path;

use crate::support::{fathom, preset, read, run_experiment, scratch, write_scenario};

/// The committed test world (east-north-up metres; one building beside the path).
const BLOCK_OBJ: &str = "scenarios/worlds/urban_block.obj";

/// The preset's methods.
pub(crate) const METHODS: [&str; 6] = [
    "INS-only",
    "GPS/INS",
    "GPS/INS-all-sats",
    "GREKF",
    "MGPMF",
    "PF",
];
const METRICS: [&str; 10] = [
    "rmse_h",
    "rmse_3d",
    "rmse_vel",
    "rmse_roll",
    "rmse_pitch",
    "rmse_yaw",
    "mean_3d",
    "p95_3d",
    "time_map_aided_s",
    "nees_mean",
];

fn row<'a>(rows: &'a [serde_json::Value], method: &str, metric: &str) -> &'a serde_json::Value {
    rows.iter()
        .find(|r| r["method"] == method && r["metric"] == metric)
        .unwrap_or_else(|| panic!("row {method} {metric} missing"))
}

/// The preset cut to 2 runs (ablations 2 runs): rows, paper column, claims, figures,
/// report sections.
#[test]
fn preset_rows_claims_figures_and_report() {
    let dir = scratch("urban-preset");
    let text = preset("urban.toml")
        .replace("runs = 50 ", "runs = 2 ")
        .replace("runs = 20", "runs = 2");
    assert!(text.contains("runs = 2 "), "preset's run count line moved");
    write_scenario(&dir, "urban.toml", &text);
    run_experiment(&dir, "urban", Some(2)).unwrap();
    let out = dir.join("out").join("urban");
    let summary: serde_json::Value = serde_json::from_str(&read(&out, "summary.json")).unwrap();
    let rows = summary["rows"].as_array().unwrap();
    for scene in ["bridge", "buildings"] {
        for m in METHODS {
            for metric in METRICS {
                let r = row(rows, &format!("{scene}/{m}"), metric);
                assert!(r["value"].as_f64().unwrap().is_finite(), "{r}");
                assert_eq!(r["ci95"].as_array().map(Vec::len), Some(2), "{r}");
                let paired = (scene == "bridge" && m == "GREKF" && metric == "rmse_3d")
                    || (scene == "buildings"
                        && m == "MGPMF"
                        && !matches!(metric, "time_map_aided_s" | "nees_mean"));
                assert_eq!(!r["paper"].is_null(), paired, "{r}");
            }
        }
    }
    assert_eq!(row(rows, "bridge/GREKF", "rmse_3d")["paper"], 0.2972);
    assert_eq!(row(rows, "buildings/MGPMF", "rmse_yaw")["paper"], 2.763);
    assert_eq!(row(rows, "buildings/MGPMF", "p95_3d")["paper"], 2.12);
    // the swapped pairings and the ablations are rows too
    row(rows, "bridge/MGPMF", "rmse_3d");
    row(rows, "buildings/GREKF", "rmse_3d");
    row(
        rows,
        "buildings/MGPMF@glass_incidence-vs-main",
        "diff_rmse_3d",
    );
    row(rows, "bridge/GREKF@lidar_step_0.25deg", "rmse_3d");
    row(rows, "buildings/MGPMF@control_on_estimate", "rmse_3d");
    // open sky: GPS/INS against INS-only where the sky is open (paired, signed)
    for scene in ["bridge", "buildings"] {
        row(rows, &format!("{scene}/GPS/INS"), "rmse_3d_open");
        let d = row(
            rows,
            &format!("{scene}/GPS/INS-vs-INS-only"),
            "diff_rmse_3d_open",
        );
        assert_eq!(d["ci_method"], "student-t", "{d}");
        row(rows, &format!("{scene}/GPS/INS"), "gps_reacquired");
    }
    // issue 33: the flights switch; the switching rows have their fixed names
    for scene in ["bridge", "buildings"] {
        let used = row(rows, &format!("{scene}/GNSS"), "satellites_used");
        assert_eq!(used["value"].as_f64(), Some(9.0), "{used}");
        for m in METHODS {
            let name = format!("{scene}/{m}");
            let beyond = row(rows, &name, "runs_beyond_1m")["value"]
                .as_f64()
                .unwrap();
            assert!((0.0..=2.0).contains(&beyond), "{name}: {beyond}");
            if matches!(m, "GREKF" | "MGPMF" | "PF") {
                row(rows, &name, "switches");
                let fewest = row(rows, &name, "switches_min")["value"].as_f64().unwrap();
                assert!(fewest >= 2.0, "{name} switched {fewest} times in a run");
                let map_s = row(rows, &name, "time_map_aided_s")["value"]
                    .as_f64()
                    .unwrap();
                let gps_s = row(rows, &name, "time_gps_ins_s")["value"]
                    .as_f64()
                    .unwrap();
                assert!(
                    map_s > 10.0 && gps_s > 10.0,
                    "{name}: {map_s} s / {gps_s} s"
                );
            }
        }
    }
    let per_run = read(&out, "per_run.csv");
    let header = per_run.lines().next().unwrap();
    for col in [
        "switches",
        "lost_lock",
        "relocks",
        "map_left_out",
        "gps_reacquired",
    ] {
        assert!(
            header.split(',').any(|h| h == col),
            "per_run.csv lacks {col}"
        );
    }
    let claims: Vec<&str> = summary["claims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["id"].as_str().unwrap())
        .collect();
    for id in [
        "grekf_bridge_rms_le_0_3",
        "grekf_bridge_att_lt_0_5",
        "mgpmf_buildings_table2",
        "mgpmf_buildings_table2_rmse_h",
        "los_check_improves_gps",
        "map_aided_beats_ins_only",
        "gps_ins_beats_ins_only_in_open_sky",
        "mgpmf_beats_grekf_near_walls",
    ] {
        assert!(claims.contains(&id), "claim {id} missing: {claims:?}");
    }
    for fig in [
        "world_plan_bridge.svg",
        "world_side_bridge.svg",
        "estimate_buildings_mgpmf.svg",
        "errors_pos_buildings.svg",
        "errors_att_bridge.svg",
        "los_satellites_buildings.svg",
        "scan_bridge.svg",
        "mgpmf_grid_buildings.svg",
        "histogram_bridge_grekf.svg",
    ] {
        let svg = read(&out, fig);
        assert!(svg.contains("<svg"), "{fig}");
    }
    let report = read(&out, "report.md");
    for section in [
        "## Results: bridge",
        "Paper against this run",
        "## Claims",
        "## Ablations",
        "## Spread over runs",
        "eq. (7), (9)",
        "eq. (21)/(22)",
        "## Settings the paper does not give",
        "switch.min_los_satellites",
        "## Mode switching",
        "## Consistency (NEES)",
    ] {
        assert!(report.contains(section), "report lacks `{section}`");
    }
}

/// The preset's shared sections with `body` as the only scenario and no
/// `[ablations]` table (optional in a user's file).
fn user_scenario(body: &str) -> String {
    let text = preset("urban.toml").replace("runs = 50 ", "runs = 2 ");
    let head = text.split("[[scenarios]]").next().unwrap();
    assert!(
        !head.contains("[ablations]"),
        "the ablations follow the scenarios"
    );
    format!("{head}\n{body}\n")
}

pub(crate) fn block(world: &str, waypoints: &str) -> String {
    user_scenario(&format!(
        "[[scenarios]]\nname = \"block\"\nranging = \"rangefinders\"\n\n\
         [scenarios.world]\nfile = \"{world}\"\naxes = \"enu_z_up\"\n\n\
         [scenarios.path]\nwaypoints = {waypoints}\nstart_height_m = 0.5\n"
    ))
}

/// Rest at the first waypoint, climb to 10 m, fly 60 m north past the building.
pub(crate) const GOOD_PATH: &str = "[[0.0, -30.0, 0.5], [0.0, -30.0, 10.0], [0.0, 30.0, 10.0]]";

pub(crate) fn setup(dir: &Path) {
    let world = std::fs::read(crate::support::repo_root().join(BLOCK_OBJ)).unwrap();
    std::fs::write(dir.join("block.obj"), world).unwrap();
    std::fs::write(dir.join("empty.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
}

/// A user's OBJ world flown through processor-in-the-loop (`fathom pils FILE`, two
/// processes, lockstep) with every method: each session equals the offline run fed
/// the same MAVLink-quantized measurements, byte for byte.
#[test]
fn user_obj_world_flies_through_pils_equal_to_offline_quantized() {
    let dir = scratch("urban-obj-pils");
    setup(&dir);
    std::fs::write(dir.join("u.toml"), block("block.obj", GOOD_PATH)).unwrap();
    for method in METHODS {
        let out = method.replace('/', "_");
        let r = fathom(&dir, &["pils", "u.toml", "--method", method, "--out", &out]);
        assert_eq!(r.code, 0, "{method}: {}{}", r.stdout, r.stderr);
        let sim: serde_json::Value =
            serde_json::from_str(&read(&dir, &format!("{out}/sim/pils.json"))).unwrap();
        assert_eq!(sim["equal_to_offline_quantized"], true, "{method}");
        assert_eq!(
            (sim["scenario"].as_str(), sim["method"].as_str()),
            (Some("block"), Some(method))
        );
        let q = format!("{out}-q");
        let r = fathom(
            &dir,
            &[
                "pils",
                "offline",
                "u.toml",
                "--method",
                method,
                "--quantized",
                "--out",
                &q,
            ],
        );
        assert_eq!(r.code, 0, "{method}: {}", r.stderr);
        assert!(
            read(&dir, &format!("{out}/sim/solutions.csv"))
                == read(&dir, &format!("{q}/solutions.csv")),
            "{method}: PILS != offline quantized"
        );
    }
}

/// A user's OBJ world and a three-waypoint path run end to end; the summary is
/// byte-identical for 1 and 2 threads, and another seed changes it.
#[test]
fn user_obj_world_runs_end_to_end() {
    let dir = scratch("urban-obj");
    setup(&dir);
    std::fs::write(dir.join("u.toml"), block("block.obj", GOOD_PATH)).unwrap();
    let check = fathom(&dir, &["check", "u.toml"]);
    assert_eq!(check.code, 0, "{check:?}");
    let mut summaries = Vec::new();
    for (out, threads, seed) in [("o1", "1", "7"), ("o2", "2", "7"), ("o3", "2", "8")] {
        let ran = fathom(
            &dir,
            &[
                "run",
                "u.toml",
                "--out",
                out,
                "--threads",
                threads,
                "--seed",
                seed,
            ],
        );
        assert_eq!(ran.code, 0, "{ran:?}");
        summaries.push(std::fs::read(dir.join(out).join("summary.json")).unwrap());
    }
    assert_eq!(summaries[0], summaries[1], "1 vs 2 threads differ");
    assert_ne!(
        summaries[0], summaries[2],
        "another seed gave the same summary"
    );
    let summary: serde_json::Value =
        serde_json::from_str(std::str::from_utf8(&summaries[0]).unwrap()).unwrap();
    let rows = summary["rows"].as_array().unwrap();
    for m in METHODS {
        let r = row(rows, &format!("block/{m}"), "rmse_3d");
        assert!(r["value"].as_f64().unwrap().is_finite(), "{r}");
        assert!(r["paper"].is_null(), "{r}");
    }
    // issue 33: whether the map-aided filter ran follows the switches, and a world
    // where nothing switched is said so in words
    let value = |metric: &str| row(rows, "block/MGPMF", metric)["value"].as_f64().unwrap();
    let report = std::fs::read_to_string(dir.join("o1").join("report.md")).unwrap();
    let none = "In `block` no switching method switched in any run";
    if value("switches") == 0.0 {
        assert!(report.contains(none), "no switching, not said so");
        assert_eq!(value("switches_min"), 0.0);
    } else {
        assert!(!report.contains(none));
        assert!(value("time_map_aided_s") > 0.0);
    }
    assert!(dir.join("o1").join("world_plan_block.svg").exists());
    methods_select_the_methods_run(&dir, rows);
}

/// `methods = ["MGPMF", "INS-only"]`: only those run; their rows equal the full
/// run's (`rows`, same seed) bit for bit, no other method has a row, no claim is
/// made and the report says why; `fathom list` names what `urban` accepts.
fn methods_select_the_methods_run(dir: &Path, full: &[serde_json::Value]) {
    let text = block("block.obj", GOOD_PATH).replacen(
        "\nruns = 2 ",
        "\nmethods = [\"MGPMF\", \"INS-only\"]\nruns = 2 ",
        1,
    );
    assert!(text.contains("methods = "), "the preset's runs line moved");
    std::fs::write(dir.join("two.toml"), text).unwrap();
    let ran = fathom(
        dir,
        &[
            "run",
            "two.toml",
            "--out",
            "two",
            "--threads",
            "2",
            "--seed",
            "7",
        ],
    );
    assert_eq!(ran.code, 0, "{ran:?}");
    let summary: serde_json::Value =
        serde_json::from_str(&read(&dir.join("two"), "summary.json")).unwrap();
    let rows = summary["rows"].as_array().unwrap();
    let methods: std::collections::BTreeSet<&str> =
        rows.iter().map(|r| r["method"].as_str().unwrap()).collect();
    assert_eq!(
        methods.into_iter().collect::<Vec<_>>(),
        [
            "block/GNSS",
            "block/INS-only",
            "block/MGPMF",
            // The paired difference of two selected methods stays.
            "block/MGPMF-vs-INS-only"
        ]
    );
    for r in rows {
        assert_eq!(
            r,
            row(
                full,
                r["method"].as_str().unwrap(),
                r["metric"].as_str().unwrap()
            )
        );
    }
    assert_eq!(
        summary["claims"].as_array().map_or(0, Vec::len),
        0,
        "{summary}"
    );
    // A user's world is reported as theirs: no claims section, none of the paper's
    // numbers or errata.
    let report = read(&dir.join("two"), "report.md");
    assert!(
        report.contains("Not judged: they are about the paper's own setup")
            && !report.contains("inconsistencies found on the way")
            && !report.contains("Paper against this run"),
        "{report}"
    );
    assert!(!report.contains("| GREKF"), "{report}");
    let csv = read(&dir.join("two"), "mean_errors_block.csv");
    assert!(
        csv.starts_with("time_s,ins_only_err_3d_m,"),
        "{}",
        &csv[..80.min(csv.len())]
    );
    assert!(!csv.lines().next().unwrap().contains("grekf"));
    let list = fathom(dir, &["list"]);
    for w in ["\"GPS/INS-all-sats\"", "\"INS-DVL-gated\""] {
        assert!(list.stdout.contains(w), "{w}: {}", list.stdout);
    }
}

/// Path through the building, a waypoint outside the mesh, an OBJ without faces, a
/// missing file: exit 2 and one line naming the file and the problem, from `run` and
/// from `check` alike.
#[test]
fn bad_user_worlds_are_one_line_usage_errors() {
    let dir = scratch("urban-obj-bad");
    setup(&dir);
    let cases = [
        (
            "wall.toml",
            block(
                "block.obj",
                "[[0.0, -30.0, 0.5], [0.0, -30.0, 10.0], [20.0, 30.0, 10.0]]",
            ),
            "passes through",
            "block.obj",
        ),
        (
            "outside.toml",
            block("block.obj", "[[0.0, -30.0, 0.5], [0.0, -300.0, 10.0]]"),
            "outside the bounds",
            "block.obj",
        ),
        (
            "empty.toml",
            block("empty.obj", GOOD_PATH),
            "no faces",
            "empty.obj",
        ),
        (
            "missing.toml",
            block("nope.obj", GOOD_PATH),
            "cannot read",
            "nope.obj",
        ),
    ];
    for (file, text, problem, world) in cases {
        std::fs::write(dir.join(file), text).unwrap();
        let ran = fathom(&dir, &["run", file, "--out", "o"]);
        assert_eq!(ran.code, 2, "{file}: {ran:?}");
        let msg = ran.stderr.trim();
        assert_eq!(msg.lines().count(), 1, "{file}: {msg}");
        assert!(
            msg.contains(problem) && msg.contains(world),
            "{file}: {msg}"
        );
        assert!(msg.contains(file), "{file}: {msg}");
        // `check` loads the world as `run` does: the same exit code and message.
        let checked = fathom(&dir, &["check", file]);
        assert_eq!(
            (checked.code, checked.stderr.trim()),
            (2, msg),
            "{file}: check {checked:?}"
        );
    }
}
