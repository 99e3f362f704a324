//! The units a column header of the own-data layout may declare (`range[m]`,
//! `heading[deg]`), per physical quantity, and their conversion into SI once, when the
//! file is read (project rule: conversions at the boundary, with named functions).

use fathom_core::units::{STANDARD_GRAVITY, deg_per_hour_to_rad_per_s, deg_to_rad, knots_to_mps};

/// What a column measures; decides the accepted units and the plausibility bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Time stamp, s.
    Time,
    /// Position, distance, range, depth, m.
    Length,
    /// Heading, roll, pitch, latitude, longitude, an angle increment, rad.
    Angle,
    /// Angular rate (gyro), rad/s.
    AngularRate,
    /// Velocity, velocity increment, m/s.
    Speed,
    /// Specific force (accelerometer), m/s².
    Acceleration,
    /// Propeller speed, rev/min.
    Rpm,
    /// Magnetic flux density (magnetometer), T.
    MagneticField,
    /// A number without unit: a beacon id, a 0/1 flag.
    Count,
}

/// `(spelling, factor or conversion)` of every accepted unit, SI first.
type Conversion = fn(f64) -> f64;

fn identity(v: f64) -> f64 {
    v
}

fn g_to_mps2(v: f64) -> f64 {
    v * STANDARD_GRAVITY
}

fn per_minute(v: f64) -> f64 {
    v
}

/// Gauss (PX4's magnetometer unit) to tesla.
fn gauss_to_tesla(v: f64) -> f64 {
    v * 1e-4
}

fn microtesla_to_tesla(v: f64) -> f64 {
    v * 1e-6
}

impl Quantity {
    /// The accepted unit spellings and their conversions into the SI unit (the first).
    fn units(self) -> &'static [(&'static str, Conversion)] {
        match self {
            Quantity::Time => &[("s", identity)],
            Quantity::Length => &[("m", identity)],
            Quantity::Angle => &[("rad", identity), ("deg", deg_to_rad)],
            Quantity::AngularRate => &[
                ("rad/s", identity),
                ("deg/s", deg_to_rad),
                ("deg/h", deg_per_hour_to_rad_per_s),
            ],
            Quantity::Speed => &[("m/s", identity), ("kn", knots_to_mps)],
            Quantity::Acceleration => &[("m/s^2", identity), ("g", g_to_mps2)],
            Quantity::Rpm => &[("rpm", per_minute), ("1/min", per_minute)],
            Quantity::MagneticField => &[
                ("T", identity),
                ("G", gauss_to_tesla),
                ("uT", microtesla_to_tesla),
            ],
            Quantity::Count => &[],
        }
    }

    /// What the quantity is, for messages.
    pub fn describe(self) -> &'static str {
        match self {
            Quantity::Time => "a time",
            Quantity::Length => "a length",
            Quantity::Angle => "an angle",
            Quantity::AngularRate => "an angular rate",
            Quantity::Speed => "a velocity",
            Quantity::Acceleration => "a specific force",
            Quantity::Rpm => "a propeller speed",
            Quantity::MagneticField => "a magnetic flux density",
            Quantity::Count => "a number without unit",
        }
    }

    /// The accepted spellings, for messages (`rad, deg`).
    pub fn accepted(self) -> String {
        self.units()
            .iter()
            .map(|(u, _)| *u)
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The SI spelling (`m`, `rad/s`); empty for [`Quantity::Count`].
    pub fn si(self) -> &'static str {
        self.units().first().map_or("", |u| u.0)
    }

    /// Whether the quantity carries a unit at all.
    pub fn has_unit(self) -> bool {
        !self.units().is_empty()
    }

    /// The conversion of `unit` into SI, if the unit is accepted.
    pub fn conversion(self, unit: &str) -> Option<Unit> {
        self.units()
            .iter()
            .find(|(u, _)| *u == unit)
            .map(|&(spelling, to_si)| Unit { spelling, to_si })
    }

    /// The largest plausible magnitude in SI: a value beyond it is refused when read
    /// (a beacon 10^308 m away or an IMU at 10^6 rad/s is a broken file, not a
    /// measurement, and would overflow the filters' arithmetic). Times up to 10^12 s
    /// (about 31,700 years: Unix stamps pass), positions 10^7 m, speeds 10^3 m/s,
    /// angles 10^3 rad (unwrapped headings pass), rates 10^3 rad/s, specific forces
    /// 10^4 m/s², propeller speeds 10^6 rpm, magnetic fields 1 T, counts 10^15.
    pub fn bound(self) -> f64 {
        match self {
            Quantity::Time => 1e12,
            Quantity::Length => 1e7,
            Quantity::Angle => 1e3,
            Quantity::AngularRate => 1e3,
            Quantity::Speed => 1e3,
            Quantity::Acceleration => 1e4,
            Quantity::Rpm => 1e6,
            Quantity::MagneticField => 1.0,
            Quantity::Count => 1e15,
        }
    }
}

/// An accepted unit of a column and its conversion into SI.
#[derive(Debug, Clone, Copy)]
pub struct Unit {
    /// The spelling in the header.
    pub spelling: &'static str,
    to_si: Conversion,
}

impl Unit {
    /// The identity "unit" of a [`Quantity::Count`] column.
    pub fn none() -> Self {
        Unit {
            spelling: "",
            to_si: identity,
        }
    }

    /// `value` (in this unit) in SI.
    pub fn to_si(&self, value: f64) -> f64 {
        (self.to_si)(value)
    }
}

impl PartialEq for Unit {
    fn eq(&self, other: &Self) -> bool {
        self.spelling == other.spelling
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_convert_once_into_si() {
        let deg = Quantity::Angle.conversion("deg").unwrap();
        assert!((deg.to_si(180.0) - std::f64::consts::PI).abs() < 1e-15);
        let dph = Quantity::AngularRate.conversion("deg/h").unwrap();
        assert!((dph.to_si(3600.0) - 1f64.to_radians()).abs() < 1e-15);
        let kn = Quantity::Speed.conversion("kn").unwrap();
        assert!((kn.to_si(1.0) - 1852.0 / 3600.0).abs() < 1e-15);
        let g = Quantity::Acceleration.conversion("g").unwrap();
        assert_eq!(g.to_si(1.0), 9.806_65);
        assert_eq!(Quantity::Length.conversion("m").unwrap().to_si(2.5), 2.5);
        let gauss = Quantity::MagneticField.conversion("G").unwrap();
        assert!((gauss.to_si(0.5) - 5e-5).abs() < 1e-20);
        // Negative controls: a unit of another quantity, a unit the layout does not know.
        assert!(Quantity::Angle.conversion("m").is_none());
        assert!(Quantity::Length.conversion("ft").is_none());
        assert!(Quantity::Count.conversion("m").is_none());
        assert_eq!(Quantity::AngularRate.accepted(), "rad/s, deg/s, deg/h");
        assert_eq!(Quantity::Speed.si(), "m/s");
        assert!(!Quantity::Count.has_unit());
    }
}
