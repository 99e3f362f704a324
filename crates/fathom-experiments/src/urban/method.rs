//! The names of `urban`'s navigation methods (what a scenario's `methods` selects and
//! every row, figure and record names); what each one does is in [`super::nav`].

use serde::{Deserialize, Serialize};

/// The navigation methods ([`super::nav`]), in report order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Method {
    /// No aiding.
    InsOnly,
    /// GPS/INS with the line-of-sight test.
    GpsIns,
    /// GPS/INS with every received satellite.
    GpsInsAllSats,
    /// Switching GPS/INS and GREKF.
    Grekf,
    /// Switching GPS/INS and MGPMF.
    Mgpmf,
    /// Switching GPS/INS and the particle filter.
    Particle,
}

impl Method {
    /// Every method, in report order.
    pub const ALL: [Method; 6] = [
        Method::InsOnly,
        Method::GpsIns,
        Method::GpsInsAllSats,
        Method::Grekf,
        Method::Mgpmf,
        Method::Particle,
    ];

    /// The name in rows and figures.
    pub fn name(self) -> &'static str {
        match self {
            Method::InsOnly => "INS-only",
            Method::GpsIns => "GPS/INS",
            Method::GpsInsAllSats => "GPS/INS-all-sats",
            Method::Grekf => "GREKF",
            Method::Mgpmf => "MGPMF",
            Method::Particle => "PF",
        }
    }

    /// The method of a name.
    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Whether the method switches between GPS/INS and a map-aided update.
    pub fn is_switching(self) -> bool {
        matches!(self, Method::Grekf | Method::Mgpmf | Method::Particle)
    }

    /// File-name form of the name (`gps_ins_all_sats`).
    pub fn slug(self) -> String {
        self.name().to_ascii_lowercase().replace(['/', '-'], "_")
    }
}
