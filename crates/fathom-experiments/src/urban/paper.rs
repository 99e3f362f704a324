//! The numbers seed 004 prints (reference only: never copied into a value), and
//! which row each one sits on.

use super::nav::Method;
use super::scenario::PresetWorld;

/// Under the bridge, GREKF with the lidar: 3-axis RMS position error (Fig. 8-10), m.
pub const BRIDGE_GREKF_RMS_3D_M: f64 = 0.2972;
/// Under the bridge: attitude errors "within 0.5 deg" (Fig. 10), deg.
pub const BRIDGE_ATT_BOUND_DEG: f64 = 0.5;
/// Table 2 (buildings, MGPMF with the range finders): RMSE of horizontal position (m),
/// 3-D position (m), velocity (m/s), roll, pitch, yaw (deg).
pub const TABLE2: [(&str, f64); 6] = [
    ("rmse_h", 0.683),
    ("rmse_3d", 1.030),
    ("rmse_vel", 0.182),
    ("rmse_roll", 0.329),
    ("rmse_pitch", 0.650),
    ("rmse_yaw", 2.763),
];
/// Buildings: position accuracy (read as the mean 3-D error, row `mean_3d`), m.
pub const ACCURACY_M: f64 = 1.18;
/// Buildings: position precision, 2 σ (read as the 95th percentile of the 3-D error,
/// row `p95_3d`), m.
pub const PRECISION_2SIGMA_M: f64 = 2.12;

/// The paper's number for a row, if it prints one.
pub fn paper_value(world: Option<PresetWorld>, method: Method, metric: &str) -> Option<f64> {
    match (world?, method) {
        (PresetWorld::Bridge, Method::Grekf) => match metric {
            "rmse_3d" => Some(BRIDGE_GREKF_RMS_3D_M),
            "max_att" => Some(BRIDGE_ATT_BOUND_DEG),
            _ => None,
        },
        (PresetWorld::Buildings, Method::Mgpmf) => match metric {
            "mean_3d" => Some(ACCURACY_M),
            "p95_3d" => Some(PRECISION_2SIGMA_M),
            m => TABLE2.iter().find(|(k, _)| *k == m).map(|(_, v)| *v),
        },
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_numbers_sit_on_the_paired_rows_only() {
        let b = Some(PresetWorld::Buildings);
        assert_eq!(paper_value(b, Method::Mgpmf, "rmse_yaw"), Some(2.763));
        assert_eq!(paper_value(b, Method::Mgpmf, "p95_3d"), Some(2.12));
        assert_eq!(paper_value(b, Method::Grekf, "rmse_h"), None);
        assert_eq!(
            paper_value(Some(PresetWorld::Bridge), Method::Grekf, "rmse_3d"),
            Some(0.2972)
        );
        assert_eq!(paper_value(None, Method::Grekf, "rmse_3d"), None);
    }
}
