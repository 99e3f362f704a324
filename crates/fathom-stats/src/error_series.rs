//! Distance errors per evaluation instant: the Euclidean norm of
//! (estimated position - true position), in 3D (x, y, z) or 2D (x, y only), as the
//! papers define "distance error".

use crate::error::StatsError;
use nalgebra::Vector3;

/// 3D distance error `|est - true|` over x, y, z (NED, metres).
pub fn distance_3d(est_pos_in_nav: &Vector3<f64>, true_pos_in_nav: &Vector3<f64>) -> f64 {
    (est_pos_in_nav - true_pos_in_nav).norm()
}

/// 2D (horizontal) distance error over x (north) and y (east) only; depth is ignored.
pub fn distance_2d(est_pos_in_nav: &Vector3<f64>, true_pos_in_nav: &Vector3<f64>) -> f64 {
    (est_pos_in_nav.x - true_pos_in_nav.x).hypot(est_pos_in_nav.y - true_pos_in_nav.y)
}

/// The 3D and 2D distance error series of one run, one entry per evaluation instant.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DistanceSeries {
    /// 3D distance errors, m.
    pub d3: Vec<f64>,
    /// 2D (horizontal) distance errors, m.
    pub d2: Vec<f64>,
}

fn check_pair(what: &str, est: &[Vector3<f64>], truth: &[Vector3<f64>]) -> Result<(), StatsError> {
    if est.len() != truth.len() {
        return Err(StatsError::LengthMismatch {
            what: what.into(),
            left_name: "est",
            left: est.len(),
            right_name: "truth",
            right: truth.len(),
        });
    }
    if est.is_empty() {
        return Err(StatsError::Empty { what: what.into() });
    }
    for (name, series) in [("est", est), ("truth", truth)] {
        for (row, v) in series.iter().enumerate() {
            if let Some(col) = v.iter().position(|c| !c.is_finite()) {
                return Err(StatsError::NonFiniteEntry {
                    what: format!("{what} ({name} positions)"),
                    row,
                    col,
                    value: v[col],
                });
            }
        }
    }
    Ok(())
}

/// 3D distance error series of paired estimated and true positions.
///
/// # Errors
/// [`StatsError::LengthMismatch`] (naming both lengths), [`StatsError::Empty`], or
/// [`StatsError::NonFiniteEntry`] naming the instant and axis.
pub fn distance_series_3d(
    est: &[Vector3<f64>],
    truth: &[Vector3<f64>],
) -> Result<Vec<f64>, StatsError> {
    check_pair("3D distance series", est, truth)?;
    Ok(est
        .iter()
        .zip(truth)
        .map(|(e, t)| distance_3d(e, t))
        .collect())
}

/// 2D (horizontal) distance error series of paired estimated and true positions.
///
/// # Errors
/// As [`distance_series_3d`].
pub fn distance_series_2d(
    est: &[Vector3<f64>],
    truth: &[Vector3<f64>],
) -> Result<Vec<f64>, StatsError> {
    check_pair("2D distance series", est, truth)?;
    Ok(est
        .iter()
        .zip(truth)
        .map(|(e, t)| distance_2d(e, t))
        .collect())
}

/// Both 3D and 2D distance error series in one pass.
///
/// # Errors
/// As [`distance_series_3d`].
pub fn distance_series(
    est: &[Vector3<f64>],
    truth: &[Vector3<f64>],
) -> Result<DistanceSeries, StatsError> {
    check_pair("distance series", est, truth)?;
    let (d3, d2) = est
        .iter()
        .zip(truth)
        .map(|(e, t)| (distance_3d(e, t), distance_2d(e, t)))
        .unzip();
    Ok(DistanceSeries { d3, d2 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn distances() {
        let e = Vector3::new(3.0, 4.0, 12.0);
        let t = Vector3::new(0.0, 0.0, 0.0);
        assert_relative_eq!(distance_3d(&e, &t), 13.0, epsilon = 1e-12);
        assert_relative_eq!(distance_2d(&e, &t), 5.0, epsilon = 1e-12);
    }

    #[test]
    fn series_and_errors() {
        let est = vec![Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, 2.0)];
        let truth = vec![Vector3::zeros(); 2];
        let s = distance_series(&est, &truth).unwrap();
        assert_eq!(s.d3, vec![1.0, 2.0]);
        assert_eq!(s.d2, vec![1.0, 0.0]);
        assert_eq!(distance_series_3d(&est, &truth).unwrap(), s.d3);
        assert_eq!(distance_series_2d(&est, &truth).unwrap(), s.d2);

        let err = distance_series_3d(&est, &truth[..1]).unwrap_err();
        assert!(matches!(
            err,
            StatsError::LengthMismatch {
                left: 2,
                right: 1,
                ..
            }
        ));
        assert!(err.to_string().contains("est has 2, truth has 1"));
        assert!(matches!(
            distance_series_2d(&[], &[]),
            Err(StatsError::Empty { .. })
        ));
        let bad = vec![Vector3::zeros(), Vector3::new(0.0, f64::NAN, 0.0)];
        assert!(matches!(
            distance_series(&est, &bad),
            Err(StatsError::NonFiniteEntry { row: 1, col: 1, .. })
        ));
    }
}
