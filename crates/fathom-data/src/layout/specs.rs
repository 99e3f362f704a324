//! The columns of every file of the log kinds (`docs/own-data.md`): one
//! [`FileSpec`] per file, and the columns several files share (the time stamp, the
//! north / east position, a DVL's body velocity) declared once. The parsers of the
//! kinds ([`super::range_beacon`], [`super::ins_dvl`]) re-export their kind's specs.

use super::table::{Check, ColumnSpec as C, FileSpec, TimeOrder};
use super::units::Quantity::{
    Acceleration, Angle, AngularRate, Count, Length, MagneticField, Rpm, Speed, Time,
};

/// `time[s]`, the first column of every timed file.
const TIME: C = C::required("time", Time, Check::Any);
/// North of a position, m.
const NORTH: C = C::required("north", Length, Check::Any);
/// East of a position, m.
const EAST: C = C::required("east", Length, Check::Any);
/// A DVL's body velocity: `u` forward, `v` right, `w` down, m/s.
const DVL_VELOCITY: [C; 3] = [
    C::required("u", Speed, Check::Any),
    C::required("v", Speed, Check::Any),
    C::required("w", Speed, Check::Any),
];

/// `depth.csv` (down positive), shared by both kinds.
pub const DEPTH: FileSpec = FileSpec::timed(
    "depth.csv",
    &[TIME, C::required("depth", Length, Check::Any)],
);

/// The files of a `range-beacon` log.
pub mod range_beacon {
    use super::*;

    /// `beacons.csv`.
    pub const BEACONS: FileSpec = FileSpec {
        file: "beacons.csv",
        columns: &[
            C::required("id", Count, Check::Integer),
            NORTH,
            EAST,
            C::optional("down", Length, Check::Any),
        ],
        groups: &[],
        time: TimeOrder::NoTime,
    };

    /// `initial.csv`.
    pub const INITIAL: FileSpec = FileSpec::timed(
        "initial.csv",
        &[
            TIME,
            NORTH,
            EAST,
            C::optional("down", Length, Check::Any),
            C::required("heading", Angle, Check::Any),
        ],
    );

    /// `odometry.csv`.
    pub const ODOMETRY: FileSpec = FileSpec::timed(
        "odometry.csv",
        &[
            TIME,
            C::required("distance", Length, Check::Any),
            C::required("heading_change", Angle, Check::Any),
        ],
    );

    /// `dvl.csv` (body-frame velocity: x forward, y right, z down).
    pub const DVL: FileSpec = FileSpec::timed(
        "dvl.csv",
        &[TIME, DVL_VELOCITY[0], DVL_VELOCITY[1], DVL_VELOCITY[2]],
    );

    /// `heading.csv` (clockwise from north).
    pub const HEADING: FileSpec = FileSpec::timed(
        "heading.csv",
        &[TIME, C::required("heading", Angle, Check::Any)],
    );

    /// `ranges.csv` (several beacons may share a stamp).
    pub const RANGES: FileSpec = FileSpec {
        file: "ranges.csv",
        columns: &[
            TIME,
            C::required("beacon", Count, Check::Integer),
            C::required("range", Length, Check::NonNegative),
        ],
        groups: &[],
        time: TimeOrder::NonDecreasing,
    };

    /// `truth.csv`.
    pub const TRUTH: FileSpec = FileSpec::timed(
        "truth.csv",
        &[
            TIME,
            NORTH,
            EAST,
            C::optional("down", Length, Check::Any),
            C::optional("heading", Angle, Check::Any),
        ],
    );

    /// Every file of the kind.
    pub const SPECS: [FileSpec; 8] = [
        BEACONS, INITIAL, ODOMETRY, DVL, HEADING, RANGES, DEPTH, TRUTH,
    ];
}

/// The files of an `ins-dvl` log.
pub mod ins_dvl {
    use super::*;

    /// `initial.csv`.
    pub const INITIAL: FileSpec = FileSpec::timed(
        "initial.csv",
        &[
            TIME,
            C::required("latitude", Angle, Check::Latitude),
            C::required("longitude", Angle, Check::Any),
            C::required("depth", Length, Check::Any),
            C::required("vel_north", Speed, Check::Any),
            C::required("vel_east", Speed, Check::Any),
            C::required("vel_down", Speed, Check::Any),
            C::required("roll", Angle, Check::Any),
            C::required("pitch", Angle, Check::Any),
            C::required("heading", Angle, Check::Any),
        ],
    );

    /// The IMU increment columns.
    pub const INCREMENTS: &[&str] = &["dtheta_x", "dtheta_y", "dtheta_z", "dv_x", "dv_y", "dv_z"];
    /// The IMU rate columns.
    pub const RATES: &[&str] = &[
        "gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z",
    ];

    /// `imu.csv`: increments or mean rates over (previous row, this row].
    pub const IMU: FileSpec = FileSpec {
        file: "imu.csv",
        columns: &[
            TIME,
            C::required("dtheta_x", Angle, Check::Any),
            C::required("dtheta_y", Angle, Check::Any),
            C::required("dtheta_z", Angle, Check::Any),
            C::required("dv_x", Speed, Check::Any),
            C::required("dv_y", Speed, Check::Any),
            C::required("dv_z", Speed, Check::Any),
            C::required("gyro_x", AngularRate, Check::Any),
            C::required("gyro_y", AngularRate, Check::Any),
            C::required("gyro_z", AngularRate, Check::Any),
            C::required("accel_x", Acceleration, Check::Any),
            C::required("accel_y", Acceleration, Check::Any),
            C::required("accel_z", Acceleration, Check::Any),
        ],
        groups: &[INCREMENTS, RATES],
        time: TimeOrder::Increasing,
    };

    /// `dvl.csv` (body-frame velocity: x forward, y right, z down; an optional
    /// bottom-lock flag).
    pub const DVL: FileSpec = FileSpec::timed(
        "dvl.csv",
        &[
            TIME,
            DVL_VELOCITY[0],
            DVL_VELOCITY[1],
            DVL_VELOCITY[2],
            C::optional("bottom_lock", Count, Check::Flag),
        ],
    );

    /// `altitude.csv` (echo sounder).
    pub const ALTITUDE: FileSpec = FileSpec::timed(
        "altitude.csv",
        &[TIME, C::required("altitude", Length, Check::NonNegative)],
    );

    /// `rpm.csv`.
    pub const RPM: FileSpec =
        FileSpec::timed("rpm.csv", &[TIME, C::required("rpm", Rpm, Check::Any)]);

    /// `truth.csv` (north and east from the start position, depth).
    pub const TRUTH: FileSpec = FileSpec::timed(
        "truth.csv",
        &[
            TIME,
            NORTH,
            EAST,
            C::required("depth", Length, Check::Any),
            C::optional("vel_north", Speed, Check::Any),
            C::optional("vel_east", Speed, Check::Any),
            C::optional("vel_down", Speed, Check::Any),
        ],
    );

    /// Every file of the kind.
    pub const SPECS: [FileSpec; 7] = [INITIAL, IMU, DVL, DEPTH, ALTITUDE, RPM, TRUTH];
}

/// The files of a `gnss-ins` log (a drone's flight: `fathom log from-ulog`).
pub mod gnss_ins {
    use super::*;

    /// Geodetic position: latitude, longitude, altitude (above the GNSS datum, up).
    const LATITUDE: C = C::required("latitude", Angle, Check::Latitude);
    const LONGITUDE: C = C::required("longitude", Angle, Check::Any);
    const ALTITUDE: C = C::required("altitude", Length, Check::Any);
    /// NED velocity.
    const VEL: [C; 3] = [
        C::required("vel_north", Speed, Check::Any),
        C::required("vel_east", Speed, Check::Any),
        C::required("vel_down", Speed, Check::Any),
    ];

    /// `imu.csv`: mean body rates and specific force over (previous row, this row],
    /// body axes forward-right-down.
    pub const IMU: FileSpec = FileSpec::timed(
        "imu.csv",
        &[
            TIME,
            C::required("gyro_x", AngularRate, Check::Any),
            C::required("gyro_y", AngularRate, Check::Any),
            C::required("gyro_z", AngularRate, Check::Any),
            C::required("accel_x", Acceleration, Check::Any),
            C::required("accel_y", Acceleration, Check::Any),
            C::required("accel_z", Acceleration, Check::Any),
        ],
    );

    /// `gnss.csv`: the receiver's fixes with its accuracy estimates.
    pub const GNSS: FileSpec = FileSpec::timed(
        "gnss.csv",
        &[
            TIME,
            LATITUDE,
            LONGITUDE,
            ALTITUDE,
            C::required("h_acc", Length, Check::NonNegative),
            C::required("v_acc", Length, Check::NonNegative),
            VEL[0],
            VEL[1],
            VEL[2],
            C::required("speed_acc", Speed, Check::NonNegative),
            C::required("fix_type", Count, Check::Integer),
            C::required("satellites", Count, Check::Integer),
        ],
    );

    /// `baro.csv`: barometric altitude (up).
    pub const BARO: FileSpec = FileSpec::timed(
        "baro.csv",
        &[TIME, C::required("altitude", Length, Check::Any)],
    );

    /// `mag.csv`: magnetometer, body axes.
    pub const MAG: FileSpec = FileSpec::timed(
        "mag.csv",
        &[
            TIME,
            C::required("mag_x", MagneticField, Check::Any),
            C::required("mag_y", MagneticField, Check::Any),
            C::required("mag_z", MagneticField, Check::Any),
        ],
    );

    /// `range.csv`: distance sensors (PX4 `orientation` code: 25 = downward), or
    /// beams of any direction (`beam_x, beam_y, beam_z` in body axes); several beams
    /// may share a stamp (a scan).
    pub const RANGE: FileSpec = FileSpec {
        file: "range.csv",
        columns: &[
            TIME,
            C::required("distance", Length, Check::NonNegative),
            C::required("orientation", Count, Check::Integer),
            C::optional("beam_x", Count, Check::Any),
            C::optional("beam_y", Count, Check::Any),
            C::optional("beam_z", Count, Check::Any),
        ],
        groups: &[],
        time: TimeOrder::NonDecreasing,
    };

    /// `reference.csv`: the autopilot's own estimate (PX4's EKF2), a reference track.
    pub const REFERENCE: FileSpec = FileSpec::timed(
        "reference.csv",
        &[
            TIME,
            LATITUDE,
            LONGITUDE,
            ALTITUDE,
            VEL[0],
            VEL[1],
            VEL[2],
            C::required("roll", Angle, Check::Any),
            C::required("pitch", Angle, Check::Any),
            C::required("heading", Angle, Check::Any),
        ],
    );

    /// `truth.csv`: ground truth (a simulator's).
    pub const TRUTH: FileSpec = FileSpec::timed(
        "truth.csv",
        &[TIME, LATITUDE, LONGITUDE, ALTITUDE, VEL[0], VEL[1], VEL[2]],
    );

    /// Every file of the kind.
    pub const SPECS: [FileSpec; 7] = [IMU, GNSS, BARO, MAG, RANGE, REFERENCE, TRUTH];
}
