//! Thinning of a scene's time series for display: a page draws at most a few
//! thousand epochs, scans and beams whatever the flight's rates. Only the page is
//! thinned; the reports' numbers come from the full series.

use super::data::{Scan, Scene, SkyEpoch};

/// At most this many path epochs per scene (plus the epochs where a mode changes).
pub const MAX_EPOCHS: usize = 1500;
/// At most this many range scans per scene.
pub const MAX_SCANS: usize = 300;
/// At most this many returns per scan.
pub const MAX_HITS: usize = 240;
/// At most this many GNSS epochs per scene.
pub const MAX_SKY: usize = 600;

/// Indices `0..len` evenly spread, at most `max` of them, the first and the last
/// always kept (all of them when `len <= max`).
pub fn keep(len: usize, max: usize) -> Vec<usize> {
    if len <= max {
        return (0..len).collect();
    }
    if max < 2 {
        return vec![0];
    }
    let mut out: Vec<usize> = (0..max)
        .map(|k| ((k as f64) * (len - 1) as f64 / (max - 1) as f64).round() as usize)
        .collect();
    out.dedup();
    out
}

fn pick<T: Clone>(v: &[T], idx: &[usize]) -> Vec<T> {
    idx.iter().filter_map(|&i| v.get(i).cloned()).collect()
}

impl Scene {
    /// The scene thinned to the display limits: evenly spread epochs plus every epoch
    /// where a method's mode changes (and the one before it), so that no switch is
    /// lost; scans, beams and GNSS epochs evenly spread.
    pub fn decimated(&self) -> Scene {
        let n = self.times.len();
        let mut idx = keep(n, MAX_EPOCHS);
        if idx.len() < n {
            for m in &self.methods {
                for k in 1..m.mode.len() {
                    if m.mode[k] != m.mode[k - 1] {
                        idx.extend([k - 1, k]);
                    }
                }
            }
            idx.sort_unstable();
            idx.dedup();
        }
        let scans = pick(&self.scans, &keep(self.scans.len(), MAX_SCANS))
            .into_iter()
            .map(|s| Scan {
                hits: pick(&s.hits, &keep(s.hits.len(), MAX_HITS)),
                ..s
            })
            .collect();
        let sky: Vec<SkyEpoch> = pick(&self.sky, &keep(self.sky.len(), MAX_SKY));
        Scene {
            name: self.name.clone(),
            mesh: self.mesh.clone(),
            times: pick(&self.times, &idx),
            truth: pick(&self.truth, &idx),
            methods: self
                .methods
                .iter()
                .map(|m| super::data::MethodTrack {
                    name: m.name.clone(),
                    positions: pick(&m.positions, &idx),
                    mode: pick(&m.mode, &idx),
                    mode_names: m.mode_names.clone(),
                })
                .collect(),
            scans,
            sky,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Short series stay whole; long ones keep both ends and at most `max` indices.
    #[test]
    fn keep_spreads_and_keeps_the_ends() {
        assert_eq!(keep(3, 10), vec![0, 1, 2]);
        let k = keep(1001, 11);
        assert_eq!(k.len(), 11);
        assert_eq!((k[0], k[10]), (0, 1000));
        assert!(k.windows(2).all(|w| w[1] > w[0]));
        assert_eq!(keep(5, 1), vec![0]);
    }

    /// A one-epoch mode episode survives thinning: the switch in and out is shown.
    #[test]
    fn decimation_keeps_every_mode_switch() {
        let n = 10 * MAX_EPOCHS + 7;
        let mut s = super::super::data::tests_support::scene_of_len(n);
        s.methods[0].mode[4321] = 1;
        let d = s.decimated();
        assert!(d.times.len() <= MAX_EPOCHS + 4);
        let m = &d.methods[0].mode;
        assert_eq!(m.iter().filter(|&&x| x == 1).count(), 1);
        assert_eq!(m.len(), d.times.len());
        assert_eq!(d.truth.len(), d.times.len());
    }
}
