//! The `urban` figures (SVG) and per-time CSV files: the world in plan and side view
//! with the flown path and its GNSS-shadowed stretches, estimate versus truth per
//! method, mean errors versus time with the map-aided mode shaded, the LOS satellite
//! count, one scan over the map, the MGPMF grid weights and the error histograms.
//!
//! The map is drawn by casting rays against the scenario's own mesh (the figures see
//! the world as the sensors do): straight down on a plan grid for the structures'
//! footprints, straight up along the path for the ceiling (the bridge deck).

use fathom_core::RayCaster;
use nalgebra::Vector3;

use super::nav::Method;
use super::record::{BatchFold, SceneDetail};
use super::world::{Prepared, PreparedScene};
use fathom_report::plot::{HeatMap, Histogram, LinePlot, PlanPlot, Series};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

/// Plan-grid points per axis for the structures' footprints.
const PLAN_GRID: usize = 90;
/// Margin around the flown path in the plan figures, m.
const PLAN_MARGIN_M: f64 = 30.0;
/// A down-cast that hits this far above the lowest surface is a structure, m.
const STRUCTURE_MIN_HEIGHT_M: f64 = 1.0;

/// The structures' footprints inside `lo ..= hi` (north, east) as plan points
/// `(east, north)`: a grid cast straight down from above the mesh.
pub(super) fn footprints(scene: &PreparedScene, lo: [f64; 2], hi: [f64; 2]) -> Vec<(f64, f64)> {
    let Some((min, max)) = scene.mesh.bounds() else {
        return Vec::new();
    };
    let top = min.z - 1.0;
    let ground = max.z;
    let depth = ground - top + 1.0;
    let mut out = Vec::new();
    for i in 0..PLAN_GRID {
        for j in 0..PLAN_GRID {
            let n = lo[0] + (hi[0] - lo[0]) * i as f64 / (PLAN_GRID - 1) as f64;
            let e = lo[1] + (hi[1] - lo[1]) * j as f64 / (PLAN_GRID - 1) as f64;
            let from = Vector3::new(n, e, top);
            let structure = scene
                .caster
                .cast(&from, &Vector3::z(), depth)
                .is_some_and(|hit| top + hit.range < ground - STRUCTURE_MIN_HEIGHT_M);
            if structure {
                out.push((e, n));
            }
        }
    }
    out
}

/// The `(east, north)` size of one footprint cell of [`footprints`] over `lo ..= hi`.
fn footprint_cell(lo: [f64; 2], hi: [f64; 2]) -> (f64, f64) {
    let step = |a: usize| (hi[a] - lo[a]) / (PLAN_GRID - 1) as f64;
    (step(1), step(0))
}

/// `(north, east)` bounds of the truth with the plan margin.
fn plan_bounds(truth: &[[f64; 3]]) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in truth {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a] - PLAN_MARGIN_M);
            hi[a] = hi[a].max(p[a] + PLAN_MARGIN_M);
        }
    }
    (lo, hi)
}

/// Intervals `[from, to]` of `times` where `flag` holds.
pub(super) fn intervals(times: &[f64], flag: &[bool]) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut start = None;
    for (k, (&t, &f)) in times.iter().zip(flag).enumerate() {
        match (f, start) {
            (true, None) => start = Some(t),
            (false, Some(s)) => {
                out.push((s, times[k - 1].max(s)));
                start = None;
            }
            _ => {}
        }
    }
    if let (Some(s), Some(&last)) = (start, times.last()) {
        out.push((s, last));
    }
    out
}

/// The paper's method of a scenario (its mode is the shaded one).
fn paired_method(detail_ranging_is_lidar: bool) -> Method {
    if detail_ranging_is_lidar {
        Method::Grekf
    } else {
        Method::Mgpmf
    }
}

/// Writes the figures and the per-time CSV files.
pub(super) fn write(prep: &Prepared, fold: &BatchFold, out: &mut Analysis) -> Result<(), SimError> {
    let c = &prep.checked;
    let eval_dt = c.imu.dt() * c.steps.eval as f64;
    for (s, spec) in c.scenes.iter().enumerate() {
        let Some(methods) = fold.scenes.get(s) else {
            continue;
        };
        let name = &spec.name;
        let means: Vec<_> = methods.iter().map(|m| m.means()).collect();
        let n = means.iter().map(|m| m.0.len()).min().unwrap_or(0);
        let time: Vec<f64> = (1..=n).map(|k| c.rest_s + k as f64 * eval_dt).collect();
        let mut headers = vec!["time_s".to_string()];
        let mut cols: Vec<Vec<f64>> = vec![time.clone()];
        for (m, (e3, ev, ea)) in c.methods.iter().zip(&means) {
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
        out.csv_columns(&format!("mean_errors_{name}.csv"), &h, &cr)?;
        let detail = fold.detail.as_ref().and_then(|d| d.get(s));
        let paired = paired_method(matches!(spec.ranging, super::scenario::Ranging::Lidar));
        // The paired method's map-aided intervals, when it ran (`methods`).
        let paired_index = c.index_of(paired);
        let shade = detail
            .zip(paired_index)
            .and_then(|(d, i)| d.map_mode.get(i).map(|mode| intervals(&d.times, mode)))
            .unwrap_or_default();
        // Map-aided over (nearly) the whole flight: said in the title instead of a
        // shading that covers the plot.
        let span = time.last().copied().unwrap_or(0.0) - time.first().copied().unwrap_or(0.0);
        let covered: f64 = shade.iter().map(|(a, b)| b - a).sum();
        let throughout = span > 0.0 && covered >= 0.95 * span;
        if n > 1 {
            for (k, (what, unit)) in [
                ("3-D position error", "m"),
                ("velocity error", "m/s"),
                ("attitude error", "deg"),
            ]
            .iter()
            .enumerate()
            {
                // Diverged curves are cut at a cap so the map-aided ones stay
                // readable; the title says so when a curve reaches it.
                let cap = clip(k);
                let capped = means
                    .iter()
                    .any(|mm| [&mm.0, &mm.1, &mm.2][k][..n].iter().any(|v| *v > cap));
                let mut title = format!("{name}: mean {what} over {} runs", c.runs);
                if capped {
                    title.push_str(&format!(", cut at {cap} {unit}"));
                }
                if paired_index.is_some() && throughout {
                    title.push_str(&format!("; {} map-aided throughout (run 0)", paired.name()));
                }
                let mut plot = LinePlot::new(title, "time (s)", format!("{what} ({unit})"));
                for (m, mm) in c.methods.iter().zip(&means) {
                    let y = [&mm.0, &mm.1, &mm.2][k];
                    let y: Vec<f64> = y[..n].iter().map(|v| v.min(cap)).collect();
                    plot.series.push(Series::from_xy(m.name(), &time, &y)?);
                }
                if !throughout {
                    plot.shaded_x.clone_from(&shade);
                    plot.shaded_label = format!("{} map-aided mode (run 0)", paired.name());
                }
                let file = ["pos", "vel", "att"][k];
                out.figure(&format!("errors_{file}_{name}.svg"), &plot)?;
            }
        }
        let hist_hi = c.histogram.0;
        for (m, mf) in c.methods.iter().zip(methods) {
            let bins = c.histogram.1;
            if mf.hist.len() != bins + 1 || mf.hist.iter().all(|h| *h == 0) {
                continue;
            }
            let edges: Vec<f64> = (0..=bins)
                .map(|b| hist_hi * b as f64 / bins as f64)
                .collect();
            let beyond = mf.hist[bins];
            let total: u64 = mf.hist.iter().sum();
            let pct = 100.0 * beyond as f64 / total.max(1) as f64;
            let plot = Histogram::new(
                format!(
                    "{name}/{}: 3-D position error, {total} samples of all runs ({beyond} = {pct:.0} % beyond {hist_hi} m)",
                    m.name()
                ),
                "3-D position error (m)",
                "count",
                edges,
                mf.hist[..bins].iter().map(|h| *h as f64).collect(),
            );
            out.figure(&format!("histogram_{name}_{}.svg", m.slug()), &plot)?;
        }
        if let Some(d) = detail {
            run0_csv(name, &c.methods, d, out)?;
            run0_figures(prep, s, d, out)?;
        }
    }
    Ok(())
}

/// Clip of the error curves per quantity (position m, velocity m/s, attitude deg).
fn clip(k: usize) -> f64 {
    [20.0, 2.0, 5.0][k]
}

fn run0_csv(
    name: &str,
    methods: &[Method],
    d: &SceneDetail,
    out: &mut Analysis,
) -> Result<(), SimError> {
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
    for (m, (est, mode)) in methods.iter().zip(d.estimates.iter().zip(&d.map_mode)) {
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
    out.csv_columns(&format!("run0_{name}.csv"), &h, &cr)
}

/// The run-0 figures of scenario `s`: world plan and side view, estimates, LOS count,
/// scan, grid.
fn run0_figures(
    prep: &Prepared,
    s: usize,
    d: &SceneDetail,
    out: &mut Analysis,
) -> Result<(), SimError> {
    let c = &prep.checked;
    let scene = &prep.scenes[s];
    let name = &c.scenes[s].name;
    let k = d.times.len().min(d.truth.len());
    if k < 2 {
        return Ok(());
    }
    let truth = &d.truth[..k];
    let (lo, hi) = plan_bounds(truth);
    let structures = footprints(scene, lo, hi);
    let plan_truth = Series::new("truth", truth.iter().map(|p| (p[1], p[0])).collect());
    // GNSS-shadowed truth points: the true LOS count of the last GNSS epoch below
    // the count at which the switching methods leave GPS/INS (the threshold run.rs
    // counts the shadowed epochs with)
    let threshold = c.filter.switch.leave_gps_below();
    let reenter = c.filter.switch.enter_gps_at();
    let mut g = 0;
    let mut shadowed = Vec::new();
    for (t, p) in d.times[..k].iter().zip(truth) {
        while g + 1 < d.gnss.len() && d.gnss[g + 1].0 <= *t {
            g += 1;
        }
        if d.gnss.get(g).is_some_and(|e| e.1 < threshold) {
            shadowed.push((p[1], p[0]));
        }
    }
    // Structures and shadowed stretches under the paths, in fixed colours.
    let with_world = |plot: PlanPlot| {
        let plot = if structures.is_empty() {
            plot
        } else {
            plot.with_area(
                Series::new("structures", structures.clone()),
                footprint_cell(lo, hi),
            )
        };
        if shadowed.is_empty() {
            plot
        } else {
            plot.with_highlight(Series::new(
                format!("GNSS-shadowed (< {threshold} LOS satellites)"),
                shadowed.clone(),
            ))
        }
    };
    let plan = with_world(PlanPlot::new(
        format!("{name}: plan view, flown path (run 0) and shadowed stretches"),
        "east (m)",
        "north (m)",
    ))
    .with_path(plan_truth.clone());
    out.figure(&format!("world_plan_{name}.svg"), &plan)?;
    // side view: height against distance flown, with the ceiling above the path
    let mut dist = vec![0.0];
    for w in truth.windows(2) {
        let step = ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt();
        dist.push(dist.last().copied().unwrap_or(0.0) + step);
    }
    let heights: Vec<f64> = truth.iter().map(|p| -p[2]).collect();
    let mut side = LinePlot::new(
        format!("{name}: side view along the path"),
        "distance flown (m)",
        "height (m)",
    )
    .with_series(Series::from_xy("truth", &dist, &heights)?);
    let ceiling: Vec<(f64, f64)> = truth
        .iter()
        .zip(&dist)
        .filter_map(|(p, x)| {
            let from = Vector3::new(p[0], p[1], p[2]);
            scene
                .caster
                .cast(&from, &-Vector3::z(), 200.0)
                .map(|h| (*x, -p[2] + h.range))
        })
        .collect();
    if !ceiling.is_empty() {
        side.series
            .push(Series::new("structure above the path", ceiling));
    }
    let shadow_flag: Vec<bool> = {
        let mut g = 0;
        d.times[..k]
            .iter()
            .map(|t| {
                while g + 1 < d.gnss.len() && d.gnss[g + 1].0 <= *t {
                    g += 1;
                }
                d.gnss.get(g).is_some_and(|e| e.1 < threshold)
            })
            .collect()
    };
    let shadowed_x = intervals(&dist, &shadow_flag);
    let total = dist.last().copied().unwrap_or(0.0);
    if total > 0.0 && shadowed_x.iter().map(|(a, b)| b - a).sum::<f64>() >= 0.95 * total {
        // Shadowed all along: said in the title, not by a shading over the plot.
        side.title = format!("{name}: side view along the path (GNSS-shadowed all along)");
    } else {
        side.shaded_x = shadowed_x;
        side.shaded_label = "GNSS-shadowed".to_string();
    }
    out.figure(&format!("world_side_{name}.svg"), &side)?;
    for (m, est) in c.methods.iter().zip(&d.estimates) {
        let est: Vec<(f64, f64)> = est[..k.min(est.len())]
            .iter()
            .filter(|p| p[0] > lo[0] - 100.0 && p[0] < hi[0] + 100.0)
            .filter(|p| p[1] > lo[1] - 100.0 && p[1] < hi[1] + 100.0)
            .map(|p| (p[1], p[0]))
            .collect();
        if est.len() < 2 {
            continue;
        }
        let plot = with_world(PlanPlot::new(
            format!("{name}/{}: estimate vs truth (run 0)", m.name()),
            "east (m)",
            "north (m)",
        ))
        .with_path(plan_truth.clone())
        .with_path(Series::new(format!("{} estimate", m.name()), est));
        out.figure(&format!("estimate_{name}_{}.svg", m.slug()), &plot)?;
    }
    if d.gnss.len() > 1 {
        let t: Vec<f64> = d.gnss.iter().map(|g| g.0).collect();
        let n: Vec<f64> = d.gnss.iter().map(|g| g.1 as f64).collect();
        let leave = vec![threshold as f64; t.len()];
        let back = vec![reenter as f64; t.len()];
        let plot = LinePlot::new(
            format!("{name}: satellites in true line of sight (run 0)"),
            "time (s)",
            "satellites",
        )
        .with_series(Series::from_xy("LOS satellites", &t, &n)?)
        .with_series(Series::from_xy(
            format!("leave GPS/INS below {threshold} (switch.min_los_satellites)"),
            &t,
            &leave,
        )?)
        .with_series(Series::from_xy(
            format!("re-enter GPS/INS at {reenter} (+ hysteresis)"),
            &t,
            &back,
        )?);
        out.figure(&format!("los_satellites_{name}.svg"), &plot)?;
    }
    if let Some(scan) = d.scan.as_ref().filter(|s| !s.hits.is_empty()) {
        // The map around the vehicle and every return, with a margin.
        let margin = 5.0;
        let mut slo = [scan.pos[0] - margin, scan.pos[1] - margin];
        let mut shi = [scan.pos[0] + margin, scan.pos[1] + margin];
        for h in &scan.hits {
            for a in 0..2 {
                slo[a] = slo[a].min(h[a] - margin);
                shi[a] = shi[a].max(h[a] + margin);
            }
        }
        let mut plot = PlanPlot::new(
            format!(
                "{name}: one range scan over the map at t = {:.1} s (run 0)",
                scan.time
            ),
            "east (m)",
            "north (m)",
        );
        let fp = footprints(scene, slo, shi);
        if !fp.is_empty() {
            plot = plot.with_area(Series::new("structures", fp), footprint_cell(slo, shi));
        }
        plot = plot
            .with_markers(Series::new(
                "returns",
                scan.hits.iter().map(|h| (h[1], h[0])).collect(),
            ))
            .with_markers(Series::new("vehicle", vec![(scan.pos[1], scan.pos[0])]));
        out.figure(&format!("scan_{name}.svg"), &plot)?;
    }
    if let Some(grid) = d.grid.as_ref().filter(|g| !g.weights.is_empty()) {
        // North up: the last grid row (largest north error) on top.
        let mut plot = HeatMap::new(
            format!(
                "{name}: MGPMF weights (sum over yaw), rows north / columns east error (m), t = {:.1} s",
                grid.time
            ),
            grid.north.iter().rev().map(|v| format!("{v:.3}")).collect(),
            grid.east.iter().map(|v| format!("{v:.3}")).collect(),
            grid.weights.iter().rev().cloned().collect(),
        );
        plot.decimals = 2;
        plot.value_label = "weight".into();
        plot.size = (1000, 900);
        out.figure(&format!("mgpmf_grid_{name}.svg"), &plot)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_cover_the_flagged_runs() {
        let t = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let f = [false, true, true, false, true, true];
        assert_eq!(intervals(&t, &f), vec![(1.0, 2.0), (4.0, 5.0)]);
        assert!(intervals(&t, &[false; 6]).is_empty());
        assert_eq!(intervals(&t, &[true; 6]), vec![(0.0, 5.0)]);
    }
}
