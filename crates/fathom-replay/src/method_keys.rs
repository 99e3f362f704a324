//! The values the `[[methods]]` entries of a replay's settings accept, key by key:
//! what `fathom list` shows (each value is tested to be accepted, and a value beside
//! them refused).

/// `(key, accepted values)` of a `[[methods]]` entry of a `range-beacon` replay.
pub const RANGE_BEACON: &[(&str, &[&str])] = &[
    ("filter", &["dead-reckoning", "ekf"]),
    ("scheme", &["AS", "SC", "SI"]),
    ("calibration", &["none", "offset", "affine"]),
    ("outliers", &["robust", "gate"]),
];

/// `(key, accepted values)` of a `[[methods]]` entry of an `ins-dvl` replay (`eskf`:
/// the 15-state error-state filter, `ESKF` in the `vkf` experiment).
pub const INS_DVL: &[(&str, &[&str])] = &[("filter", &["pins", "ins-dvl", "vkf", "eskf"])];

/// `(key, accepted values)` of a `[[methods]]` entry of a `gnss-ins` replay
/// (`grekf`, `mgpmf`: with a world, `--world`).
pub const GNSS_INS: &[(&str, &[&str])] = &[(
    "filter",
    &["ins", "gps-ins-12", "gps-ins-15", "grekf", "mgpmf"],
)];

/// The keys and values of the replay named `kind` (`range-beacon`, `ins-dvl`,
/// `gnss-ins`); none for another name.
pub fn method_keys(kind: &str) -> &'static [(&'static str, &'static [&'static str])] {
    match kind {
        "range-beacon" => RANGE_BEACON,
        "ins-dvl" => INS_DVL,
        "gnss-ins" => GNSS_INS,
        _ => &[],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::own_log::{GNSS_INS_PRESET, INS_DVL_PRESET, RANGE_BEACON_PRESET};

    /// The preset with its `[[methods]]` replaced by one `entry`.
    fn with_method(preset: &str, entry: &str) -> String {
        let head = &preset[..preset.find("[[methods]]").expect("a [[methods]] list")];
        format!("{head}[[methods]]\nname = \"m\"\n{entry}\n")
    }

    /// A complete entry of a range-beacon method setting `key = value`.
    fn range_beacon_entry(key: &str, value: &str) -> String {
        match (key, value) {
            ("filter", "dead-reckoning") => "filter = \"dead-reckoning\"".into(),
            ("filter", v) => format!("filter = \"{v}\"\nscheme = \"AS\""),
            ("outliers", "gate") => "scheme = \"AS\"\noutliers = \"gate\"\ngate_sigma = 3.0".into(),
            ("scheme", v) => format!("scheme = \"{v}\""),
            (k, v) => format!("scheme = \"AS\"\n{k} = \"{v}\""),
        }
    }

    #[test]
    fn every_listed_value_is_accepted_and_another_refused() {
        for (key, values) in RANGE_BEACON {
            for v in *values {
                let text = with_method(RANGE_BEACON_PRESET, &range_beacon_entry(key, v));
                crate::range_beacon::parse_settings(&text, "t.toml")
                    .unwrap_or_else(|e| panic!("{key} = {v}: {e}"));
            }
            let text = with_method(RANGE_BEACON_PRESET, &range_beacon_entry(key, "bogus"));
            assert!(
                crate::range_beacon::parse_settings(&text, "t.toml").is_err(),
                "{key} = bogus"
            );
        }
        for (key, values) in INS_DVL {
            for v in values.iter().chain(&["bogus"]) {
                let text = with_method(INS_DVL_PRESET, &format!("{key} = \"{v}\""));
                let parsed = crate::ins_dvl::parse_settings(&text, "t.toml");
                assert_eq!(parsed.is_ok(), *v != "bogus", "{key} = {v}: {parsed:?}");
            }
        }
        // the map-aided filters need a world: accepted with one, refused without
        let with_world =
            GNSS_INS_PRESET.replace("[initial]", "[world]\nfile = \"w.obj\"\n\n[initial]");
        for (key, values) in GNSS_INS {
            for v in values.iter().chain(&["bogus"]) {
                let text = with_method(&with_world, &format!("{key} = \"{v}\""));
                let parsed = crate::gnss_ins::parse_settings(&text, "t.toml");
                assert_eq!(parsed.is_ok(), *v != "bogus", "{key} = {v}: {parsed:?}");
                let text = with_method(GNSS_INS_PRESET, &format!("{key} = \"{v}\""));
                let map_aided = ["grekf", "mgpmf"].contains(v);
                let parsed = crate::gnss_ins::parse_settings(&text, "t.toml");
                assert_eq!(parsed.is_ok(), *v != "bogus" && !map_aided, "{key} = {v}");
            }
        }
        assert_eq!(method_keys("ins-dvl"), INS_DVL);
        assert!(method_keys("plaza").is_empty());
    }
}
