//! The PX4 topics and fields fathom reads from a flight log, and their extraction in
//! one streaming pass into [`UlogTopics`]: per topic the time stamps and the chosen
//! fields, nothing else of the log.
//!
//! | topic | fields |
//! | --- | --- |
//! | `sensor_combined` | `gyro_rad[3]` (rad/s), `accelerometer_m_s2[3]` (m/s², body FRD, means over the integration interval) |
//! | `vehicle_gps_position` (else `sensor_gps`) | `lat`/`lon` (1e-7 deg) or `latitude_deg`/`longitude_deg`, `alt` (mm) or `altitude_msl_m`, `eph`, `epv`, `vel_n_m_s`, `vel_e_m_s`, `vel_d_m_s`, `s_variance_m_s`, `fix_type`, `satellites_used` |
//! | `vehicle_air_data` | `baro_alt_meter` |
//! | `vehicle_magnetometer` | `magnetometer_ga[3]` (gauss, body FRD) |
//! | `distance_sensor` | `current_distance` (m), `orientation` |
//! | `vehicle_local_position` | `x, y, z, vx, vy, vz` (local NED), `ref_lat`, `ref_lon` (deg), `ref_alt` (m), `xy_valid` |
//! | `vehicle_attitude` | `q[4]` (body FRD to NED, `w x y z`) |
//! | `vehicle_local_position_groundtruth` | as `vehicle_local_position` (simulation only) |
//!
//! Only instance 0 of a multi-instance topic is read (the primary sensor).

use std::io::Read;
use std::path::Path;

use super::error::UlogError;
use super::stream::{FieldRequest as F, TopicRequest, stream_topics};

/// The most messages of one topic kept in memory (10^7: 14 h of IMU at 200 Hz).
pub const MAX_MESSAGES_PER_TOPIC: usize = 10_000_000;

const fn req(names: &'static [&'static str]) -> F {
    F::required(names)
}
const fn opt(names: &'static [&'static str]) -> F {
    F::optional(names)
}

/// `sensor_combined`.
pub const IMU: usize = 0;
/// `vehicle_gps_position`.
pub const GPS: usize = 1;
/// `sensor_gps`.
pub const SENSOR_GPS: usize = 2;
/// `vehicle_air_data`.
pub const BARO: usize = 3;
/// `vehicle_magnetometer`.
pub const MAG: usize = 4;
/// `distance_sensor`.
pub const RANGE: usize = 5;
/// `vehicle_local_position`.
pub const EKF_POSITION: usize = 6;
/// `vehicle_attitude`.
pub const EKF_ATTITUDE: usize = 7;
/// `vehicle_local_position_groundtruth`.
pub const TRUTH_POSITION: usize = 8;

const GNSS_FIELDS: &[F] = &[
    opt(&["lat"]),
    opt(&["latitude_deg"]),
    opt(&["lon"]),
    opt(&["longitude_deg"]),
    opt(&["alt"]),
    opt(&["altitude_msl_m"]),
    req(&["eph"]),
    req(&["epv"]),
    req(&["vel_n_m_s"]),
    req(&["vel_e_m_s"]),
    req(&["vel_d_m_s"]),
    req(&["s_variance_m_s"]),
    req(&["fix_type"]),
    req(&["satellites_used"]),
];

const LOCAL_FIELDS: &[F] = &[
    req(&["x"]),
    req(&["y"]),
    req(&["z"]),
    req(&["vx"]),
    req(&["vy"]),
    req(&["vz"]),
    req(&["ref_lat"]),
    req(&["ref_lon"]),
    req(&["ref_alt"]),
    opt(&["xy_valid"]),
];

/// The topics read, indexed by the constants above.
pub const REQUESTS: [TopicRequest; 9] = [
    TopicRequest {
        topic: "sensor_combined",
        fields: &[
            req(&["gyro_rad[0]"]),
            req(&["gyro_rad[1]"]),
            req(&["gyro_rad[2]"]),
            req(&["accelerometer_m_s2[0]"]),
            req(&["accelerometer_m_s2[1]"]),
            req(&["accelerometer_m_s2[2]"]),
        ],
    },
    TopicRequest {
        topic: "vehicle_gps_position",
        fields: GNSS_FIELDS,
    },
    TopicRequest {
        topic: "sensor_gps",
        fields: GNSS_FIELDS,
    },
    TopicRequest {
        topic: "vehicle_air_data",
        fields: &[req(&["baro_alt_meter"])],
    },
    TopicRequest {
        topic: "vehicle_magnetometer",
        fields: &[
            req(&["magnetometer_ga[0]"]),
            req(&["magnetometer_ga[1]"]),
            req(&["magnetometer_ga[2]"]),
        ],
    },
    TopicRequest {
        topic: "distance_sensor",
        fields: &[req(&["current_distance"]), req(&["orientation"])],
    },
    TopicRequest {
        topic: "vehicle_local_position",
        fields: LOCAL_FIELDS,
    },
    TopicRequest {
        topic: "vehicle_attitude",
        fields: &[
            req(&["q[0]"]),
            req(&["q[1]"]),
            req(&["q[2]"]),
            req(&["q[3]"]),
        ],
    },
    TopicRequest {
        topic: "vehicle_local_position_groundtruth",
        fields: LOCAL_FIELDS,
    },
];

/// The messages of one topic: time stamps (microseconds since boot) and the fields
/// of each, row-major.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TopicSeries {
    /// Time stamps, microseconds, non-decreasing.
    pub time_us: Vec<u64>,
    /// Fields per message (the request's order).
    pub stride: usize,
    /// `time_us.len() * stride` values.
    pub values: Vec<f64>,
}

impl TopicSeries {
    /// Number of messages.
    pub fn len(&self) -> usize {
        self.time_us.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.time_us.is_empty()
    }

    /// The fields of message `k`.
    pub fn row(&self, k: usize) -> &[f64] {
        &self.values[k * self.stride..(k + 1) * self.stride]
    }
}

/// The topics of [`REQUESTS`] read from a log.
#[derive(Debug, Clone, PartialEq)]
pub struct UlogTopics {
    /// One series per request (empty when the log lacks the topic).
    pub series: Vec<TopicSeries>,
    /// Bytes read.
    pub bytes: u64,
}

impl UlogTopics {
    /// Reads the topics from `reader` (the file `path`, which labels errors), in one
    /// streaming pass.
    ///
    /// # Errors
    /// As [`stream_topics`], and [`UlogError::TimeBackwards`],
    /// [`UlogError::TooManyMessages`].
    pub fn read(reader: impl Read, path: &Path) -> Result<Self, UlogError> {
        let mut series: Vec<TopicSeries> = REQUESTS
            .iter()
            .map(|r| TopicSeries {
                stride: r.fields.len(),
                ..TopicSeries::default()
            })
            .collect();
        let mut sink = |s: &super::stream::Sample<'_>| {
            let topic = REQUESTS[s.request].topic;
            let ser = &mut series[s.request];
            if let Some(&previous_us) = ser.time_us.last()
                && s.time_us < previous_us
            {
                return Err(UlogError::TimeBackwards {
                    path: path.to_path_buf(),
                    topic: topic.into(),
                    index: ser.len(),
                    previous_us,
                    time_us: s.time_us,
                });
            }
            if ser.len() >= MAX_MESSAGES_PER_TOPIC {
                return Err(UlogError::TooManyMessages {
                    path: path.to_path_buf(),
                    topic: topic.into(),
                    limit: MAX_MESSAGES_PER_TOPIC,
                });
            }
            ser.time_us.push(s.time_us);
            ser.values.extend_from_slice(s.values);
            Ok(())
        };
        let bytes = stream_topics(reader, path, &REQUESTS, &mut sink)?;
        Ok(Self { series, bytes })
    }

    /// Reads the file at `path` (a regular file; opened, streamed, closed).
    ///
    /// # Errors
    /// [`UlogError::Io`] when it cannot be opened or is not a regular file, else as
    /// [`UlogTopics::read`].
    pub fn read_file(path: &Path) -> Result<Self, UlogError> {
        let io = |source| UlogError::Io {
            path: path.to_path_buf(),
            source,
        };
        let meta = std::fs::metadata(path).map_err(io)?;
        if !meta.is_file() {
            return Err(io(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "not a regular file",
            )));
        }
        let file = std::fs::File::open(path).map_err(io)?;
        Self::read(std::io::BufReader::new(file), path)
    }
}
