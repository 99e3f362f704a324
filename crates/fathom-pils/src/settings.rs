//! The settings of a PILS session (a TOML file): the run (seed, run index, method,
//! flight and sensors) and the link (pacing, timeouts, faults, signing).

use serde::{Deserialize, Serialize};

use crate::PilsError;
use crate::faults::FaultParams;
use crate::scenario::{Method, RunParams};

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
    /// Silence after which either side gives up, s.
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

/// A PILS settings file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PilsFile {
    /// Must be `"pils"`.
    pub experiment: String,
    /// Base seed.
    #[serde(default = "one")]
    pub seed: u64,
    /// Run index (its own random stream).
    #[serde(default)]
    pub run: u64,
    /// The navigation method (`INS-only`, `GPS/INS`, `GREKF`, `MGPMF`).
    #[serde(default = "mgpmf")]
    pub method: String,
    /// Flight and sensors.
    #[serde(default)]
    pub flight: RunParams,
    /// The link.
    #[serde(default)]
    pub link: LinkParams,
}

fn one() -> u64 {
    1
}

fn mgpmf() -> String {
    "MGPMF".into()
}

/// Checked settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// The file's content.
    pub file: PilsFile,
    /// The method.
    pub method: Method,
}

impl PilsFile {
    /// Parses and checks TOML text.
    ///
    /// # Errors
    /// [`PilsError::Setting`] naming the problem.
    pub fn parse(text: &str) -> Result<Settings, PilsError> {
        let f: PilsFile = toml::from_str(text)
            .map_err(|e| PilsError::setting("file", "TOML", e.to_string().trim().to_string()))?;
        f.check()
    }

    /// Checks the settings.
    ///
    /// # Errors
    /// [`PilsError::Setting`] naming the field.
    pub fn check(self) -> Result<Settings, PilsError> {
        if self.experiment != "pils" {
            return Err(PilsError::setting(
                "experiment",
                &self.experiment,
                "must be \"pils\"",
            ));
        }
        let method = Method::from_name(&self.method).ok_or_else(|| {
            PilsError::setting(
                "method",
                &self.method,
                "must be INS-only, GPS/INS, GREKF or MGPMF",
            )
        })?;
        let l = &self.link;
        if !(l.timeout_s > 0.0 && l.timeout_s <= 600.0) {
            return Err(PilsError::setting(
                "link.timeout_s",
                l.timeout_s,
                "must be in (0, 600]",
            ));
        }
        if !(l.retransmit_s > 0.0 && l.retransmit_s < l.timeout_s) {
            return Err(PilsError::setting(
                "link.retransmit_s",
                l.retransmit_s,
                "must be in (0, timeout_s)",
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
        l.faults.check()?;
        Ok(Settings { file: self, method })
    }
}

impl Settings {
    /// The signing key, if any.
    pub fn key(&self) -> Option<[u8; 32]> {
        self.file
            .link
            .signing_passphrase
            .as_deref()
            .map(crate::frame::Signing::key_from_passphrase)
    }
}
