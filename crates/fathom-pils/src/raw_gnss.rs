//! Raw GNSS measurements on the wire: every satellite above the mask (ECEF position
//! and pseudorange) in `DEBUG_FLOAT_ARRAY` messages named `GNSS_RAW`, for a
//! navigation that tests each satellite's line of sight against its own map and
//! solves its own fix (the `urban` methods). The common dialect has no message for
//! raw observables; `HIL_GPS` carries the receiver's fix beside them.
//!
//! Layout of one message (`array_id` = block index): `data[0]` the number of
//! satellites of the epoch, then per satellite eight floats: x, y, z (ECEF, m) and
//! the pseudorange (m; NaN when no signal was received), each as an `f32` pair
//! `hi = f32(v)`, `lo = f32(v - hi)` (about 1e-7 m at GPS distances).

use mavlink::dialects::common::{DEBUG_FLOAT_ARRAY_DATA, MavMessage};
use nalgebra::Vector3;

use crate::epoch::SatReading;

/// The `name` of the messages.
pub const NAME: &[u8; 10] = b"GNSS_RAW\0\0";
/// Satellites per message.
pub const PER_MESSAGE: usize = 7;
/// Most satellites an epoch may carry (the blocks a step may take are bounded).
pub const MAX_SATELLITES: usize = 64;

/// Messages an epoch of `n` satellites takes (at least one: an empty sky is said).
pub fn messages(n: usize) -> usize {
    n.div_ceil(PER_MESSAGE).max(1)
}

fn split(v: f64) -> [f32; 2] {
    let hi = v as f32;
    [hi, (v - f64::from(hi)) as f32]
}

fn join(p: &[f32]) -> f64 {
    f64::from(p[0]) + f64::from(p[1])
}

/// The messages of one epoch's satellites, stamped `usec`.
pub fn encode(usec: u64, sats: &[SatReading]) -> Vec<MavMessage> {
    let n = sats.len().min(MAX_SATELLITES);
    (0..messages(n))
        .map(|b| {
            let mut data = [0f32; 58];
            data[0] = n as f32;
            for (i, s) in sats[..n]
                .iter()
                .skip(b * PER_MESSAGE)
                .take(PER_MESSAGE)
                .enumerate()
            {
                let o = 1 + 8 * i;
                for (a, v) in s.pos_ecef.iter().enumerate() {
                    data[o + 2 * a..o + 2 * a + 2].copy_from_slice(&split(*v));
                }
                let pr = s.pseudorange_m.map_or([f32::NAN; 2], split);
                data[o + 6..o + 8].copy_from_slice(&pr);
            }
            MavMessage::DEBUG_FLOAT_ARRAY(DEBUG_FLOAT_ARRAY_DATA {
                time_usec: usec,
                name: (*NAME).into(),
                array_id: b as u16,
                data,
            })
        })
        .collect()
}

/// One decoded block: the block index, the epoch's satellite count and the
/// satellites it holds (in order). `None` for another array name, a count or block
/// index out of range, or a non-finite position.
pub fn decode(d: &DEBUG_FLOAT_ARRAY_DATA) -> Option<(usize, usize, Vec<SatReading>)> {
    if d.name.as_slice() != NAME.as_slice() {
        return None;
    }
    let data: &[f32] = d.data.as_slice();
    let count = data.first().copied()?;
    if !(count.is_finite()
        && count >= 0.0
        && count <= MAX_SATELLITES as f32
        && count.fract() == 0.0)
    {
        return None;
    }
    let n = count as usize;
    let b = usize::from(d.array_id);
    if b >= messages(n) {
        return None;
    }
    let here = n.saturating_sub(b * PER_MESSAGE).min(PER_MESSAGE);
    let mut sats = Vec::with_capacity(here);
    for i in 0..here {
        let o = 1 + 8 * i;
        let p = &data[o..o + 8];
        let pos = Vector3::new(join(&p[0..2]), join(&p[2..4]), join(&p[4..6]));
        if pos.iter().any(|c| !c.is_finite()) {
            return None;
        }
        let pr = join(&p[6..8]);
        sats.push(SatReading {
            pos_ecef: pos,
            pseudorange_m: pr.is_finite().then_some(pr),
        });
    }
    Some((b, n, sats))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sats(n: usize) -> Vec<SatReading> {
        (0..n)
            .map(|i| SatReading {
                pos_ecef: Vector3::new(
                    2.0e7 + i as f64 * 1_234.567_891,
                    -1.3e7 + 0.1 * i as f64,
                    1.7e7,
                ),
                pseudorange_m: (i % 3 != 0).then_some(2.2e7 + 0.123_456_789 * i as f64),
            })
            .collect()
    }

    #[test]
    fn satellites_round_trip_to_a_micrometre_in_blocks_of_seven() {
        for n in [0, 1, 7, 9, 15] {
            let s = sats(n);
            let msgs = encode(5, &s);
            assert_eq!(msgs.len(), messages(n));
            let mut back = Vec::new();
            for m in &msgs {
                let MavMessage::DEBUG_FLOAT_ARRAY(d) = m else {
                    panic!("{m:?}")
                };
                let (_, count, mut part) = decode(d).unwrap();
                assert_eq!(count, n);
                back.append(&mut part);
            }
            assert_eq!(back.len(), n);
            for (a, b) in s.iter().zip(&back) {
                assert!((a.pos_ecef - b.pos_ecef).amax() < 1e-6, "{a:?} {b:?}");
                assert_eq!(a.pseudorange_m.is_some(), b.pseudorange_m.is_some());
                if let (Some(x), Some(y)) = (a.pseudorange_m, b.pseudorange_m) {
                    assert!((x - y).abs() < 1e-6);
                }
            }
        }
    }

    #[test]
    fn foreign_or_bad_blocks_are_refused() {
        let MavMessage::DEBUG_FLOAT_ARRAY(d) = &encode(1, &sats(9))[1] else {
            unreachable!()
        };
        let mut other = d.clone();
        other.name = (*b"OTHER\0\0\0\0\0").into();
        assert!(decode(&other).is_none());
        let mut far = d.clone();
        far.array_id = 2;
        assert!(decode(&far).is_none());
        let mut nan = d.clone();
        nan.data[0] = f32::NAN;
        assert!(decode(&nan).is_none());
        let mut pos = d.clone();
        pos.data[1] = f32::INFINITY;
        assert!(decode(&pos).is_none());
        assert!(
            decode(d).is_some(),
            "the unchanged block decodes (negative control)"
        );
    }
}
