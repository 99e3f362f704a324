//! The quantization that MAVLink's field types impose, as explicit functions: the
//! epoch, the initial estimate and the solution encoded into common-dialect messages
//! (`HIL_SENSOR`, `HIL_GPS`, `DISTANCE_SENSOR`, `OBSTACLE_DISTANCE`, `ODOMETRY`) and
//! decoded back. The navigation process decodes what arrives with these functions,
//! and the offline run with MAVLink quantization passes its measurements through
//! `decode(encode(x))` ([`crate::assemble::quantize_epochs`]), so the two see the same numbers bit
//! for bit (docs/pils.md lists every field, unit and resolution).

use fathom_sensors::gnss::LocalFrame;
use fathom_sensors::gnss::geodesy::{ecef_from_geodetic, geodetic_from_ecef};
use mavlink::dialects::common::{
    DISTANCE_SENSOR_DATA, HIL_GPS_DATA, HIL_SENSOR_DATA, HilSensorUpdatedFlags, MavDistanceSensor,
    MavEstimatorType, MavFrame, MavMessage, MavSensorOrientation, OBSTACLE_DISTANCE_DATA,
    ODOMETRY_DATA,
};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

use crate::epoch::{Epoch, GpsFixReading, GpsReading, InitialEstimate, Solution};

/// Distances per `OBSTACLE_DISTANCE` message.
pub const SCAN_SLOTS: usize = 72;
/// `OBSTACLE_DISTANCE` / `DISTANCE_SENSOR` value for "unknown / not used".
pub const UNUSED_CM: u16 = u16::MAX;

/// The geometry of the range sensor as the wire describes it.
#[derive(Debug, Clone, PartialEq)]
pub enum RangeWire {
    /// Separate range finders (`DISTANCE_SENSOR`, one per beam, `id` = beam index,
    /// orientation `MAV_SENSOR_ROTATION_CUSTOM` with the beam's quaternion).
    Beams {
        /// Beam directions, body, unit.
        dirs: Vec<Vector3<f64>>,
        /// Max range, m.
        max_range_m: f64,
    },
    /// A planar scan in the body's horizontal plane (`OBSTACLE_DISTANCE`, 72 beams per
    /// message, `increment_f` and `angle_offset` in deg, frame `MAV_FRAME_BODY_FRD`).
    Scan {
        /// Azimuth of beam 0, deg (positive to starboard).
        first_deg: f64,
        /// Azimuth step, deg.
        step_deg: f64,
        /// Beams.
        beams: usize,
        /// Max range, m.
        max_range_m: f64,
    },
}

impl RangeWire {
    /// Beams of a scan.
    pub fn beams(&self) -> usize {
        match self {
            RangeWire::Beams { dirs, .. } => dirs.len(),
            RangeWire::Scan { beams, .. } => *beams,
        }
    }

    /// Messages one scan takes.
    pub fn messages(&self) -> usize {
        match self {
            RangeWire::Beams { dirs, .. } => dirs.len(),
            RangeWire::Scan { beams, .. } => beams.div_ceil(SCAN_SLOTS),
        }
    }

    fn max_cm(&self) -> u16 {
        let m = match self {
            RangeWire::Beams { max_range_m, .. } | RangeWire::Scan { max_range_m, .. } => {
                *max_range_m
            }
        };
        range_to_cm(m).min(UNUSED_CM - 2)
    }
}

/// Time to the wire's microseconds (rounded; negative or non-finite -> 0).
pub fn time_to_usec(t: f64) -> u64 {
    if t.is_finite() && t > 0.0 {
        (t * 1e6).round().min(u64::MAX as f64) as u64
    } else {
        0
    }
}

/// Microseconds to seconds.
pub fn usec_to_time(us: u64) -> f64 {
    us as f64 / 1e6
}

/// A range to centimetres (rounded, clamped to `0..=65533`; non-finite -> 0).
pub fn range_to_cm(r: f64) -> u16 {
    if r.is_finite() {
        (r * 100.0).round().clamp(0.0, f64::from(UNUSED_CM - 2)) as u16
    } else {
        0
    }
}

/// Centimetres to metres.
pub fn cm_to_range(cm: u16) -> f64 {
    f64::from(cm) / 100.0
}

/// An `f64` to the wire's `f32` (round to nearest).
pub fn to_f32(x: f64) -> f32 {
    x as f32
}

/// Degrees ×1e7 (rounded, saturating).
fn deg_e7(rad: f64) -> i32 {
    (rad.to_degrees() * 1e7)
        .round()
        .clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
}

/// Millimetres (rounded, saturating).
fn mm(m: f64) -> i32 {
    (m * 1e3)
        .round()
        .clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
}

/// DOP ×100 (rounded, `0..=65534`; non-finite: `UINT16_MAX`, unknown).
fn dop_e2(d: f64) -> u16 {
    if d.is_finite() {
        (d * 100.0).round().clamp(0.0, 65534.0) as u16
    } else {
        u16::MAX
    }
}

/// The messages of an epoch in sending order: `HIL_GPS`s, the range messages, and
/// `HIL_SENSOR` last (the IMU sample closes the step).
pub fn encode_epoch(e: &Epoch, frame: &LocalFrame, wire: &RangeWire) -> Vec<MavMessage> {
    let usec = time_to_usec(e.time);
    let mut out = Vec::new();
    for g in &e.gps {
        out.push(MavMessage::HIL_GPS(encode_gps(usec, g, frame)));
    }
    if let Some(sats) = &e.raw_gnss {
        out.extend(crate::raw_gnss::encode(usec, sats));
    }
    if let Some(r) = &e.ranges {
        out.extend(encode_ranges(usec, r, wire));
    }
    let dt = e.dt;
    let gyro = e.delta_theta / dt;
    let acc = e.delta_v / dt;
    let mut flags = HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_XACC
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_YACC
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_ZACC
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_XGYRO
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_YGYRO
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_ZGYRO;
    let mut mag = [0f32; 3];
    if let Some(m) = e.mag_body_gauss {
        flags |= HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_XMAG
            | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_YMAG
            | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_ZMAG;
        mag = [to_f32(m.x), to_f32(m.y), to_f32(m.z)];
    }
    let mut pressure = 0.0;
    if let Some(p) = e.pressure_pa {
        flags |= HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_ABS_PRESSURE;
        pressure = to_f32(p / 100.0);
    }
    out.push(MavMessage::HIL_SENSOR(HIL_SENSOR_DATA {
        time_usec: usec,
        xacc: to_f32(acc.x),
        yacc: to_f32(acc.y),
        zacc: to_f32(acc.z),
        xgyro: to_f32(gyro.x),
        ygyro: to_f32(gyro.y),
        zgyro: to_f32(gyro.z),
        xmag: mag[0],
        ymag: mag[1],
        zmag: mag[2],
        abs_pressure: pressure,
        diff_pressure: 0.0,
        pressure_alt: 0.0,
        temperature: 15.0,
        fields_updated: flags,
        id: 0,
    }));
    out
}

fn encode_gps(usec: u64, g: &GpsReading, frame: &LocalFrame) -> HIL_GPS_DATA {
    let mut d = HIL_GPS_DATA {
        time_usec: usec,
        fix_type: 1,
        lat: 0,
        lon: 0,
        alt: 0,
        eph: u16::MAX,
        epv: u16::MAX,
        vel: u16::MAX,
        vn: 0,
        ve: 0,
        vd: 0,
        cog: u16::MAX,
        satellites_visible: g.los_count,
        id: g.id,
        yaw: 0,
    };
    if let Some(f) = &g.fix {
        let (lat, lon, h) = geodetic_from_ecef(&frame.ecef_from_ned(&f.pos_in_nav));
        d.fix_type = 3;
        d.lat = deg_e7(lat);
        d.lon = deg_e7(lon);
        d.alt = mm(h);
        d.eph = dop_e2(f.hdop);
        d.epv = dop_e2(f.vdop);
    }
    d
}

/// Decodes a `HIL_GPS` (a fix needs `fix_type >= 3` and known DOPs).
pub fn decode_gps(d: &HIL_GPS_DATA, frame: &LocalFrame) -> GpsReading {
    let fix = (d.fix_type >= 3 && d.eph != u16::MAX && d.epv != u16::MAX).then(|| {
        let lat = (f64::from(d.lat) / 1e7).to_radians();
        let lon = (f64::from(d.lon) / 1e7).to_radians();
        let h = f64::from(d.alt) / 1e3;
        GpsFixReading {
            pos_in_nav: frame.ned_from_ecef_point(&ecef_from_geodetic(lat, lon, h)),
            hdop: f64::from(d.eph) / 100.0,
            vdop: f64::from(d.epv) / 100.0,
        }
    });
    GpsReading {
        id: d.id,
        fix,
        los_count: d.satellites_visible,
    }
}

fn encode_ranges(usec: u64, ranges: &[Option<f64>], wire: &RangeWire) -> Vec<MavMessage> {
    let max_cm = wire.max_cm();
    let cm = |r: &Option<f64>| r.map_or(max_cm + 1, |r| range_to_cm(r).min(max_cm));
    match wire {
        RangeWire::Beams { dirs, .. } => ranges
            .iter()
            .zip(dirs)
            .enumerate()
            .map(|(i, (r, d))| {
                let q = UnitQuaternion::rotation_between(&Vector3::x(), d).unwrap_or_else(|| {
                    UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::PI)
                });
                MavMessage::DISTANCE_SENSOR(DISTANCE_SENSOR_DATA {
                    time_boot_ms: (usec / 1000).min(u64::from(u32::MAX)) as u32,
                    min_distance: 0,
                    max_distance: max_cm,
                    current_distance: cm(r),
                    mavtype: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
                    id: i.min(255) as u8,
                    orientation: MavSensorOrientation::MAV_SENSOR_ROTATION_CUSTOM,
                    covariance: u8::MAX,
                    horizontal_fov: 0.0,
                    vertical_fov: 0.0,
                    quaternion: [to_f32(q.w), to_f32(q.i), to_f32(q.j), to_f32(q.k)],
                    signal_quality: if r.is_some() { 100 } else { 1 },
                })
            })
            .collect(),
        RangeWire::Scan {
            first_deg,
            step_deg,
            ..
        } => ranges
            .chunks(SCAN_SLOTS)
            .enumerate()
            .map(|(m, chunk)| {
                let mut distances = [UNUSED_CM; SCAN_SLOTS];
                for (slot, r) in distances.iter_mut().zip(chunk) {
                    *slot = cm(r);
                }
                MavMessage::OBSTACLE_DISTANCE(OBSTACLE_DISTANCE_DATA {
                    time_usec: usec,
                    distances,
                    min_distance: 0,
                    max_distance: max_cm,
                    sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
                    increment: 0,
                    increment_f: to_f32(*step_deg),
                    angle_offset: to_f32(first_deg + (m * SCAN_SLOTS) as f64 * step_deg),
                    frame: MavFrame::MAV_FRAME_BODY_FRD,
                })
            })
            .collect(),
    }
}

/// Decodes one `DISTANCE_SENSOR` into `(beam, range)`; `None` for a beam index
/// outside the sensor.
pub fn decode_distance(d: &DISTANCE_SENSOR_DATA, wire: &RangeWire) -> Option<(usize, Option<f64>)> {
    let beam = usize::from(d.id);
    (beam < wire.beams()).then(|| {
        let r = (d.current_distance <= d.max_distance).then(|| cm_to_range(d.current_distance));
        (beam, r)
    })
}

/// Decodes one `OBSTACLE_DISTANCE` into its first beam index and ranges; `None` when
/// the angle offset does not fall on a 72-beam block of the scan or the step differs.
pub fn decode_scan(
    d: &OBSTACLE_DISTANCE_DATA,
    wire: &RangeWire,
) -> Option<(usize, Vec<Option<f64>>)> {
    let RangeWire::Scan {
        first_deg,
        step_deg,
        beams,
        ..
    } = wire
    else {
        return None;
    };
    if d.increment_f != to_f32(*step_deg) {
        return None;
    }
    let block = (0..beams.div_ceil(SCAN_SLOTS))
        .find(|m| to_f32(first_deg + (m * SCAN_SLOTS) as f64 * step_deg) == d.angle_offset)?;
    let first = block * SCAN_SLOTS;
    let n = (beams - first).min(SCAN_SLOTS);
    let ranges = d.distances[..n]
        .iter()
        .map(|&cm| (cm <= d.max_distance).then(|| cm_to_range(cm)))
        .collect();
    Some((first, ranges))
}

/// The IMU part of a `HIL_SENSOR`: time stamp, gyro rates (rad/s) and specific force
/// (m/s²) as sent, pressure (Pa) when flagged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuReading {
    /// Time stamp, µs.
    pub time_usec: u64,
    /// Body rate, rad/s.
    pub gyro: Vector3<f64>,
    /// Specific force, m/s².
    pub accel: Vector3<f64>,
    /// Static pressure, Pa.
    pub pressure_pa: Option<f64>,
    /// Magnetic field, body, gauss.
    pub mag_body_gauss: Option<Vector3<f64>>,
}

/// Decodes a `HIL_SENSOR`.
pub fn decode_imu(d: &HIL_SENSOR_DATA) -> ImuReading {
    let p = d
        .fields_updated
        .contains(HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_ABS_PRESSURE)
        .then(|| f64::from(d.abs_pressure) * 100.0);
    let mag = HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_XMAG
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_YMAG
        | HilSensorUpdatedFlags::HIL_SENSOR_UPDATED_ZMAG;
    ImuReading {
        time_usec: d.time_usec,
        gyro: Vector3::new(d.xgyro.into(), d.ygyro.into(), d.zgyro.into()),
        accel: Vector3::new(d.xacc.into(), d.yacc.into(), d.zacc.into()),
        pressure_pa: p,
        mag_body_gauss: d
            .fields_updated
            .contains(mag)
            .then(|| Vector3::new(d.xmag.into(), d.ymag.into(), d.zmag.into())),
    }
}

/// An epoch from its decoded parts: the increments are the rates times the step
/// length from the time stamps (`(t_k - t_prev) / 1e6`).
pub fn epoch_from_parts(
    step: u64,
    imu: &ImuReading,
    prev_usec: u64,
    gps: Vec<GpsReading>,
    raw_gnss: Option<Vec<crate::epoch::SatReading>>,
    ranges: Option<Vec<Option<f64>>>,
) -> Epoch {
    let dt = usec_to_time(imu.time_usec.saturating_sub(prev_usec));
    Epoch {
        step,
        time: usec_to_time(imu.time_usec),
        dt,
        delta_theta: imu.gyro * dt,
        delta_v: imu.accel * dt,
        pressure_pa: imu.pressure_pa,
        mag_body_gauss: imu.mag_body_gauss,
        gps,
        raw_gnss,
        ranges,
    }
}

fn upper_triangle(m: &nalgebra::Matrix6<f64>) -> [f32; 21] {
    let mut out = [0f32; 21];
    let mut k = 0;
    for i in 0..6 {
        for j in i..6 {
            out[k] = to_f32(m[(i, j)]);
            k += 1;
        }
    }
    out
}

fn from_upper_triangle(t: &[f32; 21]) -> nalgebra::Matrix6<f64> {
    let mut m = nalgebra::Matrix6::zeros();
    let mut k = 0;
    for i in 0..6 {
        for j in i..6 {
            m[(i, j)] = f64::from(t[k]);
            m[(j, i)] = f64::from(t[k]);
            k += 1;
        }
    }
    m
}

/// The estimator types the solution's `ODOMETRY.estimator_type` carries: the mode.
fn estimator_type(map_aided: bool) -> MavEstimatorType {
    if map_aided {
        MavEstimatorType::MAV_ESTIMATOR_TYPE_LIDAR
    } else {
        MavEstimatorType::MAV_ESTIMATOR_TYPE_GPS_INS
    }
}

/// Encodes a solution as `ODOMETRY` (frame and child frame `MAV_FRAME_LOCAL_NED`;
/// pose covariance over x, y, z and the attitude error about N, E, D; velocity
/// covariance over vx, vy, vz, rates unknown: 0).
pub fn encode_solution(s: &Solution) -> ODOMETRY_DATA {
    let mut pose = nalgebra::Matrix6::zeros();
    pose.fixed_view_mut::<3, 3>(0, 0).copy_from(&s.pos_cov);
    pose.fixed_view_mut::<3, 3>(3, 3).copy_from(&s.att_cov);
    pose.fixed_view_mut::<3, 3>(0, 3).copy_from(&s.pos_att_cov);
    pose.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&s.pos_att_cov.transpose());
    let mut vel = nalgebra::Matrix6::zeros();
    vel.fixed_view_mut::<3, 3>(0, 0).copy_from(&s.vel_cov);
    let q = s.nav_from_body.quaternion();
    ODOMETRY_DATA {
        time_usec: time_to_usec(s.time),
        frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
        child_frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
        x: to_f32(s.pos_in_nav.x),
        y: to_f32(s.pos_in_nav.y),
        z: to_f32(s.pos_in_nav.z),
        q: [to_f32(q.w), to_f32(q.i), to_f32(q.j), to_f32(q.k)],
        vx: to_f32(s.vel_in_nav.x),
        vy: to_f32(s.vel_in_nav.y),
        vz: to_f32(s.vel_in_nav.z),
        rollspeed: to_f32(s.omega_body.x),
        pitchspeed: to_f32(s.omega_body.y),
        yawspeed: to_f32(s.omega_body.z),
        pose_covariance: upper_triangle(&pose),
        velocity_covariance: upper_triangle(&vel),
        reset_counter: 0,
        estimator_type: estimator_type(s.map_aided),
        quality: 100,
    }
}

fn quaternion_of(q: &[f32; 4]) -> Option<UnitQuaternion<f64>> {
    let q: Quaternion<f64> = Quaternion::new(q[0].into(), q[1].into(), q[2].into(), q[3].into());
    let n = q.norm();
    (n.is_finite() && n > 0.5).then(|| UnitQuaternion::new_normalize(q))
}

/// Decodes an `ODOMETRY` solution; `None` when a field is not finite, the quaternion
/// is not near unit length, or the frames are not local NED.
pub fn decode_solution(d: &ODOMETRY_DATA, step: u64) -> Option<Solution> {
    if d.frame_id != MavFrame::MAV_FRAME_LOCAL_NED
        || d.child_frame_id != MavFrame::MAV_FRAME_LOCAL_NED
    {
        return None;
    }
    let v3 = |a: f32, b: f32, c: f32| Vector3::new(f64::from(a), f64::from(b), f64::from(c));
    let pos = v3(d.x, d.y, d.z);
    let vel = v3(d.vx, d.vy, d.vz);
    let rate = v3(d.rollspeed, d.pitchspeed, d.yawspeed);
    if !(pos
        .iter()
        .chain(vel.iter())
        .chain(rate.iter())
        .all(|x| x.is_finite()))
    {
        return None;
    }
    let q = quaternion_of(&d.q)?;
    let pose = from_upper_triangle(&d.pose_covariance);
    let velc = from_upper_triangle(&d.velocity_covariance);
    Some(Solution {
        step,
        time: usec_to_time(d.time_usec),
        pos_in_nav: pos,
        vel_in_nav: vel,
        nav_from_body: q,
        omega_body: rate,
        pos_cov: pose.fixed_view::<3, 3>(0, 0).into_owned(),
        att_cov: pose.fixed_view::<3, 3>(3, 3).into_owned(),
        pos_att_cov: pose.fixed_view::<3, 3>(0, 3).into_owned(),
        vel_cov: velc.fixed_view::<3, 3>(0, 0).into_owned(),
        map_aided: d.estimator_type == MavEstimatorType::MAV_ESTIMATOR_TYPE_LIDAR,
    })
}

/// The solution as the simulator receives it: `decode(encode(s))`.
pub fn quantize_solution(s: &Solution) -> Solution {
    decode_solution(&encode_solution(s), s.step).unwrap_or(*s)
}

/// Encodes the initial estimate as an `ODOMETRY` from the simulator
/// (`estimator_type = MAV_ESTIMATOR_TYPE_NAIVE`, covariances unknown: NaN first).
pub fn encode_initial(i: &InitialEstimate) -> ODOMETRY_DATA {
    let mut d = encode_solution(&Solution {
        step: i.step,
        time: i.time,
        pos_in_nav: i.pos_in_nav,
        vel_in_nav: i.vel_in_nav,
        nav_from_body: i.nav_from_body,
        omega_body: Vector3::zeros(),
        pos_cov: Matrix3::zeros(),
        att_cov: Matrix3::zeros(),
        pos_att_cov: Matrix3::zeros(),
        vel_cov: Matrix3::zeros(),
        map_aided: false,
    });
    d.estimator_type = MavEstimatorType::MAV_ESTIMATOR_TYPE_NAIVE;
    d.pose_covariance[0] = f32::NAN;
    d.velocity_covariance[0] = f32::NAN;
    d.quality = 0;
    d
}

/// Decodes the initial estimate.
pub fn decode_initial(d: &ODOMETRY_DATA, step: u64) -> Option<InitialEstimate> {
    let mut d2 = d.clone();
    d2.pose_covariance[0] = 0.0;
    d2.velocity_covariance[0] = 0.0;
    let s = decode_solution(&d2, step)?;
    Some(InitialEstimate {
        step,
        time: s.time,
        pos_in_nav: s.pos_in_nav,
        vel_in_nav: s.vel_in_nav,
        nav_from_body: s.nav_from_body,
    })
}

/// The initial estimate as the navigation receives it.
pub fn quantize_initial(i: &InitialEstimate) -> InitialEstimate {
    decode_initial(&encode_initial(i), i.step).unwrap_or(*i)
}
