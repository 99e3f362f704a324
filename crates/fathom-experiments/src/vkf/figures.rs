//! The `vkf` figures (the paper's Figs. 4-12 from run 0, the mean horizontal errors)
//! and CSV files.

use super::analysis::{mean_series, metrics};
use super::scenario::Checked;
use super::sim::{ESKF, GATED, INS_DVL, METHODS, PINS, RunOutput, Shared, VKF};
use fathom_report::plot::{LinePlot, PlanPlot, Series};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

/// `y_range` as a builder step.
trait WithYRange {
    fn with_y_range(self, lo: f64, hi: f64) -> Self;
}

impl WithYRange for LinePlot {
    fn with_y_range(mut self, lo: f64, hi: f64) -> Self {
        self.y_range = Some((lo, hi));
        self
    }
}

pub(super) fn shade(mut p: LinePlot, invalid: &[(f64, f64)]) -> LinePlot {
    for &(a, b) in invalid {
        p = p.with_shade(a, b);
    }
    p.with_shade_label("DVL invalid")
}

/// Palette index of the truth in the plan views (grey).
const TRUTH_COLOR: usize = 7;

/// An angle series in degrees made continuous: each step of more than 180 deg is
/// taken as a wrap and undone.
fn unwrap_deg(v: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(v.len());
    let mut offset = 0.0;
    for (k, &a) in v.iter().enumerate() {
        if k > 0 {
            let step = a - v[k - 1];
            if step > 180.0 {
                offset -= 360.0;
            } else if step < -180.0 {
                offset += 360.0;
            }
        }
        out.push(a + offset);
    }
    out
}

/// Adds every figure and CSV file to `out`.
pub(super) fn write(
    c: &Checked,
    shared: &Shared,
    runs: &[RunOutput],
    out: &mut Analysis,
) -> Result<(), SimError> {
    let inv = &shared.invalid;
    let Some(d) = runs[0].detail.as_deref() else {
        return Err(SimError::invalid_argument(
            "vkf run 0",
            "no detail recorded",
        ));
    };
    let t1 = &d.t1;
    // Truth grey, each method in its colour of the error figures.
    let ne = |k: usize| {
        Series::new(
            if k == 0 {
                "truth".to_string()
            } else {
                METHODS[k - 1].to_string()
            },
            d.ne[k].iter().map(|&(n, e)| (e, n)).collect(),
        )
        .with_color(if k == 0 { TRUTH_COLOR } else { k - 1 })
    };
    // Fig. 4: reference trajectory.
    out.figure(
        "fig04_trajectory.svg",
        &PlanPlot::new("Fig. 4: reference trajectory", "east (m)", "north (m)").with_path(ne(0)),
    )?;
    // Fig. 5: IMU signals (run 0, 1 Hz samples of the 100 Hz output).
    let axes = ["x", "y", "z"];
    let mut gyro = LinePlot::new(
        "Fig. 5a: gyro output (run 0)",
        "time (s)",
        "angular rate (deg/s)",
    );
    let mut acc = LinePlot::new(
        "Fig. 5b: accelerometer output (run 0)",
        "time (s)",
        "specific force (m/s^2)",
    );
    for i in 0..3 {
        gyro = gyro.with_series(Series::from_xy(
            format!("gyro {}", axes[i]),
            t1,
            &d.gyro_deg_s[i],
        )?);
        acc = acc.with_series(Series::from_xy(
            format!("accel {}", axes[i]),
            t1,
            &d.accel_mps2[i],
        )?);
    }
    out.figure("fig05_gyro.svg", &gyro)?;
    out.figure("fig05_accel.svg", &acc)?;
    // Fig. 6: attitude; yaw unwrapped (no jump line at +-180 deg).
    let names = ["roll", "pitch", "yaw"];
    let mut att = LinePlot::new(
        "Fig. 6: attitude, truth and PINS (run 0; yaw unwrapped)",
        "time (s)",
        "angle (deg)",
    );
    for i in 0..3 {
        let (truth, pins) = if i == 2 {
            (
                unwrap_deg(&d.truth_euler_deg[i]),
                unwrap_deg(&d.pins_euler_deg[i]),
            )
        } else {
            (d.truth_euler_deg[i].clone(), d.pins_euler_deg[i].clone())
        };
        att = att
            .with_series(Series::from_xy(format!("{} truth", names[i]), t1, &truth)?)
            .with_series(Series::from_xy(format!("{} PINS", names[i]), t1, &pins)?);
    }
    out.figure("fig06_attitude.svg", &att)?;
    // Fig. 7: PINS vs truth.
    out.figure(
        "fig07_pins_vs_truth.svg",
        &PlanPlot::new("Fig. 7: PINS vs truth (run 0)", "east (m)", "north (m)")
            .with_path(ne(0))
            .with_path(ne(1 + PINS)),
    )?;
    // Fig. 8: DVL velocity, invalid intervals shaded.
    let t5 = &d.t5;
    out.figure(
        "fig08_dvl_velocity.svg",
        &shade(
            LinePlot::new(
                "Fig. 8: DVL velocity (run 0; shaded: altitude > range)",
                "time (s)",
                "velocity (m/s)",
            )
            .with_series(Series::from_xy("DVL north", t5, &d.dvl_ne[0])?)
            .with_series(Series::from_xy("DVL east", t5, &d.dvl_ne[1])?),
            inv,
        ),
    )?;
    // Fig. 9: RPM and echo-sounder altitude.
    out.figure(
        "fig09_rpm.svg",
        &shade(
            LinePlot::new("Fig. 9a: propeller RPM (run 0)", "time (s)", "rpm")
                .with_series(Series::from_xy("rpm", t5, &d.rpm)?),
            inv,
        ),
    )?;
    let range = c.dvl.params().range;
    out.figure(
        "fig09_altitude.svg",
        &shade(
            LinePlot::new(
                "Fig. 9b: echo-sounder altitude (run 0)",
                "time (s)",
                "altitude (m)",
            )
            .with_series(Series::from_xy("measured", t5, &d.alt_meas)?)
            .with_series(Series::from_xy("true", t5, &d.alt_true)?)
            .with_series(Series::new(
                "DVL range",
                vec![(0.0, range), (c.duration, range)],
            )),
            inv,
        ),
    )?;
    // Fig. 10: VKF scale factor and bias.
    let k = c.rpm.k();
    let b = c.rpm.b();
    let band = |v: &[f64], s: &[f64], sign: f64| -> Vec<f64> {
        v.iter().zip(s).map(|(x, y)| x + sign * 3.0 * y).collect()
    };
    out.figure(
        "fig10_vkf_scale_factor.svg",
        &shade(
            LinePlot::new(
                "Fig. 10a: VKF scale factor (run 0)",
                "time (s)",
                "sf (m/s per rpm)",
            )
            .with_series(Series::from_xy("estimate", t5, &d.sf)?)
            .with_series(Series::from_xy(
                "+3 sigma",
                t5,
                &band(&d.sf, &d.sf_sigma, 1.0),
            )?)
            .with_series(Series::from_xy(
                "-3 sigma",
                t5,
                &band(&d.sf, &d.sf_sigma, -1.0),
            )?)
            .with_series(Series::new("true k_rpm", vec![(0.0, k), (c.duration, k)])),
            inv,
        )
        .with_y_range(k * 0.99, k * 1.01),
    )?;
    out.figure(
        "fig10_vkf_bias.svg",
        &shade(
            LinePlot::new("Fig. 10b: VKF bias (run 0)", "time (s)", "b (m/s)")
                .with_series(Series::from_xy("estimate", t5, &d.b)?)
                .with_series(Series::from_xy(
                    "+3 sigma",
                    t5,
                    &band(&d.b, &d.b_sigma, 1.0),
                )?)
                .with_series(Series::from_xy(
                    "-3 sigma",
                    t5,
                    &band(&d.b, &d.b_sigma, -1.0),
                )?)
                .with_series(Series::new("true b_rpm", vec![(0.0, b), (c.duration, b)])),
            inv,
        )
        .with_y_range(b - 0.3, b + 0.3),
    )?;
    // Fig. 11: RPM-derived vs DVL velocity.
    out.figure(
        "fig11_rpm_vs_dvl_velocity.svg",
        &shade(
            LinePlot::new(
                "Fig. 11: RPM-derived vs DVL velocity (run 0)",
                "time (s)",
                "velocity (m/s)",
            )
            .with_series(Series::from_xy("DVL north", t5, &d.dvl_ne[0])?)
            .with_series(Series::from_xy("RPM north", t5, &d.rpm_ne[0])?)
            .with_series(Series::from_xy("DVL east", t5, &d.dvl_ne[1])?)
            .with_series(Series::from_xy("RPM east", t5, &d.rpm_ne[1])?),
            inv,
        )
        .with_y_range(-8.0, 8.0),
    )?;
    // Fig. 12: all trajectories.
    let mut plan = PlanPlot::new(
        "Fig. 12: trajectories of all methods (run 0)",
        "east (m)",
        "north (m)",
    );
    for k in 0..=METHODS.len() {
        plan = plan.with_path(ne(k));
    }
    out.figure("fig12_trajectories.svg", &plan)?;
    let mut plan = PlanPlot::new(
        "Fig. 12: trajectories of the aided methods (run 0)",
        "east (m)",
        "north (m)",
    );
    for k in [0, 1 + VKF, 1 + GATED, 1 + ESKF] {
        plan = plan.with_path(ne(k));
    }
    out.figure("fig12_trajectories_aided.svg", &plan)?;

    // Horizontal error vs time, mean over runs.
    let tt: Vec<f64> = (0..runs[0].err_h[0].len()).map(|i| i as f64).collect();
    let means: Vec<Vec<f64>> = (0..METHODS.len()).map(|m| mean_series(runs, m)).collect();
    let mut all = LinePlot::new(
        format!(
            "horizontal error, mean of {} runs (zoom: horizontal_error_aided.svg)",
            runs.len()
        ),
        "time (s)",
        "horizontal error (m)",
    );
    for (m, name) in METHODS.iter().enumerate() {
        all = all.with_series(Series::from_xy(*name, &tt, &means[m])?);
    }
    out.figure("horizontal_error.svg", &shade(all, inv))?;
    let mut aided = LinePlot::new(
        format!(
            "horizontal error of the aided methods, mean of {} runs",
            runs.len()
        ),
        "time (s)",
        "horizontal error (m)",
    );
    // Each method in its colour of `horizontal_error.svg`.
    for m in [INS_DVL, VKF, GATED, ESKF] {
        aided = aided.with_series(Series::from_xy(METHODS[m], &tt, &means[m])?.with_color(m));
    }
    let top = [VKF, GATED, ESKF]
        .iter()
        .flat_map(|&m| means[m].iter().copied())
        .fold(0.0_f64, f64::max);
    out.figure(
        "horizontal_error_aided.svg",
        &shade(aided, inv).with_y_range(0.0, (3.0 * top).max(1.0)),
    )?;
    for (m, name) in METHODS.iter().enumerate() {
        let slug = name.to_lowercase().replace('-', "_");
        let mut p = LinePlot::new(
            format!(
                "{name}: horizontal error (mean and runs 0-{})",
                runs.len().min(5) - 1
            ),
            "time (s)",
            "horizontal error (m)",
        )
        .with_series(Series::from_xy("mean", &tt, &means[m])?);
        let per_run: Vec<&[f64]> = runs.iter().map(|r| r.err_h[m].as_slice()).collect();
        let (_, band) = fathom_stats::mean_curve_ci95(&tt, &per_run)?;
        p = p.with_band(0, band);
        for (i, r) in runs.iter().take(5).enumerate() {
            p = p.with_series(Series::from_xy(format!("run {i}"), &tt, &r.err_h[m])?);
        }
        out.figure(&format!("error_{slug}.svg"), &shade(p, inv))?;
    }

    // CSV.
    let mut headers = vec!["time_s".to_string()];
    headers.extend(
        METHODS
            .iter()
            .map(|m| format!("{}_mean_err_h_m", m.to_lowercase().replace('-', "_"))),
    );
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    let mut cols: Vec<&[f64]> = vec![&tt];
    cols.extend(means.iter().map(Vec::as_slice));
    out.csv_columns("mean_horizontal_error.csv", &h, &cols)?;
    out.csv_columns(
        "run0_sensors.csv",
        &[
            "time_s",
            "altitude_true_m",
            "altitude_meas_m",
            "rpm",
            "dvl_north_mps",
            "dvl_east_mps",
            "rpm_north_mps",
            "rpm_east_mps",
            "true_north_mps",
            "true_east_mps",
            "dvl_forward_mps",
            "rpm_forward_mps",
            "vkf_sf_mps_per_rpm",
            "vkf_b_mps",
            "vkf_sf_sigma",
            "vkf_b_sigma_mps",
            "vkf_source_rpm",
        ],
        &[
            t5,
            &d.alt_true,
            &d.alt_meas,
            &d.rpm,
            &d.dvl_ne[0],
            &d.dvl_ne[1],
            &d.rpm_ne[0],
            &d.rpm_ne[1],
            &d.true_ne[0],
            &d.true_ne[1],
            &d.dvl_fwd,
            &d.rpm_fwd,
            &d.sf,
            &d.b,
            &d.sf_sigma,
            &d.b_sigma,
            &d.vkf_source_rpm,
        ],
    )?;
    let col = |k: usize, j: usize| -> Vec<f64> {
        d.ne[k]
            .iter()
            .map(|p| if j == 0 { p.0 } else { p.1 })
            .collect()
    };
    let mut tr_headers = vec!["time_s".to_string()];
    let mut tr_cols = vec![t1.clone()];
    for k in 0..=METHODS.len() {
        let name = if k == 0 {
            "truth".to_string()
        } else {
            METHODS[k - 1].to_lowercase().replace('-', "_")
        };
        tr_headers.push(format!("{name}_north_m"));
        tr_headers.push(format!("{name}_east_m"));
        tr_cols.push(col(k, 0));
        tr_cols.push(col(k, 1));
    }
    let h: Vec<&str> = tr_headers.iter().map(String::as_str).collect();
    let cols: Vec<&[f64]> = tr_cols.iter().map(Vec::as_slice).collect();
    out.csv_columns("run0_trajectories.csv", &h, &cols)?;
    let run_idx: Vec<f64> = (0..runs.len()).map(|i| i as f64).collect();
    let mut pr_headers = vec!["run".to_string()];
    let mut pr_cols = vec![run_idx];
    for (m, name) in METHODS.iter().enumerate() {
        let mm = metrics(runs, m);
        let slug = name.to_lowercase().replace('-', "_");
        pr_headers.push(format!("{slug}_final_h_m"));
        pr_headers.push(format!("{slug}_rms_h_m"));
        pr_headers.push(format!("{slug}_rms_vel_mps"));
        pr_cols.push(mm.final_h);
        pr_cols.push(mm.rms_h);
        pr_cols.push(mm.rms_vel);
    }
    pr_headers.push("dvl_scale_factor".into());
    pr_cols.push(runs.iter().map(|r| r.dvl_scale_factor).collect());
    let h: Vec<&str> = pr_headers.iter().map(String::as_str).collect();
    let cols: Vec<&[f64]> = pr_cols.iter().map(Vec::as_slice).collect();
    out.csv_columns("per_run_metrics.csv", &h, &cols)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::unwrap_deg;

    #[test]
    fn unwrap_removes_the_wrap_and_keeps_small_steps() {
        assert_eq!(
            unwrap_deg(&[170.0, 179.0, -179.0, -170.0]),
            [170.0, 179.0, 181.0, 190.0]
        );
        assert_eq!(unwrap_deg(&[-170.0, 170.0]), [-170.0, -190.0]);
        // Negative control: steps below 180 deg are kept as they are.
        assert_eq!(unwrap_deg(&[0.0, 90.0, -80.0]), [0.0, 90.0, -80.0]);
    }
}
