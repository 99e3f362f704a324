//! The settings of a PILS session (a TOML file): the `urban` scenario flown (its
//! file, the scene, the method, the run index) and the link (pacing, timeouts,
//! faults, signing).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::PilsError;
use crate::faults::FaultParams;

/// Pacing of the simulator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pacing {
    /// Each step waits for the navigation's solution (deterministic).
    Lockstep,
    /// Steps go out on the wall clock; late solutions are counted, not waited for.
    Realtime,
}

/// Link settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LinkParams {
    /// Pacing.
    pub pacing: Pacing,
    /// Silence after which either side gives up, s (0.001 ... 600).
    pub timeout_s: f64,
    /// Lockstep: resend a step's messages after this long without its solution, s.
    pub retransmit_s: f64,
    /// MAVLink 2 signing: the shared key is the SHA-256 of this passphrase (none:
    /// unsigned frames).
    pub signing_passphrase: Option<String>,
    /// Faults applied by both senders.
    pub faults: FaultParams,
}

impl Default for LinkParams {
    fn default() -> Self {
        Self {
            pacing: Pacing::Lockstep,
            timeout_s: 3.0,
            retransmit_s: 0.2,
            signing_passphrase: None,
            faults: FaultParams::NONE,
        }
    }
}

/// A PILS settings file: the `urban` scenario flown and the link. `fathom pils` also
/// takes an `urban` scenario file itself (the link's defaults, its first scene and
/// map-aided method).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PilsFile {
    /// Must be `"pils"`.
    pub experiment: String,
    /// The `urban` scenario file flown, relative to this file's folder.
    pub scenario: String,
    /// The scene flown (a `[[scenarios]]` name; none: the first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<String>,
    /// The navigation method (one of the scenario's; none: its first map-aided one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<String>,
    /// Run index: the run's random streams are those of run `run` of `fathom run`.
    #[serde(default)]
    pub run: u64,
    /// The link.
    #[serde(default)]
    pub link: LinkParams,
}

/// Checked settings with the `urban` scenario they fly.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// The settings (for an `urban` file given directly: the defaults, naming it).
    pub file: PilsFile,
    /// The `urban` scenario's text.
    pub scenario_text: String,
    /// Where it was read (its folder is where its world files are looked up).
    pub scenario_path: PathBuf,
    /// The scenario's `base_seed` (the link's fault streams are seeded from it).
    pub seed: u64,
    /// Whether the simulator side writes the 3D scene page `scene.html` (`--no-scene`:
    /// no; not a key of the file).
    pub scene_page: bool,
}

/// Largest settings or scenario file read, bytes.
const MAX_FILE_BYTES: u64 = 16 << 20;

/// Reads a regular file of at most [`MAX_FILE_BYTES`].
fn read_file(path: &Path, what: &str) -> Result<String, PilsError> {
    let bad = |reason: String| PilsError::setting(what, path.display(), reason);
    let meta = std::fs::metadata(path).map_err(|e| bad(e.to_string()))?;
    if !meta.is_file() {
        return Err(bad("is not a regular file".into()));
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(bad(format!(
            "is {} bytes, more than the {MAX_FILE_BYTES} a settings file may have",
            meta.len()
        )));
    }
    std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))
}

impl Settings {
    /// Reads the settings of `fathom pils FILE`: PILS settings (`experiment =
    /// "pils"`) and the `urban` scenario they name, or an `urban` scenario file.
    ///
    /// # Errors
    /// [`PilsError::Setting`] naming the key or file.
    pub fn load(path: &Path) -> Result<Self, PilsError> {
        let text = read_file(path, "file")?;
        Self::from_text(&text, path)
    }

    /// [`Settings::load`] on the text of the file at `path`.
    ///
    /// # Errors
    /// As [`Settings::load`].
    pub fn from_text(text: &str, path: &Path) -> Result<Self, PilsError> {
        let table: toml::Table = toml::from_str(text)
            .map_err(|e| PilsError::setting("file", "TOML", e.to_string().trim().to_string()))?;
        let experiment = table.get("experiment").and_then(toml::Value::as_str);
        let (file, scenario_text, scenario_path) = match experiment {
            Some("urban") => (
                PilsFile {
                    experiment: "pils".into(),
                    scenario: path.display().to_string(),
                    scene: None,
                    method: None,
                    run: 0,
                    link: LinkParams::default(),
                },
                text.to_string(),
                path.to_path_buf(),
            ),
            _ => {
                let f: PilsFile = toml::from_str(text).map_err(|e| {
                    PilsError::setting("file", "TOML", e.to_string().trim().to_string())
                })?;
                if f.experiment != "pils" {
                    return Err(PilsError::setting(
                        "experiment",
                        &f.experiment,
                        "must be \"pils\" (settings naming an `urban` scenario) or \"urban\" (the scenario itself)",
                    ));
                }
                let p = path.parent().unwrap_or(Path::new(".")).join(&f.scenario);
                let t = read_file(&p, "scenario")?;
                (f, t, p)
            }
        };
        let seed = toml::from_str::<toml::Table>(&scenario_text)
            .ok()
            .and_then(|t| t.get("base_seed").and_then(toml::Value::as_integer))
            .and_then(|s| u64::try_from(s).ok())
            .unwrap_or(0);
        file.link.check()?;
        Ok(Self {
            file,
            scenario_text,
            scenario_path,
            seed,
            scene_page: true,
        })
    }

    /// The signing key, if any.
    pub fn key(&self) -> Option<[u8; 32]> {
        self.file
            .link
            .signing_passphrase
            .as_deref()
            .map(crate::frame::Signing::key_from_passphrase)
    }
}

impl LinkParams {
    /// Checks the link settings.
    ///
    /// # Errors
    /// [`PilsError::Setting`] naming the field.
    pub fn check(&self) -> Result<(), PilsError> {
        let l = self;
        // below 1 ms no answer can come back, even on loopback
        if !(l.timeout_s >= 1e-3 && l.timeout_s <= 600.0) {
            return Err(PilsError::setting(
                "link.timeout_s",
                l.timeout_s,
                "must be in [0.001, 600] s",
            ));
        }
        if !(l.retransmit_s > 0.0 && l.retransmit_s < l.timeout_s) {
            return Err(PilsError::setting(
                "link.retransmit_s",
                l.retransmit_s,
                format!("must be in (0, link.timeout_s = {} s)", l.timeout_s),
            ));
        }
        if l.signing_passphrase.as_deref() == Some("") {
            // An empty passphrase would sign with a key anyone can derive.
            return Err(PilsError::setting(
                "link.signing_passphrase",
                "\"\"",
                "must not be empty (leave the key out for no signing)",
            ));
        }
        l.faults.check().map(drop)
    }
}
