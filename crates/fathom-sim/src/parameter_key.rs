//! The scenario key behind a parameter check's error: the parameter the error names
//! ([`ParameterError`]) found among the keys of the scenario table the parameters
//! came from, so that the message names the key the user wrote (issue #38).

use fathom_core::ParameterError;
use serde::Serialize;

use crate::SimError;

/// A parameter check's error as a scenario error ([`SimError::Invalid`]) naming the
/// key of `section` (the scenario table at `table_path`) that the error's parameter
/// is ([`key_of`]); the table itself when the parameter is none of its keys (a value
/// derived from several).
pub fn parameter_invalid<E: ParameterError>(
    file: &str,
    table_path: &str,
    section: &impl Serialize,
    e: &E,
) -> SimError {
    parameter_invalid_aliased(file, table_path, section, e, &[])
}

/// [`parameter_invalid`] where some parameters have names of their own: `aliases`
/// pairs the last word of a parameter's name (`sigma0[2]`) with its key
/// (`sigma0_accel_bias_mps2`).
pub fn parameter_invalid_aliased<E: ParameterError>(
    file: &str,
    table_path: &str,
    section: &impl Serialize,
    e: &E,
    aliases: &[(&str, &str)],
) -> SimError {
    let keys = section_keys(section);
    let key = e.parameter().and_then(|p| {
        let word = p.rsplit(' ').next().unwrap_or(&p);
        aliases
            .iter()
            .find(|(name, _)| *name == word)
            .map(|(_, key)| (*key).to_string())
            .or_else(|| key_of(&p, &keys))
    });
    let key = key.map_or_else(|| table_path.to_string(), |k| format!("{table_path}.{k}"));
    SimError::invalid(file, key, e.to_string())
}

/// The top-level keys `section` serializes to (none for a value that is not a table).
pub fn section_keys(section: &impl Serialize) -> Vec<String> {
    match toml::Value::try_from(section) {
        Ok(toml::Value::Table(t)) => t.keys().cloned().collect(),
        _ => Vec::new(),
    }
}

/// The key among `keys` that a parameter called `name` is, with its array index:
/// the last word of `name` (`nav accel_psd` is `accel_psd`), then its last dotted
/// part or all its parts joined by `_` (`imu.arw` is `arw`, `range.gate_probability`
/// is `range_gate_probability`), equal to a key or, when exactly one key is it with a
/// unit suffix, that key (`rpm.b` is `b_mps`).
pub fn key_of(name: &str, keys: &[String]) -> Option<String> {
    let word = name.rsplit(' ').next()?;
    let (base, index) = match word.find('[') {
        Some(i) => (&word[..i], &word[i..]),
        None => (word, ""),
    };
    let parts: Vec<&str> = base.split('.').collect();
    let mut candidates = vec![(*parts.last()?).to_string(), parts.join("_")];
    if parts.len() > 2 {
        candidates.push(parts[1..].join("_"));
    }
    if let Some(c) = candidates.iter().find(|c| keys.contains(c)) {
        return Some(format!("{c}{index}"));
    }
    candidates.iter().find_map(|c| {
        let prefix = format!("{c}_");
        let mut with_unit = keys.iter().filter(|k| k.starts_with(&prefix));
        match (with_unit.next(), with_unit.next()) {
            (Some(k), None) => Some(format!("{k}{index}")),
            _ => None,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(names: &[&str]) -> Vec<String> {
        names.iter().map(|s| (*s).to_string()).collect()
    }

    #[test]
    fn names_map_onto_the_keys_the_user_wrote() {
        let k = keys(&[
            "rate_hz",
            "b_mps",
            "k_mps_per_rpm",
            "range_gate_probability",
            "grid_points",
            "sigma0_pos_m",
            "sigma0_vel_mps",
        ]);
        assert_eq!(key_of("rate_hz", &k).as_deref(), Some("rate_hz"));
        assert_eq!(key_of("rpm.b", &k).as_deref(), Some("b_mps"));
        assert_eq!(key_of("rpm.k", &k).as_deref(), Some("k_mps_per_rpm"));
        assert_eq!(
            key_of("range.gate_probability", &k).as_deref(),
            Some("range_gate_probability")
        );
        assert_eq!(
            key_of("setting mgpmf.grid_points[0]", &k).as_deref(),
            Some("grid_points[0]")
        );
        // ambiguous (two keys with that start) or unknown: no key, the table is named
        assert_eq!(key_of("nav sigma0[2]", &k), None);
        assert_eq!(key_of("box.z[1]", &k), None);
    }
}
