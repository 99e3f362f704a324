//! The `urban` figures (SVG) and per-time CSV files.

use super::nav::Method;
use super::record::BatchFold;
use super::world::Prepared;
use crate::SimError;
use crate::experiment::Analysis;

/// Writes the figures and the per-time CSV files.
pub(super) fn write(prep: &Prepared, fold: &BatchFold, out: &mut Analysis) -> Result<(), SimError> {
    let c = &prep.checked;
    let eval_dt = c.imu.dt() * c.steps.eval as f64;
    for (s, spec) in c.scenes.iter().enumerate() {
        let Some(methods) = fold.scenes.get(s) else {
            continue;
        };
        let means: Vec<_> = methods.iter().map(|m| m.means()).collect();
        let n = means.iter().map(|m| m.0.len()).min().unwrap_or(0);
        let time: Vec<f64> = (1..=n).map(|k| c.rest_s + k as f64 * eval_dt).collect();
        let mut headers = vec!["time_s".to_string()];
        let mut cols: Vec<Vec<f64>> = vec![time];
        for (m, (e3, ev, ea)) in Method::ALL.iter().zip(&means) {
            let slug = m.slug();
            headers.push(format!("{slug}_err_3d_m"));
            cols.push(e3[..n].to_vec());
            headers.push(format!("{slug}_err_vel_mps"));
            cols.push(ev[..n].to_vec());
            headers.push(format!("{slug}_err_att_deg"));
            cols.push(ea[..n].to_vec());
        }
        let h: Vec<&str> = headers.iter().map(String::as_str).collect();
        let cr: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        out.csv_columns(&format!("mean_errors_{}.csv", spec.name), &h, &cr)?;
        if let Some(d) = fold.detail.as_ref().and_then(|d| d.get(s)) {
            let mut headers = vec![
                "time_s".to_string(),
                "true_n_m".into(),
                "true_e_m".into(),
                "true_d_m".into(),
            ];
            let k = d.times.len().min(d.truth.len());
            let mut cols: Vec<Vec<f64>> = vec![d.times[..k].to_vec()];
            for i in 0..3 {
                cols.push(d.truth[..k].iter().map(|p| p[i]).collect());
            }
            for (m, (est, mode)) in Method::ALL.iter().zip(d.estimates.iter().zip(&d.map_mode)) {
                let slug = m.slug();
                for (i, a) in ["n", "e", "d"].iter().enumerate() {
                    headers.push(format!("{slug}_est_{a}_m"));
                    cols.push(est[..k].iter().map(|p| p[i]).collect());
                }
                headers.push(format!("{slug}_map_aided"));
                cols.push(mode[..k].iter().map(|b| f64::from(u8::from(*b))).collect());
            }
            let h: Vec<&str> = headers.iter().map(String::as_str).collect();
            let cr: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
            out.csv_columns(&format!("run0_{}.csv", spec.name), &h, &cr)?;
        }
    }
    Ok(())
}
