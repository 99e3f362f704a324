//! `cargo xtask bench [--compare] [--mesh FILE] [FILTER]`: runs the criterion
//! benchmarks of the workspace (`cargo bench --workspace`), collects criterion's
//! estimates into `target/bench/bench.json` (`{"name", "ns_per_iter", "iters", ...}`
//! per benchmark) and prints a table with the performance targets of
//! `docs/performance.md` (with the ns per ray cast inside each map-aided update:
//! `cargo xtask bench map_aided`). `--mesh FILE` hands an OBJ mesh (NED metres, as
//! the Embree reference script of docs/performance.md writes it) to the ray-casting bench through the
//! `FATHOM_RAYCAST_MESH` environment variable (`raycast/mesh`). The target directory
//! is `CARGO_TARGET_DIR` when set (where cargo and criterion write), else `target/`.
//! `--compare` also times FilterPy's `KalmanFilter` on the identical 6-state /
//! 3-measurement problem when `python3` and `filterpy` are installed (skipped with a
//! message otherwise) and prints the ratio.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::SystemTime;

use anyhow::{Context, Result, bail};
use serde_json::{Value, json};

/// One collected benchmark.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchResult {
    /// Criterion's full id, e.g. `kf_6x3_predict_update` or `mc_run/vkf`.
    pub name: String,
    /// Median time per iteration, ns.
    pub ns_per_iter: f64,
    /// Fastest sample's time per iteration, ns.
    pub min_ns_per_iter: f64,
    /// Iterations measured (sum over samples).
    pub iters: u64,
}

/// A performance target of the issue: benchmark, bound, and whether lower is better.
struct Target {
    name: &'static str,
    what: &'static str,
    bound_ns: f64,
}

const TARGETS: [Target; 4] = [
    Target {
        name: "kf_6x3_predict_update",
        what: "KF 6/3 predict+update",
        bound_ns: 200.0,
    },
    Target {
        name: "strapdown_step",
        what: "strapdown step",
        bound_ns: 200.0,
    },
    Target {
        name: "mc_run/vkf",
        what: "one vkf Monte Carlo run",
        bound_ns: 0.5e9,
    },
    Target {
        name: "map_aided/mgpmf_41x41x9_7beams",
        what: "MGPMF update 41x41x9, 7 beams",
        bound_ns: 10e6,
    },
];

/// The map-aided updates of `fathom-sim/benches/map_aided.rs`, the bench casting the
/// same rays alone, and the number of rays: ns per ray cast inside each update and
/// the share of the update the casts take. The GREKF scan's ray count is what the
/// bench prints (the beams with a return); the 109-beam scan returns 93 there.
const RAY_SHARES: [(&str, &str, f64); 3] = [
    (
        "map_aided/grekf_109_beams",
        "map_aided_rays/grekf_scan",
        93.0,
    ),
    (
        "map_aided/mgpmf_41x41x9_7beams",
        "map_aided_rays/grid_41x41x9_7beams_packets",
        (41 * 41 * 9 * 7) as f64,
    ),
    (
        "map_aided/particle_15129_7beams",
        "map_aided_rays/grid_41x41x9_7beams_packets",
        (41 * 41 * 9 * 7) as f64,
    ),
];

/// Minimum Monte Carlo speed-up from 1 to 2 threads.
const MIN_SPEEDUP: f64 = 1.7;

/// The target directory: `CARGO_TARGET_DIR` (relative to the workspace root when
/// relative) or `<root>/target`.
pub fn target_dir(root: &Path) -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(d) if !d.is_empty() => root.join(PathBuf::from(d)),
        _ => root.join("target"),
    }
}

/// Runs the benchmarks and writes the report.
pub fn run(root: &Path, compare: bool, mesh: Option<&Path>, filter: Option<&str>) -> Result<()> {
    let started = SystemTime::now();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(root)
        .args(["bench", "--workspace", "--bench", "*", "--"]);
    if let Some(m) = mesh {
        let m = std::path::absolute(m).with_context(|| format!("mesh path {}", m.display()))?;
        if !m.is_file() {
            bail!("--mesh {}: no such file", m.display());
        }
        cmd.env("FATHOM_RAYCAST_MESH", m);
    }
    if let Some(f) = filter {
        cmd.arg(f);
    }
    let status = cmd.status().context("running `cargo bench`")?;
    if !status.success() {
        bail!("`cargo bench` failed ({status})");
    }
    let criterion_dir = target_dir(root).join("criterion");
    let mut results = collect(&criterion_dir, started)?;
    results.sort_by(|a, b| a.name.cmp(&b.name));
    if results.is_empty() {
        bail!(
            "no criterion results newer than this run under {}",
            criterion_dir.display()
        );
    }
    let out_dir = target_dir(root).join("bench");
    std::fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let json_path = out_dir.join("bench.json");
    let entries: Vec<Value> = results
        .iter()
        .map(|r| {
            json!({
                "name": r.name,
                "ns_per_iter": r.ns_per_iter,
                "min_ns_per_iter": r.min_ns_per_iter,
                "iters": r.iters,
            })
        })
        .collect();
    std::fs::write(&json_path, serde_json::to_string_pretty(&entries)? + "\n")
        .with_context(|| format!("writing {}", json_path.display()))?;
    println!("\n{}", table(&results));
    println!("{}", targets(&results));
    if compare {
        filterpy_compare(&results);
    }
    println!("results: {}", json_path.display());
    Ok(())
}

/// Human-readable duration.
fn fmt_ns(ns: f64) -> String {
    if ns < 1e3 {
        format!("{ns:.1} ns")
    } else if ns < 1e6 {
        format!("{:.2} us", ns / 1e3)
    } else if ns < 1e9 {
        format!("{:.2} ms", ns / 1e6)
    } else {
        format!("{:.3} s", ns / 1e9)
    }
}

fn table(results: &[BenchResult]) -> String {
    let w = results
        .iter()
        .map(|r| r.name.len())
        .max()
        .unwrap_or(4)
        .max(9);
    let mut s = format!(
        "{:<w$}  {:>12}  {:>12}  {:>12}\n",
        "benchmark", "median", "fastest", "iterations"
    );
    for r in results {
        s.push_str(&format!(
            "{:<w$}  {:>12}  {:>12}  {:>12}\n",
            r.name,
            fmt_ns(r.ns_per_iter),
            fmt_ns(r.min_ns_per_iter),
            r.iters
        ));
    }
    s
}

fn find<'a>(results: &'a [BenchResult], name: &str) -> Option<&'a BenchResult> {
    results.iter().find(|r| r.name == name)
}

fn targets(results: &[BenchResult]) -> String {
    let mut s = String::from(
        "targets (median; machine load makes these noisy, see docs/performance.md):\n",
    );
    for t in &TARGETS {
        if let Some(r) = find(results, t.name) {
            s.push_str(&format!(
                "  {:<28} {:>10} (target <= {}): {}\n",
                t.what,
                fmt_ns(r.ns_per_iter),
                fmt_ns(t.bound_ns),
                if r.ns_per_iter <= t.bound_ns {
                    "met"
                } else {
                    "NOT met"
                }
            ));
        }
    }
    if let (Some(one), Some(two)) = (
        find(results, "mc_batch32_beacons/threads_1"),
        find(results, "mc_batch32_beacons/threads_2"),
    ) {
        let speedup = one.ns_per_iter / two.ns_per_iter;
        let best = one.min_ns_per_iter / two.min_ns_per_iter;
        s.push_str(&format!(
            "  {:<28} {:>10.2}x (fastest samples {:.2}x; target >= {MIN_SPEEDUP}x): {}\n",
            "Monte Carlo 1 -> 2 threads",
            speedup,
            best,
            if speedup >= MIN_SPEEDUP {
                "met"
            } else {
                "NOT met"
            }
        ));
    }
    for (name, what) in [
        ("raycast/buildings", "closest-hit ray, buildings"),
        ("raycast/mesh", "closest-hit ray, --mesh"),
    ] {
        if let Some(r) = find(results, name) {
            s.push_str(&format!(
                "  {what:<28} {:>10} per ray (fastest sample {}); Embree: run \
                 the reference script on the same mesh (docs/performance.md)\n",
                fmt_ns(r.ns_per_iter),
                fmt_ns(r.min_ns_per_iter),
            ));
        }
    }
    for (update, rays, count) in RAY_SHARES {
        if let (Some(u), Some(r)) = (find(results, update), find(results, rays)) {
            s.push_str(&format!(
                "  {:<28} {:>10} per update; {:.0} rays at {:.1} ns per ray cast = {:.0} % of it\n",
                update.trim_start_matches("map_aided/"),
                fmt_ns(u.ns_per_iter),
                count,
                r.ns_per_iter / count,
                100.0 * r.ns_per_iter / u.ns_per_iter,
            ));
        }
    }
    if let (Some(kf), Some(reference)) = (
        find(results, "kf_6x3_predict_update"),
        find(results, "nalgebra_reference_6x3_predict_update"),
    ) {
        // the machine's speed varies from minute to minute on a shared VM; the
        // check-free nalgebra step measured in the same run shows how fast it was
        s.push_str(&format!(
            "  KF 6/3 vs check-free nalgebra step in this run: {:.2}x by the median \
             ({} vs {}; fastest samples {:.2}x)\n",
            kf.ns_per_iter / reference.ns_per_iter,
            fmt_ns(kf.ns_per_iter),
            fmt_ns(reference.ns_per_iter),
            kf.min_ns_per_iter / reference.min_ns_per_iter,
        ));
    }
    s
}

/// Reads `<dir>/**/new/{benchmark,estimates,sample}.json` written after `since`.
fn collect(dir: &Path, since: SystemTime) -> Result<Vec<BenchResult>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if !p.is_dir() {
                continue;
            }
            if p.file_name().is_some_and(|n| n == "new") {
                if let Some(r) = read_one(&p, since)? {
                    out.push(r);
                }
            } else {
                stack.push(p);
            }
        }
    }
    Ok(out)
}

fn read_json(p: &Path) -> Result<Value> {
    let text = std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))
}

fn read_one(new_dir: &Path, since: SystemTime) -> Result<Option<BenchResult>> {
    let bench = new_dir.join("benchmark.json");
    let fresh = std::fs::metadata(&bench)
        .and_then(|m| m.modified())
        .is_ok_and(|t| t >= since);
    if !fresh {
        return Ok(None);
    }
    let meta = read_json(&bench)?;
    let est = read_json(&new_dir.join("estimates.json"))?;
    let sample = read_json(&new_dir.join("sample.json"))?;
    let name = meta["full_id"]
        .as_str()
        .context("benchmark.json without full_id")?
        .to_string();
    let ns_per_iter = est["median"]["point_estimate"]
        .as_f64()
        .context("estimates.json without median")?;
    let nums = |key: &str| -> Vec<f64> {
        sample[key]
            .as_array()
            .map(|a| a.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default()
    };
    let (iters, times) = (nums("iters"), nums("times"));
    let min_ns_per_iter = iters
        .iter()
        .zip(&times)
        .map(|(n, t)| t / n)
        .fold(f64::INFINITY, f64::min);
    Ok(Some(BenchResult {
        name,
        ns_per_iter,
        min_ns_per_iter: if min_ns_per_iter.is_finite() {
            min_ns_per_iter
        } else {
            ns_per_iter
        },
        iters: iters.iter().sum::<f64>() as u64,
    }))
}

/// FilterPy's `KalmanFilter` on the problem of `kf_6x3_predict_update` (3-D constant
/// velocity, dt = 0.1 s, white-acceleration Q, position measurement, the same R).
/// FilterPy's default update is `P = (I-KH) P (I-KH)^T + K R K^T` (Joseph form).
const FILTERPY_SCRIPT: &str = r#"
import timeit
import numpy as np
from filterpy.kalman import KalmanFilter
dt = 0.1
kf = KalmanFilter(dim_x=6, dim_z=3)
F = np.eye(6); F[0:3, 3:6] = np.eye(3) * dt
q = np.array([0.1, 0.1, 0.05])
Q = np.zeros((6, 6))
for i in range(3):
    Q[i, i] = q[i] * dt**3 / 3; Q[i, i+3] = Q[i+3, i] = q[i] * dt**2 / 2; Q[i+3, i+3] = q[i] * dt
kf.F = F; kf.Q = Q
kf.H = np.hstack([np.eye(3), np.zeros((3, 3))])
kf.R = np.array([[0.25, 0.02, 0.0], [0.02, 0.25, 0.01], [0.0, 0.01, 0.5]])
kf.x = np.zeros(6); kf.P = np.eye(6)
z = np.array([1.0, -2.0, 0.5])
def step():
    kf.predict(); kf.update(z)
n = 20000
best = min(timeit.repeat(step, number=n, repeat=5)) / n
print(best * 1e9)
"#;

fn filterpy_compare(results: &[BenchResult]) {
    let Some(ours) = find(results, "kf_6x3_predict_update") else {
        println!("--compare: kf_6x3_predict_update was not run (filter?), nothing to compare");
        return;
    };
    let python = ["python3", "python"]
        .into_iter()
        .find(|p| Command::new(p).arg("--version").output().is_ok());
    let Some(python) = python else {
        println!("--compare skipped: no python3 on PATH");
        return;
    };
    let out = match Command::new(python).args(["-c", FILTERPY_SCRIPT]).output() {
        Ok(o) => o,
        Err(e) => {
            println!("--compare skipped: cannot run {python}: {e}");
            return;
        }
    };
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let last = err.lines().last().unwrap_or("").trim();
        println!(
            "--compare skipped: FilterPy not usable ({last}); `pip install filterpy` to enable"
        );
        return;
    }
    let text = String::from_utf8_lossy(&out.stdout);
    match text.trim().parse::<f64>() {
        Ok(ns) => println!(
            "--compare: FilterPy KalmanFilter predict+update (6/3) {} (best of 5 x 20000) vs fathom {} (median): fathom is {:.0}x faster",
            fmt_ns(ns),
            fmt_ns(ours.ns_per_iter),
            ns / ours.ns_per_iter
        ),
        Err(_) => println!(
            "--compare skipped: unexpected FilterPy output `{}`",
            text.trim()
        ),
    }
}

/// The criterion output directory of a workspace (for tests).
#[cfg(test)]
fn criterion_dir(root: &Path) -> std::path::PathBuf {
    root.join("target").join("criterion")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_criterion_output() {
        let dir = std::env::temp_dir().join(format!("xtask-bench-{}", std::process::id()));
        let new = criterion_dir(&dir).join("grp").join("f").join("new");
        std::fs::create_dir_all(&new).unwrap();
        std::fs::write(new.join("benchmark.json"), r#"{"full_id":"grp/f"}"#).unwrap();
        std::fs::write(
            new.join("estimates.json"),
            r#"{"median":{"point_estimate":150.0}}"#,
        )
        .unwrap();
        std::fs::write(
            new.join("sample.json"),
            r#"{"iters":[10.0,20.0],"times":[1600.0,2800.0]}"#,
        )
        .unwrap();
        let r = collect(&criterion_dir(&dir), SystemTime::UNIX_EPOCH).unwrap();
        assert_eq!(
            r,
            vec![BenchResult {
                name: "grp/f".into(),
                ns_per_iter: 150.0,
                min_ns_per_iter: 140.0,
                iters: 30
            }]
        );
        // results older than the run are ignored
        let later = SystemTime::now() + std::time::Duration::from_secs(3600);
        assert!(collect(&criterion_dir(&dir), later).unwrap().is_empty());
        let kf = BenchResult {
            name: "kf_6x3_predict_update".into(),
            ns_per_iter: 150.0,
            min_ns_per_iter: 140.0,
            iters: 1,
        };
        let t = targets(std::slice::from_ref(&kf));
        assert!(t.contains("met") && !t.contains("NOT met"), "{t}");
        assert!(!t.contains("nalgebra"), "{t}");
        let reference = BenchResult {
            name: "nalgebra_reference_6x3_predict_update".into(),
            ns_per_iter: 300.0,
            min_ns_per_iter: 200.0,
            iters: 1,
        };
        let t = targets(&[kf, reference]);
        assert!(
            t.contains("0.50x by the median (150.0 ns vs 300.0 ns; fastest samples 0.70x)"),
            "{t}"
        );
        let update = BenchResult {
            name: "map_aided/mgpmf_41x41x9_7beams".into(),
            ns_per_iter: 9e6,
            min_ns_per_iter: 8.5e6,
            iters: 1,
        };
        let rays = BenchResult {
            name: "map_aided_rays/grid_41x41x9_7beams_packets".into(),
            ns_per_iter: 6.75e6,
            ..update.clone()
        };
        let t = targets(&[update, rays]);
        assert!(
            t.contains("MGPMF update 41x41x9, 7 beams") && t.contains(": met"),
            "{t}"
        );
        assert!(
            t.contains("105903 rays at 63.7 ns per ray cast = 75 % of it"),
            "{t}"
        );
        assert!(table(&r).contains("grp/f"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
