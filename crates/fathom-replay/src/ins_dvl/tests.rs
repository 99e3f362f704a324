//! Tests of the INS / DVL replay settings (the replay itself is tested on the
//! simulated example log in `fathom-experiments`, which simulates it).

use super::*;

fn preset() -> String {
    std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/ins-dvl.toml"),
    )
    .unwrap()
}

#[test]
fn bad_settings_name_the_key() {
    for (from, to, key) in [
        ("filter = \"vkf\"", "filter = \"ukf\"", "methods[2].filter"),
        (
            "gate_probability = 0.999",
            "gate_probability = 1.5",
            "methods[3].gate_probability",
        ),
        (
            "filter = \"pins\"",
            "filter = \"pins\"\ngate_probability = 0.9",
            "methods[0].gate_probability",
        ),
        (
            "accel_bias_frame = \"nav\"",
            "accel_bias_frame = \"ned\"",
            "nav_filter.accel_bias_frame",
        ),
        ("timeout_s = 1.0", "timeout_s = -1.0", "dvl.timeout_s"),
        ("name = \"ESKF\"", "name = \"VKF\"", "methods[4].name"),
    ] {
        let t = preset().replacen(from, to, 1);
        assert_ne!(t, preset(), "{from}");
        let e = parse_settings(&t, "i.toml").unwrap_err().to_string();
        assert!(e.contains(key), "{key}: {e}");
    }
    let cut = &preset()[..preset().find("[[methods]]").unwrap()];
    let s = parse_settings(cut, "i.toml").unwrap();
    assert_eq!(s.methods.len(), 5);
}
