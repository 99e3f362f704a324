//! MAVLink 2 frames on datagrams: encoding (optionally signed with a shared key) and
//! a parser that takes any bytes and never panics: it walks a datagram frame by
//! frame, resynchronizing on the start marker, and sorts every failure into a
//! [`Drop`] reason (garbage, truncated, unsupported flags, bad CRC, unknown message,
//! undecodable payload, unsigned or badly signed).

use mavlink::dialects::common::MavMessage;
use mavlink::{
    MAVLinkV2MessageRaw, MavHeader, MavlinkVersion, Message, SigningConfig, SigningData, consts,
};

use crate::stats::Drop;

/// The MAVLink 2 start marker.
pub const STX_V2: u8 = 0xFD;
/// The simulator's system id.
pub const SIM_SYSTEM: u8 = 1;
/// The navigation's system id.
pub const NAV_SYSTEM: u8 = 2;
/// The component id both sides use (`MAV_COMP_ID_AUTOPILOT1`).
pub const COMPONENT: u8 = 1;

/// MAVLink 2 signing with a shared 32-byte key (`None`: unsigned frames).
pub struct Signing {
    data: SigningData,
}

impl std::fmt::Debug for Signing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Signing { .. }")
    }
}

impl Signing {
    /// Signing with `key` on link `link_id`; unsigned frames are refused.
    pub fn new(key: [u8; 32], link_id: u8) -> Self {
        Self {
            data: SigningData::from_config(SigningConfig::new(key, link_id, true, false)),
        }
    }

    /// A key from a passphrase: its SHA-256 (as MAVLink's ground stations derive
    /// keys from passphrases).
    pub fn key_from_passphrase(passphrase: &str) -> [u8; 32] {
        use sha2::{Digest, Sha256};
        Sha256::digest(passphrase.as_bytes()).into()
    }
}

/// The sending side of the frames: system id, sequence number, signing.
#[derive(Debug)]
pub struct Encoder {
    system: u8,
    sequence: u8,
    signing: Option<Signing>,
}

impl Encoder {
    /// An encoder for `system`, signing when `signing` is given.
    pub fn new(system: u8, signing: Option<Signing>) -> Self {
        Self {
            system,
            sequence: 0,
            signing,
        }
    }

    /// The system id frames carry.
    pub fn system(&self) -> u8 {
        self.system
    }

    /// One frame's bytes.
    pub fn encode(&mut self, m: &MavMessage) -> Vec<u8> {
        let header = MavHeader {
            system_id: self.system.into(),
            component_id: COMPONENT,
            sequence: self.sequence,
        };
        self.sequence = self.sequence.wrapping_add(1);
        let mut raw = MAVLinkV2MessageRaw::new();
        match &self.signing {
            Some(s) => {
                raw.serialize_message_for_signing(header, m);
                s.data.sign_message(&mut raw);
            }
            None => raw.serialize_message(header, m),
        }
        raw.raw_bytes().to_vec()
    }
}

/// A frame that parsed: sender system and the message.
#[derive(Debug, Clone, PartialEq)]
pub struct Received {
    /// Sender system id.
    pub system: u32,
    /// The message.
    pub message: MavMessage,
}

/// Largest header size (MAVLink 2 with a 32-bit system id).
const MAX_HEADER: usize = consts::v2::MAX_HEADER_SIZE;

/// Parses every frame of a datagram, calling `out` with each message or drop reason
/// (never panics, whatever the bytes; bounded by the datagram length).
pub fn parse_datagram(
    bytes: &[u8],
    signing: Option<&Signing>,
    mut out: impl FnMut(Result<Received, Drop>),
) {
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] != STX_V2 {
            // Skip to the next start marker: one garbage report per run of bytes.
            let next = bytes[i..]
                .iter()
                .position(|&b| b == STX_V2)
                .map_or(bytes.len(), |p| i + p);
            out(Err(Drop::Garbage));
            i = next;
            continue;
        }
        match parse_frame(&bytes[i..], signing) {
            Ok((len, r)) => {
                out(r);
                i += len;
            }
            Err(why) => {
                out(Err(why));
                // Resynchronize after this marker.
                i += 1;
            }
        }
    }
}

/// One frame at the start of `b` (`b[0]` is the marker): its length and its result,
/// or a drop that consumed no frame (truncated, unsupported flags, bad CRC).
fn parse_frame(
    b: &[u8],
    signing: Option<&Signing>,
) -> Result<(usize, Result<Received, Drop>), Drop> {
    if b.len() < 1 + consts::v2::MIN_HEADER_SIZE {
        return Err(Drop::Truncated);
    }
    let payload_len = usize::from(b[1]);
    let iflags = b[2];
    if iflags & !consts::v2::SUPPORTED_IFLAGS != 0 {
        return Err(Drop::UnsupportedFlags);
    }
    let header = if iflags & consts::v2::IFLAG_SYSID32 != 0 {
        MAX_HEADER
    } else {
        consts::v2::MIN_HEADER_SIZE
    };
    let signed = iflags & consts::v2::IFLAG_SIGNED != 0;
    let len = 1
        + header
        + payload_len
        + consts::CHECKSUM_SIZE
        + if signed {
            consts::v2::SIGNATURE_SIZE
        } else {
            0
        };
    if b.len() < len || len > consts::MAX_FRAME_SIZE {
        return Err(Drop::Truncated);
    }
    let mut buf = [0u8; consts::MAX_FRAME_SIZE];
    buf[..len].copy_from_slice(&b[..len]);
    let raw = MAVLinkV2MessageRaw::from_bytes_unparsed(buf);
    let id = raw.message_id();
    if MavMessage::default_message_from_id(id).is_none() {
        // The CRC of an unknown message cannot be checked (no CRC_EXTRA).
        return Ok((len, Err(Drop::UnknownMessage)));
    }
    if !raw.has_valid_crc::<MavMessage>() {
        return Err(Drop::BadCrc);
    }
    if let Some(s) = signing {
        if !signed {
            return Ok((len, Err(Drop::Unsigned)));
        }
        if !s.data.verify_signature(&raw) {
            return Ok((len, Err(Drop::BadSignature)));
        }
    }
    let r = MavMessage::parse(MavlinkVersion::V2, id, raw.payload())
        .map(|message| Received {
            system: raw.system_id(),
            message,
        })
        .map_err(|_| Drop::Undecodable);
    Ok((len, r))
}

/// The type name of a message (`HIL_SENSOR`, ...).
pub fn name_of(m: &MavMessage) -> &'static str {
    m.message_name()
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::{ATTITUDE_DATA, HIL_SENSOR_DATA};
    use proptest::prelude::*;

    fn hil(t: u64) -> MavMessage {
        MavMessage::HIL_SENSOR(HIL_SENSOR_DATA {
            time_usec: t,
            xacc: 1.5,
            ..HIL_SENSOR_DATA::DEFAULT
        })
    }

    fn parse_all(b: &[u8], s: Option<&Signing>) -> Vec<Result<Received, Drop>> {
        let mut v = Vec::new();
        parse_datagram(b, s, |r| v.push(r));
        v
    }

    #[test]
    fn frames_round_trip_and_several_per_datagram() {
        let mut e = Encoder::new(SIM_SYSTEM, None);
        let mut d = e.encode(&hil(10));
        d.extend(e.encode(&hil(20)));
        let r = parse_all(&d, None);
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].as_ref().unwrap().message, hil(10));
        assert_eq!(r[1].as_ref().unwrap().message, hil(20));
        assert_eq!(r[1].as_ref().unwrap().system, u32::from(SIM_SYSTEM));
    }

    #[test]
    fn every_kind_of_damage_is_sorted() {
        let mut e = Encoder::new(SIM_SYSTEM, None);
        let good = e.encode(&hil(10));
        // truncated
        let r = parse_all(&good[..good.len() - 3], None);
        assert!(r.contains(&Err(Drop::Truncated)), "{r:?}");
        // bad CRC: flip a payload byte
        let mut bad = good.clone();
        bad[12] ^= 0x40;
        assert!(parse_all(&bad, None).contains(&Err(Drop::BadCrc)));
        // garbage before a good frame: the frame still parses
        let mut g = vec![1u8, 2, 3];
        g.extend(&good);
        let r = parse_all(&g, None);
        assert_eq!(r[0], Err(Drop::Garbage));
        assert!(r[1].is_ok());
        // unknown message id
        let mut u = good.clone();
        u[7] = 0xEE;
        u[8] = 0xEE;
        u[9] = 0x0E;
        assert!(parse_all(&u, None).contains(&Err(Drop::UnknownMessage)));
        // unsupported incompatibility flag
        let mut f = good.clone();
        f[2] = 0x80;
        assert!(parse_all(&f, None).contains(&Err(Drop::UnsupportedFlags)));
        // a valid frame of another type parses (the caller decides it is unexpected)
        let a = e.encode(&MavMessage::ATTITUDE(ATTITUDE_DATA::DEFAULT));
        assert!(matches!(
            parse_all(&a, None)[0],
            Ok(Received {
                message: MavMessage::ATTITUDE(_),
                ..
            })
        ));
    }

    #[test]
    fn signing_accepts_the_key_and_refuses_the_rest() {
        let key = Signing::key_from_passphrase("fathom");
        let tx = Signing::new(key, 0);
        let rx = Signing::new(key, 0);
        let mut e = Encoder::new(SIM_SYSTEM, Some(tx));
        let f1 = e.encode(&hil(1));
        let f2 = e.encode(&hil(2));
        assert!(parse_all(&f1, Some(&rx))[0].is_ok());
        // replay of the same frame: timestamp not newer
        assert_eq!(parse_all(&f1, Some(&rx))[0], Err(Drop::BadSignature));
        assert!(parse_all(&f2, Some(&rx))[0].is_ok());
        // another key
        let other = Signing::new(Signing::key_from_passphrase("other"), 0);
        let f3 = e.encode(&hil(3));
        assert_eq!(parse_all(&f3, Some(&other))[0], Err(Drop::BadSignature));
        // unsigned frames refused
        let mut plain = Encoder::new(SIM_SYSTEM, None);
        assert_eq!(
            parse_all(&plain.encode(&hil(4)), Some(&rx))[0],
            Err(Drop::Unsigned)
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        #[test]
        fn any_bytes_parse_without_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
            let mut n = 0;
            parse_datagram(&bytes, None, |_| n += 1);
            prop_assert!(n <= bytes.len());
        }

        #[test]
        fn any_mutation_of_a_frame_is_caught_or_harmless(i in 0usize..40, x in 1u8..=255) {
            let mut e = Encoder::new(SIM_SYSTEM, None);
            let good = e.encode(&hil(123_456));
            let mut b = good.clone();
            let i = i % b.len();
            b[i] ^= x;
            let r = parse_all(&b, None);
            // A changed byte never yields the original message with other content.
            for m in r.into_iter().flatten() {
                if let MavMessage::HIL_SENSOR(d) = m.message {
                    prop_assert!(d.time_usec == 123_456 && d.xacc == 1.5);
                }
            }
        }
    }
}
