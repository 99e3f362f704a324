//! Processor-in-the-loop (issues 21, 34): `fathom pils` flies an `urban` scenario as
//! two real processes on loopback. Lockstep equals the offline run fed the same
//! MAVLink-quantized data, bit for bit, also with junk from a foreign address and
//! with link faults; two processes started for different methods refuse to run; a
//! killed peer ends the other side with a non-zero exit within the timeout.

use std::io::{BufRead, BufReader};
use std::net::{SocketAddr, UdpSocket};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::support::{fathom, fathom_bin, preset, scratch};

/// The `urban` preset with a short bridge (`deck_m` long, `margin_m` of ground around
/// it), 2 s of rest, 0.5 s hovers and base seed 3.
pub(crate) fn short_urban(deck_m: f64, margin_m: f64) -> String {
    let text = preset("urban.toml")
        .replace("base_seed = 4 ", "base_seed = 3 ")
        .replace("rest_s = 10.0 ", "rest_s = 2.0 ")
        .replace("hover_s = 3.0 ", "hover_s = 0.5 ")
        .replace(
            "deck_length_m = 200.0",
            &format!("deck_length_m = {deck_m:.1}"),
        )
        .replace(
            "ground_margin_m = 100.0\npath_height_m = 5.0",
            &format!("ground_margin_m = {margin_m:.1}\npath_height_m = 5.0"),
        );
    for line in [
        "base_seed = 3 ",
        "rest_s = 2.0 ",
        "hover_s = 0.5 ",
        "deck_length_m = ",
    ] {
        assert!(text.contains(line), "the preset's `{line}` line moved");
    }
    assert!(text.contains(&format!("ground_margin_m = {margin_m:.1}\npath_height_m")));
    text
}

/// A scratch folder holding `urban.toml`, a short bridge flight (a 40 m deck and 16 m
/// of open sky each side: about 30 s simulated).
fn pils_dir(test: &str) -> std::path::PathBuf {
    let dir = scratch(test);
    std::fs::write(dir.join("urban.toml"), short_urban(40.0, 20.0)).unwrap();
    dir
}

/// PILS settings flying `urban.toml`'s bridge with the GREKF, with `link` settings.
fn settings(link: &str) -> String {
    format!(
        "experiment = \"pils\"\nscenario = \"urban.toml\"\nscene = \"bridge\"\nmethod = \"GREKF\"\n\
         [link]\ntimeout_s = 3.0\nretransmit_s = 0.02\n{link}"
    )
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// The offline run with the MAVLink quantization, through the binary.
fn offline_quantized(dir: &Path, file: &str) -> String {
    let r = fathom(dir, &["pils", "offline", file, "--quantized", "--out", "q"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    std::fs::read_to_string(dir.join("q/solutions.csv")).unwrap()
}

#[test]
fn lockstep_two_processes_equal_offline_quantized_run_despite_foreign_junk() {
    let dir = pils_dir("pils-lockstep");
    std::fs::write(dir.join("pils.toml"), settings("")).unwrap();
    // The two sides started by hand, so that the junk is all in before the run (a
    // lockstep session of this flight takes a fraction of a second): the simulator on
    // a port picked here, the navigation told to take frames from it only.
    let sim_addr = UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap();
    let (nav_child, nav) = spawn_nav(&dir, &["--sim", &sim_addr.to_string(), "--out", "out/nav"]);
    // Junk from another address: random bytes, a truncated and a complete-looking
    // MAVLink 2 frame. The navigation drops and counts all of it.
    let junk = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut sent = 0u64;
    for i in 0u8..100 {
        let mut frame = vec![0xFD, 9, 0, 0, i, 1, 1, 0, 0, 0];
        frame.extend((0..11).map(|j| i.wrapping_mul(31).wrapping_add(j)));
        let d: &[u8] = match i % 3 {
            0 => &frame[..],
            1 => &frame[..6],
            _ => &frame[3..],
        };
        if junk.send_to(d, nav).is_ok() {
            sent += 1;
        }
    }
    let r = run_sim(
        &dir,
        nav,
        &["--bind", &sim_addr.to_string(), "--out", "out/sim"],
    );
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    let nav_out = nav_child.wait_with_output().unwrap();
    assert!(
        nav_out.status.success(),
        "{}",
        String::from_utf8_lossy(&nav_out.stderr)
    );
    assert!(
        r.stdout
            .contains("equal to the offline run with MAVLink quantization: true"),
        "{}",
        r.stdout
    );
    let sim = json(&dir.join("out/sim/pils.json"));
    assert_eq!(sim["status"], "ok");
    assert_eq!(sim["equal_to_offline_quantized"], true);
    assert_eq!(sim["steps_sent"], sim["steps_total"]);
    assert!(
        sim["solutions"].as_u64().unwrap() > 2000,
        "{}",
        sim["solutions"]
    );
    assert!(sim["latency"]["p50_ms"].as_f64().unwrap() > 0.0);
    assert!(sim["real_time_factor"].as_f64().unwrap() > 0.0);
    let nav_report = json(&dir.join("out/nav/nav.json"));
    assert_eq!(nav_report["status"], "ok");
    let foreign = nav_report["link"]["dropped"]["foreign_address"]
        .as_u64()
        .unwrap_or(0);
    assert_eq!(
        foreign, sent,
        "every foreign datagram is counted and dropped"
    );
    // Independently: the simulator's decoded solutions are the offline ones.
    let pils_csv = std::fs::read_to_string(dir.join("out/sim/solutions.csv")).unwrap();
    assert_eq!(pils_csv, offline_quantized(&dir, "pils.toml"));
    // summary.json is the shared contract: the reader of every job's summary reads it,
    // with the settings' seed as `base_seed` and the session's facts as extra keys.
    let summary = fathom_report::output::read_summary_json(dir.join("out/sim/summary.json"))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((summary.runs, summary.base_seed), (1, 3));
    assert!(summary.row("pils/bridge/GREKF", "rmse_3d").is_some());
    assert!(
        summary
            .row("offline_quantized/bridge/GREKF", "rmse_3d")
            .is_some()
    );
    assert_eq!(summary.extra["method"], "GREKF");
    assert_eq!(summary.extra["scenario"], "bridge");
    assert_eq!(summary.extra["equal_to_offline_quantized"], true);
    assert_eq!(summary.extra["pacing"], "lockstep");
}

#[test]
fn lockstep_over_faulty_signed_link_is_unchanged_and_counts_everything() {
    let dir = pils_dir("pils-faults");
    let faults = "signing_passphrase = \"shared\"\n[link.faults]\nloss = 0.05\nreorder = 0.05\n\
                  duplicate = 0.05\ncorrupt = 0.05\njunk = 0.05\nlatency_s = 0.0005\njitter_s = 0.0002\n";
    // a 5 ms retransmission: a lost step costs 5 ms, not 20 (the answers take well
    // under 1 ms on loopback); the session is the same, whatever the timing
    std::fs::write(
        dir.join("pils.toml"),
        settings(faults).replace("retransmit_s = 0.02", "retransmit_s = 0.005"),
    )
    .unwrap();
    let r = fathom(&dir, &["pils", "pils.toml", "--out", "out"]);
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    let sim = json(&dir.join("out/sim/pils.json"));
    assert_eq!(sim["status"], "ok");
    assert_eq!(sim["equal_to_offline_quantized"], true);
    assert!(sim["retransmissions"].as_u64().unwrap() > 0);
    let nav = json(&dir.join("out/nav/nav.json"));
    let dropped = &nav["link"]["dropped"];
    for why in ["bad_crc", "stale"] {
        assert!(dropped[why].as_u64().unwrap_or(0) > 0, "{why}: {dropped}");
    }
    assert!(sim["link"]["datagrams_lost_injected"].as_u64().unwrap() > 0);
    assert!(sim["link"]["junk_sent"].as_u64().unwrap() > 0);
    // The same result as the clean link: the offline quantized run.
    let csv = std::fs::read_to_string(dir.join("out/sim/solutions.csv")).unwrap();
    assert_eq!(csv, offline_quantized(&dir, "pils.toml"));
    // Negative control: a navigation with another key accepts nothing, and the
    // simulator gives up after the timeout with a non-zero exit.
    std::fs::write(
        dir.join("other.toml"),
        settings(&faults.replace("shared", "other")).replace("timeout_s = 3.0", "timeout_s = 6.0"),
    )
    .unwrap();
    let mut nav = Command::new(fathom_bin())
        .args(["pils", "nav", "other.toml", "--out", "nav2"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let addr = first_addr(&mut nav);
    let r = run_sim(&dir, addr, &["--out", "sim2"]);
    assert_ne!(r.code, 0);
    assert!(r.stderr.contains("silent"), "{}", r.stderr);
    let _ = nav.wait();
    let nav2 = json(&dir.join("nav2/nav.json"));
    assert!(
        nav2["link"]["dropped"]["bad_signature"]
            .as_u64()
            .unwrap_or(0)
            > 0,
        "{nav2}"
    );
}

/// Two processes started by hand for different methods: the navigation hears what
/// the simulator flies before it starts and refuses with one line naming both; the
/// simulator ends with the navigation silent. Nothing is labelled with the wrong
/// method.
#[test]
fn separate_processes_with_different_methods_refuse_to_run() {
    let dir = pils_dir("pils-mismatch");
    std::fs::write(
        dir.join("pils.toml"),
        settings("").replace("timeout_s = 3.0", "timeout_s = 1.0"),
    )
    .unwrap();
    let (nav, addr) = spawn_nav(&dir, &["--method", "MGPMF", "--out", "nav"]);
    let r = run_sim(&dir, addr, &["--out", "sim"]);
    assert_ne!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains("silent"), "{}", r.stderr);
    let out = nav.wait_with_output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bridge/GREKF") && err.contains("bridge/MGPMF"),
        "{err}"
    );
    let n = json(&dir.join("nav/nav.json"));
    assert_eq!(n["method"], "MGPMF");
    assert_eq!(n["solutions"], 0, "{n}");
}

/// `fathom pils nav pils.toml ARGS` in `dir` (stdout and stderr piped) and the
/// address it listens on.
fn spawn_nav(dir: &Path, args: &[&str]) -> (Child, SocketAddr) {
    let mut nav = Command::new(fathom_bin())
        .args(["pils", "nav", "pils.toml"])
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let addr = first_addr(&mut nav);
    (nav, addr)
}

/// `fathom pils sim pils.toml --nav NAV ARGS` in `dir`, to its end.
fn run_sim(dir: &Path, nav: SocketAddr, args: &[&str]) -> crate::support::Ran {
    let nav = nav.to_string();
    let mut all = vec!["pils", "sim", "pils.toml", "--nav", &nav];
    all.extend_from_slice(args);
    fathom(dir, &all)
}

/// The address a `fathom pils nav` prints on its first line.
fn first_addr(nav: &mut Child) -> SocketAddr {
    let mut line = String::new();
    let mut reader = BufReader::new(nav.stdout.take().unwrap());
    reader.read_line(&mut line).unwrap();
    // Keep the pipe open (a later line must not hit a closed pipe).
    std::thread::spawn(move || std::io::copy(&mut reader, &mut std::io::sink()));
    line.trim()
        .rsplit(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap_or_else(|_| panic!("{line}"))
}

/// After 4 s of a run, kills `victim`; `survivor` must exit non-zero within `limit`
/// with its report (`report`, written on the way out) saying `status`.
fn kill_and_expect_exit(
    victim: &mut Child,
    survivor: &mut Child,
    limit: Duration,
    report: &Path,
    status: &str,
) -> serde_json::Value {
    std::thread::sleep(Duration::from_secs(4));
    assert!(
        survivor.try_wait().unwrap().is_none(),
        "the run should still be going"
    );
    victim.kill().unwrap();
    let _ = victim.wait();
    let code = wait_for(survivor, limit);
    assert!(matches!(code, Some(c) if c != 0), "survivor: {code:?}");
    let r = json(report);
    assert!(
        r["status"].as_str().unwrap().contains(status),
        "{}",
        r["status"]
    );
    r
}

/// Waits for `child` at most `limit`; its exit code (`None`: still running).
fn wait_for(child: &mut Child, limit: Duration) -> Option<i32> {
    let t0 = Instant::now();
    while t0.elapsed() < limit {
        if let Some(s) = child.try_wait().unwrap() {
            return Some(s.code().unwrap_or(-1));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    None
}

#[test]
fn a_killed_peer_ends_the_other_side_within_the_timeout_with_outputs() {
    let dir = pils_dir("pils-kill");
    // Real-time pacing: the run lasts ~35 s of wall time, long enough to kill.
    std::fs::write(
        dir.join("pils.toml"),
        settings("pacing = \"realtime\"\n").replace("timeout_s = 3.0", "timeout_s = 1.0"),
    )
    .unwrap();
    let spawn_nav = |out: &str| {
        Command::new(fathom_bin())
            .args(["pils", "nav", "pils.toml", "--out", out])
            .current_dir(&dir)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap()
    };
    let spawn_sim = |addr: SocketAddr, out: &str| {
        Command::new(fathom_bin())
            .args([
                "pils",
                "sim",
                "pils.toml",
                "--nav",
                &addr.to_string(),
                "--out",
                out,
            ])
            .current_dir(&dir)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap()
    };
    // Kill the navigation: the simulator exits non-zero within the timeout.
    let mut nav = spawn_nav("nav1");
    let addr = first_addr(&mut nav);
    let mut sim = spawn_sim(addr, "sim1");
    let report = kill_and_expect_exit(
        &mut nav,
        &mut sim,
        Duration::from_secs(5),
        &dir.join("sim1/pils.json"),
        "navigation silent",
    );
    assert!(report["solutions"].as_u64().unwrap() > 0);
    // Kill the simulator: the navigation exits non-zero within the timeout.
    let mut nav = spawn_nav("nav2");
    let addr = first_addr(&mut nav);
    let mut sim = spawn_sim(addr, "sim2");
    kill_and_expect_exit(
        &mut sim,
        &mut nav,
        Duration::from_secs(4),
        &dir.join("nav2/nav.json"),
        "simulator silent",
    );
}

/// `fathom pils compare`: two runs of a very short flight, each in lockstep and in
/// real time with loss and latency; the per-run table, the paired difference with
/// its interval and the figures are written, and the realtime sessions count their
/// late solutions (20 ms one-way latency: every answer is later than one 10 ms step).
#[test]
fn compare_writes_per_run_table_and_paired_interval() {
    let dir = pils_dir("pils-compare");
    std::fs::write(dir.join("urban.toml"), short_urban(20.0, 10.0)).unwrap();
    let file = settings(
        "pacing = \"realtime\"\n[link.faults]\nloss = 0.05\nlatency_s = 0.02\njitter_s = 0.01\n",
    );
    std::fs::write(dir.join("rt.toml"), file).unwrap();
    let r = fathom(&dir, &["pils", "compare", "rt.toml", "--runs", "2"]);
    // Without `--out`: the one default place, `fathom-out/pils-compare`.
    let cmp = dir.join("fathom-out/pils-compare");
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    assert!(
        r.stdout.contains("realtime - lockstep (paired)"),
        "{}",
        r.stdout
    );
    let c = json(&cmp.join("comparison.json"));
    let runs = c["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    for run in runs {
        assert_eq!(run["lockstep_equal_offline"], true, "{run}");
        assert!(run["realtime_late"].as_u64().unwrap() > 0, "{run}");
        assert!(run["realtime_solutions"].as_u64().unwrap() > 0, "{run}");
    }
    let m = c["metrics"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["metric"] == "rmse_3d")
        .unwrap();
    let d = &m["difference"];
    let mean = d["mean"].as_f64().unwrap();
    let ci: Vec<f64> = d["ci95"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(ci[0] < mean && mean < ci[1], "{d}");
    // The paired mean is the mean of the per-run differences.
    let diff: f64 = runs
        .iter()
        .map(|r| {
            r["realtime"]["rmse_3d"].as_f64().unwrap() - r["lockstep"]["rmse_3d"].as_f64().unwrap()
        })
        .sum::<f64>()
        / 2.0;
    assert!((diff - mean).abs() < 1e-12, "{diff} {mean}");
    let summary = json(&cmp.join("summary.json"));
    assert!(
        summary["rows"]
            .as_array()
            .unwrap()
            .iter()
            .any(|r| r["method"] == "realtime-lockstep/bridge/GREKF" && r["metric"] == "rmse_3d")
    );
    assert_eq!(
        std::fs::read_to_string(cmp.join("runs.csv"))
            .unwrap()
            .lines()
            .count(),
        3
    );
    for f in [
        "report.md",
        "rmse_3d_per_run.svg",
        "error_3d_lockstep_vs_realtime.svg",
        "latency_realtime.svg",
        "run000_realtime/sim/pils.json",
        "run001_lockstep/nav/nav.json",
        "run000_lockstep/sim/error_3d.svg",
        "run_info.json",
    ] {
        assert!(cmp.join(f).is_file(), "{f}");
    }
}

/// A bad settings file is one usage error before any process starts; an output
/// folder holding a file fathom did not write is refused (exit 2) before the run,
/// and with `--force` the file is kept.
#[test]
fn bad_settings_and_foreign_output_folder_are_refused_before_the_run() {
    let dir = pils_dir("pils-refuse");
    for (bad, key) in [
        (settings("").replace("\"GREKF\"", "\"EKF\""), "method"),
        (settings("").replace("\"bridge\"", "\"tunnel\""), "scene"),
        (
            settings("").replace("urban.toml", "nowhere.toml"),
            "nowhere.toml",
        ),
        (
            settings("timeout_s = 0.0\n").replace("timeout_s = 3.0\n", ""),
            "link.timeout_s",
        ),
    ] {
        std::fs::write(dir.join("bad.toml"), bad).unwrap();
        let r = fathom(&dir, &["pils", "bad.toml", "--out", "out"]);
        assert_eq!(r.code, 2, "{}", r.stderr);
        assert_eq!(r.stderr.trim().lines().count(), 1, "{}", r.stderr);
        assert!(r.stderr.contains(key), "{key}: {}", r.stderr);
        assert!(!dir.join("out").exists());
    }
    std::fs::write(dir.join("pils.toml"), settings("")).unwrap();
    std::fs::create_dir_all(dir.join("out")).unwrap();
    std::fs::write(dir.join("out/mine.txt"), "keep").unwrap();
    for args in [
        &["pils", "pils.toml", "--out", "out"][..],
        &[
            "pils",
            "sim",
            "pils.toml",
            "--nav",
            "127.0.0.1:9",
            "--out",
            "out",
        ][..],
        &[
            "pils",
            "compare",
            "pils.toml",
            "--runs",
            "2",
            "--out",
            "out",
        ][..],
    ] {
        let r = fathom(&dir, args);
        assert_eq!(r.code, 2, "{args:?}: {}", r.stderr);
        assert!(r.stderr.contains("--out"), "{}", r.stderr);
        assert!(!dir.join("out/sim").exists());
    }
    assert_eq!(
        std::fs::read_to_string(dir.join("out/mine.txt")).unwrap(),
        "keep"
    );
}

/// A `--nav` address nobody can be at, an empty signing passphrase and an `--out`
/// that cannot be made are refused with exit 2 naming the flag or key, before any
/// socket and before the run.
#[test]
fn bad_flags_and_empty_passphrase_are_refused_before_the_run() {
    let dir = pils_dir("pils-flags");
    std::fs::write(dir.join("pils.toml"), settings("")).unwrap();
    for nav in ["127.0.0.1:0", "0.0.0.0:14550"] {
        let r = fathom(
            &dir,
            &["pils", "sim", "pils.toml", "--nav", nav, "--out", "o"],
        );
        assert_eq!(r.code, 2, "{nav}: {}", r.stderr);
        assert_eq!(r.stderr.trim().lines().count(), 1, "{}", r.stderr);
        assert!(r.stderr.contains(&format!("--nav {nav}")), "{}", r.stderr);
        assert!(!dir.join("o").exists());
    }
    std::fs::write(
        dir.join("empty-key.toml"),
        settings("signing_passphrase = \"\"\n"),
    )
    .unwrap();
    for args in [
        &["check", "empty-key.toml"][..],
        &["pils", "empty-key.toml", "--out", "o"][..],
    ] {
        let r = fathom(&dir, args);
        assert_eq!(r.code, 2, "{args:?}: {}", r.stderr);
        assert!(
            r.stderr.contains("link.signing_passphrase"),
            "{args:?}: {}",
            r.stderr
        );
        assert!(!dir.join("o").exists());
    }
    // `--out` under a regular file: refused (before the run: the check is on the
    // arguments), nothing written; the same command with a usable folder runs.
    std::fs::write(dir.join("file"), "").unwrap();
    let r = fathom(
        &dir,
        &["pils", "offline", "pils.toml", "--out", "file/offline"],
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("--out"), "{}", r.stderr);
    assert_eq!(r.stderr.trim().lines().count(), 1, "{}", r.stderr);
    let r = fathom(&dir, &["pils", "offline", "pils.toml", "--out", "offline"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(dir.join("offline/solutions.csv").is_file());
}

/// The acceptance run itself: both full flights of the `urban` preset with every
/// method, each through `fathom pils scenarios/urban.toml --scene S --method M` in
/// lockstep as two processes, equal the offline run fed the same MAVLink-quantized
/// measurements bit for bit; and `scenarios/pils.toml` (buildings, MGPMF) flies the
/// same session as the preset file with those flags. About 30 s in all.
#[test]
fn every_method_of_both_full_presets_lockstep_equals_offline_quantized_run() {
    let dir = scratch("pils-full");
    let urban = crate::support::repo_root().join("scenarios/urban.toml");
    let urban = urban.to_str().unwrap();
    for scene in ["bridge", "buildings"] {
        for method in crate::urban::METHODS {
            let out = format!("{scene}-{}", method.replace('/', "_"));
            let r = fathom(
                &dir,
                &[
                    "pils", urban, "--scene", scene, "--method", method, "--out", &out,
                ],
            );
            assert_eq!(r.code, 0, "{scene}/{method}: {}{}", r.stdout, r.stderr);
            let sim = json(&dir.join(&out).join("sim/pils.json"));
            assert_eq!(sim["status"], "ok", "{scene}/{method}");
            assert_eq!(sim["equal_to_offline_quantized"], true, "{scene}/{method}");
            assert_eq!(sim["steps_sent"], sim["steps_total"]);
            assert_eq!(
                (sim["scenario"].as_str(), sim["method"].as_str()),
                (Some(scene), Some(method))
            );
            assert!(
                sim["steps_total"].as_u64().unwrap() > 10_000,
                "{scene}/{method}: {}",
                sim["steps_total"]
            );
            // Independently of the session's own comparison: the offline command.
            let csv = std::fs::read_to_string(dir.join(&out).join("sim/solutions.csv")).unwrap();
            let r = fathom(
                &dir,
                &[
                    "pils",
                    "offline",
                    urban,
                    "--scene",
                    scene,
                    "--method",
                    method,
                    "--quantized",
                    "--out",
                    "q",
                ],
            );
            assert_eq!(r.code, 0, "{}", r.stderr);
            let offline = std::fs::read_to_string(dir.join("q/solutions.csv")).unwrap();
            assert!(
                csv == offline,
                "{scene}/{method}: PILS != offline quantized"
            );
        }
    }
    let file = crate::support::repo_root().join("scenarios/pils.toml");
    let r = fathom(&dir, &["pils", file.to_str().unwrap(), "--out", "preset"]);
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    assert_eq!(
        std::fs::read_to_string(dir.join("preset/sim/solutions.csv")).unwrap(),
        std::fs::read_to_string(dir.join("buildings-MGPMF/sim/solutions.csv")).unwrap()
    );
}
