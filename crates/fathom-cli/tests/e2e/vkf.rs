//! End-to-end: the `vkf` experiment on a shortened mission (400 s, one 100 s
//! interval without bottom lock, 3 runs): every output of the contract is written,
//! rows and claims are present and finite, and results do not depend on the thread
//! count.

use fathom_experiments::registry;
use fathom_report::output::read_summary_json;
use fathom_sim::PaperOptions;
use fathom_sim::driver::run_paper_to;

pub(crate) fn short_scenario() -> String {
    let root = &crate::support::repo_root();
    let text = std::fs::read_to_string(root.join("scenarios/vkf.toml")).unwrap();
    let mut out = String::new();
    let mut skip = false;
    for line in text.lines() {
        if line.starts_with("knots = ") {
            out.push_str(
                "knots = [[0.0, 110.0], [140.0, 110.0], [160.0, 190.0], [240.0, 190.0], \
                 [260.0, 110.0], [400.0, 110.0]]\n",
            );
            skip = true;
            continue;
        }
        if skip {
            if line.trim_start().starts_with('[') && line.trim_end().ends_with("]]") {
                skip = false;
            }
            continue;
        }
        out.push_str(&line.replace("duration_s = 1620.0", "duration_s = 400.0"));
        out.push('\n');
    }
    out
}

/// Runs `text` as the `vkf` preset with 3 runs into a fresh folder; returns the
/// results and the output folder.
fn run_text(
    tag: &str,
    text: &str,
    threads: usize,
) -> (fathom_sim::PaperResult, std::path::PathBuf) {
    let root = std::env::temp_dir().join("fathom-e2e-vkf").join(tag);
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(root.join("scenarios")).unwrap();
    std::fs::write(root.join("scenarios/vkf.toml"), text).unwrap();
    let options = PaperOptions {
        only: Some("vkf".into()),
        runs: Some(3),
        threads: Some(threads),
        workspace_root: root.clone(),
        out_root: root.join("target/paper"),
        force: false,
    };
    let res = run_paper_to(&options, &registry(), &mut Vec::new()).unwrap();
    crate::support::assert_every_row_has_a_unit(&res.experiments[0]);
    (res, root.join("target/paper/vkf"))
}

fn run(tag: &str, threads: usize) -> fathom_report::output::Summary {
    let (res, dir) = run_text(tag, &short_scenario(), threads);
    for f in [
        "summary.json",
        "report.md",
        "fig04_trajectory.svg",
        "fig08_dvl_velocity.svg",
        "fig10_vkf_scale_factor.svg",
        "fig12_trajectories.svg",
        "horizontal_error.svg",
        "mean_horizontal_error.csv",
        "run0_sensors.csv",
    ] {
        assert!(dir.join(f).exists(), "missing {f}");
    }
    assert!(res.experiments[0].figures.len() >= 15);
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(
        report.contains("+-0.5 cm/s"),
        "report must state the DVL-bias reading"
    );
    let summary = read_summary_json(dir.join("summary.json")).unwrap();
    // The literal-bias comparison is chosen by the numbers, not written in.
    let lit = |m: &str| {
        summary
            .row(&format!("{m} [b=0.5 m/s]"), "final_h")
            .unwrap()
            .value
    };
    let word = if lit("VKF") <= lit("INS-DVL") {
        "below"
    } else {
        "above"
    };
    assert!(
        report.contains(&format!("% {word} INS-DVL's")),
        "VKF {} vs INS-DVL {}: {report}",
        lit("VKF"),
        lit("INS-DVL")
    );
    summary
}

#[test]
fn vkf_short_mission_writes_the_contract() {
    let s = run("t2", 2);
    for m in ["PINS", "INS-DVL", "VKF", "INS-DVL-gated", "ESKF"] {
        for metric in ["final_h", "rms_h", "rms_vel"] {
            let row = s.row(m, metric).unwrap_or_else(|| panic!("{m} {metric}"));
            assert!(row.value.is_finite() && row.paper.is_none());
        }
    }
    assert!(s.row("VKF", "sf_error_pct_1").is_some());
    assert!(s.row("VKF", "bias_error_1").is_some());
    let ids: Vec<&str> = s.claims.iter().map(|c| c.id.as_str()).collect();
    assert_eq!(
        ids,
        [
            "vkf_beats_ins_dvl",
            "vkf_beats_pins",
            "ins_dvl_degrades_when_invalid",
            "pins_diverges"
        ]
    );
    // The garbage DVL ruins INS-DVL inside the interval but not the VKF.
    let ins_dvl = s.row("INS-DVL", "final_h").unwrap().value;
    let vkf = s.row("VKF", "final_h").unwrap().value;
    assert!(vkf < ins_dvl, "VKF {vkf} m vs INS-DVL {ins_dvl} m");
    assert_eq!(s, run("t1", 1), "results depend on the thread count");
    methods_select_the_methods_run(&s);
}

/// `methods = ["VKF", "PINS"]` runs the main batch of those two (the ESKF is not
/// computed): their rows equal the full run's bit for bit (same streams), no other
/// method has a row, no claim is made and the report says what was left out.
fn methods_select_the_methods_run(full: &fathom_report::output::Summary) {
    let text =
        short_scenario().replacen("\nruns = ", "\nmethods = [\"VKF\", \"PINS\"]\nruns = ", 1);
    assert!(text.contains("methods = "), "the preset lost its runs line");
    let (res, dir) = run_text("subset", &text, 2);
    let s = &res.experiments[0].summary;
    let methods: std::collections::BTreeSet<&str> =
        s.rows.iter().map(|r| r.method.as_str()).collect();
    assert_eq!(methods.into_iter().collect::<Vec<_>>(), ["PINS", "VKF"]);
    for row in &s.rows {
        assert_eq!(full.row(&row.method, &row.metric), Some(row), "{row:?}");
    }
    assert!(s.claims.is_empty(), "{:?}", s.claims);
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("Selected methods: PINS, VKF"), "{report}");
    assert!(report.contains("literal-bias batch"), "{report}");
    assert!(dir.join("horizontal_error_selected.svg").exists());
    let csv = std::fs::read_to_string(dir.join("mean_horizontal_error.csv")).unwrap();
    assert!(
        csv.starts_with("time_s,pins_mean_err_h_m,vkf_mean_err_h_m\n"),
        "{}",
        &csv[..csv.len().min(200)]
    );
}
