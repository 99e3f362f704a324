//! What a scene page shows, as plain numbers in NED metres: the world mesh with its
//! materials, the true path, each method's estimate and mode, range scans and the
//! satellites' lines of sight. The job crates fill it; [`super::page`] draws it.

use crate::ReportError;

/// How a surface of the mesh is drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialStyle {
    /// The material's name as the legend shows it (`opaque`, `glass`, ...).
    pub name: String,
    /// Colour as `0xRRGGBB`.
    pub color: u32,
    /// Opacity in `[0, 1]` (glass below 1: translucent).
    pub opacity: f32,
}

/// The world as a triangle mesh, NED metres, one material index per triangle.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneMesh {
    /// Vertex positions (north, east, down), m.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle, an index into `styles`.
    pub material: Vec<u8>,
    /// The material styles.
    pub styles: Vec<MaterialStyle>,
}

/// One method's estimated path.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodTrack {
    /// The method's name.
    pub name: String,
    /// Estimated positions at the scene's epochs (NED, m).
    pub positions: Vec<[f32; 3]>,
    /// Active mode per epoch, an index into `mode_names`.
    pub mode: Vec<u8>,
    /// The modes' names (`GPS/INS`, `map-aided`, ...).
    pub mode_names: Vec<String>,
}

/// A range scan: where the sensor was and where its beams returned.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// Time, s.
    pub time: f64,
    /// Sensor position (NED, m).
    pub origin: [f32; 3],
    /// Return points (NED, m).
    pub hits: Vec<[f32; 3]>,
}

/// The satellites above the mask at one GNSS epoch.
#[derive(Debug, Clone, PartialEq)]
pub struct SkyEpoch {
    /// Time, s.
    pub time: f64,
    /// Per satellite: unit direction from the receiver (NED) and whether the true
    /// position sees it (not blocked by the mesh).
    pub sats: Vec<([f32; 3], bool)>,
}

/// One scene of a page: a world and what flew in it.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Its name (the scenario's name).
    pub name: String,
    /// The world.
    pub mesh: SceneMesh,
    /// Epoch times, s (increasing).
    pub times: Vec<f64>,
    /// True positions at the epochs (NED, m).
    pub truth: Vec<[f32; 3]>,
    /// The methods' estimates at the same epochs.
    pub methods: Vec<MethodTrack>,
    /// Range scans (any times, increasing).
    pub scans: Vec<Scan>,
    /// GNSS epochs (any times, increasing).
    pub sky: Vec<SkyEpoch>,
}

/// A page: a title and its scenes.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenePage {
    /// The page title (experiment and output folder).
    pub title: String,
    /// One line under the title (which run is shown, what was decimated).
    pub note: String,
    /// The scenes, selectable in the page.
    pub scenes: Vec<Scene>,
}

fn bad(what: String, reason: &str) -> ReportError {
    ReportError::invalid_argument(what, reason)
}

fn finite3(p: &[f32; 3]) -> bool {
    p.iter().all(|v| v.is_finite())
}

impl Scene {
    /// Checks sizes, indices and finiteness (a page never draws garbage silently).
    ///
    /// # Errors
    /// [`ReportError::InvalidArgument`] naming the scene and the series.
    pub fn check(&self) -> Result<(), ReportError> {
        let at = |s: &str| format!("scene `{}` {s}", self.name);
        let m = &self.mesh;
        if m.material.len() != m.triangles.len() {
            return Err(bad(at("mesh"), "one material per triangle needed"));
        }
        if m.styles.len() > usize::from(u8::MAX) + 1 {
            return Err(bad(at("mesh"), "more than 256 material styles"));
        }
        let nv = m.vertices.len();
        if m.triangles.iter().flatten().any(|&i| i as usize >= nv) {
            return Err(bad(at("mesh"), "a triangle names a missing vertex"));
        }
        if m.material.iter().any(|&k| usize::from(k) >= m.styles.len()) {
            return Err(bad(at("mesh"), "a triangle names a missing material style"));
        }
        if !m.vertices.iter().all(finite3) {
            return Err(bad(at("mesh"), "a vertex is not finite"));
        }
        if self.truth.len() != self.times.len() || !self.truth.iter().all(finite3) {
            return Err(bad(at("truth"), "one finite position per epoch needed"));
        }
        if !self.times.iter().all(|t| t.is_finite()) || self.times.windows(2).any(|w| w[1] < w[0]) {
            return Err(bad(at("times"), "times must be finite and increasing"));
        }
        for t in &self.methods {
            let w = at(&format!("method `{}`", t.name));
            if t.positions.len() != self.times.len() || t.mode.len() != self.times.len() {
                return Err(bad(w, "one position and one mode per epoch needed"));
            }
            if !t.positions.iter().all(finite3) {
                return Err(bad(w, "an estimated position is not finite"));
            }
            if t.mode.iter().any(|&k| usize::from(k) >= t.mode_names.len()) {
                return Err(bad(w, "a mode has no name"));
            }
        }
        let scans_ok = self
            .scans
            .iter()
            .all(|s| s.time.is_finite() && finite3(&s.origin) && s.hits.iter().all(finite3));
        if !scans_ok {
            return Err(bad(at("scans"), "a scan holds a value that is not finite"));
        }
        let sky_ok = self
            .sky
            .iter()
            .all(|e| e.time.is_finite() && e.sats.iter().all(|(d, _)| finite3(d)));
        if !sky_ok {
            return Err(bad(at("satellites"), "a direction is not finite"));
        }
        Ok(())
    }
}

/// Scenes for the tests of this module and its siblings.
#[cfg(test)]
pub(crate) mod tests_support {
    use super::*;

    /// A one-triangle world, two epochs, one method switching mode.
    pub(crate) fn small_scene() -> Scene {
        Scene {
            name: "s".into(),
            mesh: SceneMesh {
                vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                triangles: vec![[0, 1, 2]],
                material: vec![0],
                styles: vec![MaterialStyle {
                    name: "opaque".into(),
                    color: 0x888888,
                    opacity: 1.0,
                }],
            },
            times: vec![0.0, 1.0],
            truth: vec![[0.0; 3], [1.0, 0.0, 0.0]],
            methods: vec![MethodTrack {
                name: "m".into(),
                positions: vec![[0.0; 3], [1.0, 0.1, 0.0]],
                mode: vec![0, 1],
                mode_names: vec!["a".into(), "b".into()],
            }],
            scans: Vec::new(),
            sky: Vec::new(),
        }
    }

    /// `n` epochs along north at 1 m/s, one method in mode 0 throughout.
    pub(crate) fn scene_of_len(n: usize) -> Scene {
        let mut s = small_scene();
        s.times = (0..n).map(|k| k as f64).collect();
        s.truth = (0..n).map(|k| [k as f32, 0.0, -5.0]).collect();
        s.methods[0].positions = s.truth.clone();
        s.methods[0].mode = vec![0; n];
        s
    }
}

#[cfg(test)]
mod tests {
    use super::tests_support::small_scene;

    /// A consistent scene passes; each kind of inconsistency is refused by name.
    #[test]
    fn check_refuses_inconsistent_scenes() {
        assert!(small_scene().check().is_ok());
        let mut s = small_scene();
        s.mesh.triangles[0][2] = 3;
        assert!(
            s.check()
                .unwrap_err()
                .to_string()
                .contains("missing vertex")
        );
        let mut s = small_scene();
        s.methods[0].mode[1] = 2;
        assert!(
            s.check()
                .unwrap_err()
                .to_string()
                .contains("mode has no name")
        );
        let mut s = small_scene();
        s.times = vec![1.0, 0.0];
        assert!(s.check().unwrap_err().to_string().contains("increasing"));
        let mut s = small_scene();
        s.truth[1][0] = f32::NAN;
        assert!(s.check().unwrap_err().to_string().contains("truth"));
    }
}
