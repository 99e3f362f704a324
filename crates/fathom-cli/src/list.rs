//! `fathom list`: what a settings file can name, generated from the registries (the
//! experiments with their methods, the replays with the values of their `[[methods]]`
//! keys), then the estimators, update schemes and sensor models, in aligned columns.

use fathom_experiments::registry;
use fathom_replay::method_keys::method_keys;
use fathom_replay::own_log_replays;
use fathom_sim::experiment::DynExperiment;

/// The estimators of `fathom-estimators`, by the names the settings files use.
const ESTIMATORS: &[(&str, &str)] = &[
    ("kf", "linear Kalman filter, Joseph-form update"),
    (
        "ekf",
        "range-beacon EKF under AS / SC / SI (beacons, plaza, replay range-beacon)",
    ),
    (
        "dead-reckoning",
        "DVL / odometry dead reckoning without corrections (DR, DVL-DR)",
    ),
    (
        "ins-dvl",
        "9-state INS / velocity filter (vkf: INS-DVL; replay ins-dvl)",
    ),
    (
        "vkf",
        "velocity filter switching DVL / RPM aiding (vkf: VKF; replay ins-dvl)",
    ),
    (
        "eskf",
        "15-state INS error-state filter (fusion: MF, T2T, EFF; vkf: ESKF; replay ins-dvl)",
    ),
    (
        "information-fusion",
        "track fusion: eq. 10, Bar-Shalom-Campo, covariance intersection (fusion)",
    ),
    (
        "GPS/INS",
        "12-state error-state INS with GPS updates (urban)",
    ),
    (
        "GREKF",
        "GPS/INS switching to the range-finder EKF in GNSS shadow (urban)",
    ),
    (
        "MGPMF",
        "GPS/INS switching to the marginalized point-mass filter (urban)",
    ),
    (
        "PF",
        "GPS/INS switching to a particle filter at the same ray budget (urban)",
    ),
    (
        "rts",
        "fixed-interval RTS smoother of a filter's forward pass (plaza: smooth = true)",
    ),
];

/// The update schemes of the range-beacon EKF.
const SCHEMES: &[(&str, &str)] = &[
    (
        "AS",
        "asynchronous: each measurement updates at its own time stamp",
    ),
    ("SC", "synchronous collective: one stacked update per epoch"),
    (
        "SI",
        "synchronous individual: sequential scalar updates per epoch",
    ),
];

/// The sensor models of `fathom-sensors`.
const SENSORS: &[(&str, &str)] = &[
    (
        "imu",
        "strapdown IMU: biases, scale, noise, flicker; ADIS16448 presets (Allan)",
    ),
    ("dvl", "Doppler velocity log: body velocity, bottom lock"),
    ("ahrs", "attitude / heading / rate sensor"),
    ("range", "acoustic / radio range to a beacon, outliers"),
    ("depth", "pressure depth gauge"),
    ("echo-sounder", "altitude above the sea floor"),
    ("rpm", "propeller RPM speed log"),
    (
        "wheel-odometry",
        "recorded odometry (plaza, replay range-beacon)",
    ),
    (
        "gnss",
        "GPS constellation, line of sight against the map, pseudoranges, SPP (urban)",
    ),
    ("barometer", "eq. 20 barometer with its calibration (urban)"),
    (
        "rangefinders",
        "6 + 1 range finders cast against the map (urban: ranging = \"rangefinders\")",
    ),
    (
        "lidar",
        "UST-20LX scanning lidar cast against the map (urban: ranging = \"lidar\")",
    ),
];

/// `fathom list`.
pub(crate) fn list_cmd() -> String {
    let experiments = registry();
    let mut replays: Vec<&'static dyn DynExperiment> = experiments
        .iter()
        .copied()
        .filter(|e| e.name() == "plaza")
        .collect();
    replays.extend(own_log_replays());
    let tables: [&[(&str, &str)]; 3] = [ESTIMATORS, SCHEMES, SENSORS];
    // One name column for every section.
    let width = experiments
        .iter()
        .chain(&replays)
        .map(|e| e.name().len())
        .chain(tables.iter().flat_map(|t| t.iter().map(|(n, _)| n.len())))
        .max()
        .unwrap_or(0);
    let pad = " ".repeat(width);
    let mut text = String::from("experiments (fathom run FILE; `experiment = \"<name>\"`):\n");
    for e in &experiments {
        text += &format!(
            "  {:<width$}  {} (preset {})\n",
            e.name(),
            e.about(),
            e.default_scenario()
        );
        if !e.methods().is_empty() {
            text += &format!(
                "  {pad}  methods = [{}] (default: all)\n",
                quoted(e.methods()).join(", ")
            );
        }
    }
    text +=
        "replays of recorded data (fathom replay KIND [DIR] --config FILE; docs/own-data.md):\n";
    for e in &replays {
        text += &format!(
            "  {:<width$}  {} (settings {})\n",
            e.name(),
            e.about(),
            e.default_scenario()
        );
        for (key, values) in method_keys(e.name()) {
            text += &format!(
                "  {pad}  [[methods]] {key} = {}\n",
                quoted(values).join(" | ")
            );
        }
    }
    for (title, table) in [
        ("estimators (fathom-estimators):", ESTIMATORS),
        (
            "update schemes (beacons, plaza, replay range-beacon):",
            SCHEMES,
        ),
        ("sensor models (fathom-sensors):", SENSORS),
    ] {
        text += title;
        text.push('\n');
        for (name, doc) in table {
            text += &format!("  {name:<width$}  {doc}\n");
        }
    }
    text
}

fn quoted(names: &[&str]) -> Vec<String> {
    names.iter().map(|n| format!("\"{n}\"")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_name_is_listed_in_aligned_columns() {
        let l = list_cmd();
        for e in registry().into_iter().chain(own_log_replays()) {
            assert!(l.contains(&format!("  {} ", e.name())), "{}\n{l}", e.name());
            for m in e.methods() {
                assert!(l.contains(&format!("\"{m}\"")), "{m}\n{l}");
            }
            for (key, values) in method_keys(e.name()) {
                assert!(l.contains(&format!("{key} = ")), "{key}\n{l}");
                for v in *values {
                    assert!(l.contains(&format!("\"{v}\"")), "{v}\n{l}");
                }
            }
        }
        for name in ["GREKF", "MGPMF", "PF", "gnss", "barometer", "lidar", "eskf"] {
            assert!(l.contains(&format!("  {name} ")), "{name}\n{l}");
        }
        assert!(!l.contains("ins-error-kf"), "{l}");
        // The second column starts at the same place on every entry line.
        let starts: Vec<usize> = l
            .lines()
            .filter(|line| line.starts_with("  ") && !line.starts_with("   "))
            .map(|line| {
                let name_end = 2 + line[2..].find(' ').unwrap();
                name_end + line[name_end..].find(|c| c != ' ').unwrap()
            })
            .collect();
        assert!(starts.len() > 30, "{l}");
        assert!(starts.iter().all(|s| *s == starts[0]), "{starts:?}\n{l}");
    }
}
