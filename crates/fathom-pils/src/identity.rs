//! What the simulator flies, said on the link: a `STATUSTEXT` (`fathom <scene>/<method>
//! run <r> #<hash>`, the hash the first 8 hex digits of the SHA-256 of the resolved
//! scenario) sent with every step of the rest, before the navigation starts. The
//! navigation compares each copy it receives with what it navigates and refuses a
//! mismatch with one line naming both, so two processes started by hand never label
//! one method's solutions with another's name. A simulator that says nothing (not
//! fathom's) is not checked.

use mavlink::dialects::common::{MavMessage, MavSeverity, STATUSTEXT_DATA};

/// The prefix of an identity text.
const PREFIX: &str = "fathom ";
/// Bytes of a `STATUSTEXT`.
const TEXT_BYTES: usize = 50;

/// The identity as it fits on the wire (cut at a character boundary).
pub fn wire_text(identity: &str) -> String {
    let mut t = format!("{PREFIX}{identity}");
    let mut end = t.len().min(TEXT_BYTES);
    while !t.is_char_boundary(end) {
        end -= 1;
    }
    t.truncate(end);
    t
}

/// The `STATUSTEXT` of an identity.
pub fn encode(identity: &str) -> MavMessage {
    MavMessage::STATUSTEXT(STATUSTEXT_DATA {
        severity: MavSeverity::MAV_SEVERITY_INFO,
        text: wire_text(identity).as_str().into(),
        id: 0,
        chunk_seq: 0,
    })
}

/// The identity text of a `STATUSTEXT` (with its prefix), if it is one.
pub fn decode(d: &STATUSTEXT_DATA) -> Option<String> {
    let t = d.text.to_str().ok()?;
    t.starts_with(PREFIX).then(|| t.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identities_round_trip_and_long_ones_are_cut_on_a_character() {
        let MavMessage::STATUSTEXT(d) = encode("bridge/GREKF run 1 #0123abcd") else {
            unreachable!()
        };
        assert_eq!(
            decode(&d).as_deref(),
            Some("fathom bridge/GREKF run 1 #0123abcd")
        );
        let long = format!("{}/MGPMF run 0 #ffffffff", "ü".repeat(40));
        let t = wire_text(&long);
        assert!(t.len() <= TEXT_BYTES && t.starts_with("fathom ü"), "{t}");
        let MavMessage::STATUSTEXT(d) = encode(&long) else {
            unreachable!()
        };
        assert_eq!(decode(&d), Some(t));
        let other = STATUSTEXT_DATA {
            text: "battery low".into(),
            ..d
        };
        assert_eq!(decode(&other), None);
    }
}
