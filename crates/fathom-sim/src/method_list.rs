//! Method selection in scenario files: the `methods = [...]` key of the experiments
//! that have one ([`crate::experiment::Experiment::METHODS`] not empty; default: all
//! their methods), and the names of the `[[methods]]` tables of the
//! replays of one's own logs. Errors name the key (`methods[2]`) and list what the
//! experiment accepts.

use crate::SimError;

/// Checks a list of method names written by the user as output labels: not empty,
/// unique, letters, digits, `_` and `-` only (they become CSV headers and legend
/// entries).
///
/// # Errors
/// [`SimError::Invalid`] naming `methods` or `methods[i].name`.
pub fn check_method_names(file: &str, names: &[&str]) -> Result<(), SimError> {
    if names.is_empty() {
        return Err(SimError::invalid(
            file,
            "methods",
            "lists no method; give at least one",
        ));
    }
    for (i, name) in names.iter().enumerate() {
        let key = format!("methods[{i}].name");
        if name.is_empty()
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        {
            return Err(SimError::invalid(
                file,
                key,
                format!("{name:?}: a method name has letters, digits, `_` and `-` only"),
            ));
        }
        if names[..i].contains(name) {
            return Err(SimError::invalid(
                file,
                key,
                format!("{name:?} appears twice"),
            ));
        }
    }
    Ok(())
}

/// The methods an experiment runs: `given` (the scenario's `methods`) checked against
/// `accepted` (the experiment's method names, in report order). Returns the selected
/// names in the experiment's order (the order written does not matter).
///
/// # Errors
/// [`SimError::Invalid`] naming `methods` (empty list) or `methods[i]` (a name the
/// experiment does not have, listing the accepted ones; a name given twice).
pub fn select_methods(
    file: &str,
    experiment: &str,
    given: &[String],
    accepted: &[&str],
) -> Result<Vec<String>, SimError> {
    if given.is_empty() {
        return Err(SimError::invalid(
            file,
            "methods",
            format!(
                "lists no method; `{experiment}` accepts {} (leave the key out for all)",
                accepted.join(", ")
            ),
        ));
    }
    for (i, name) in given.iter().enumerate() {
        let key = format!("methods[{i}]");
        if !accepted.contains(&name.as_str()) {
            return Err(SimError::invalid(
                file,
                key,
                format!(
                    "unknown method {name:?}; `{experiment}` accepts {}",
                    accepted.join(", ")
                ),
            ));
        }
        if given[..i].contains(name) {
            return Err(SimError::invalid(
                file,
                key,
                format!("{name:?} appears twice"),
            ));
        }
    }
    Ok(accepted
        .iter()
        .filter(|a| given.iter().any(|g| g == *a))
        .map(|a| a.to_string())
        .collect())
}

/// The methods a scenario's `methods` key selects from `all` (the experiment's
/// methods in report order, `name` giving each one's name): every one when the key
/// is absent, else the named ones in `all`'s order ([`select_methods`]).
///
/// # Errors
/// As [`select_methods`].
pub fn select<T: Copy>(
    file: &str,
    experiment: &str,
    given: Option<&[String]>,
    all: &[T],
    name: impl Fn(T) -> &'static str,
) -> Result<Vec<T>, SimError> {
    let Some(given) = given else {
        return Ok(all.to_vec());
    };
    let names: Vec<&str> = all.iter().map(|&m| name(m)).collect();
    let chosen = select_methods(file, experiment, given, &names)?;
    Ok(all
        .iter()
        .copied()
        .filter(|&m| chosen.iter().any(|c| c == name(m)))
        .collect())
}

/// `accepted` as an owned list: the default of a `methods` key.
pub fn all(accepted: &[&str]) -> Vec<String> {
    accepted.iter().map(|s| s.to_string()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn selection_keeps_the_experiment_order_and_names_bad_entries() {
        let acc = ["AS", "SC", "SI"];
        let s = select_methods("f.toml", "beacons", &all(&["SI", "AS"]), &acc).unwrap();
        assert_eq!(s, ["AS", "SI"]);
        let e = select_methods("f.toml", "beacons", &all(&["AS", "UKF"]), &acc)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "f.toml: key `methods[1]`: unknown method \"UKF\"; `beacons` accepts AS, SC, SI"
        );
        let e = select_methods("f.toml", "beacons", &all(&["SC", "SC"]), &acc).unwrap_err();
        assert!(
            e.to_string().contains("`methods[1]`: \"SC\" appears twice"),
            "{e}"
        );
        let e = select_methods("f.toml", "beacons", &[], &acc).unwrap_err();
        assert!(
            e.to_string().contains("key `methods`: lists no method"),
            "{e}"
        );
        assert!(check_method_names("f", &["a-1", "b_2"]).is_ok());
        for bad in [&["a", "a"][..], &["a b"], &[""], &[]] {
            assert!(check_method_names("f", bad).is_err(), "{bad:?}");
        }
    }
}
