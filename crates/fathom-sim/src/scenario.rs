//! Scenario files: TOML loading into `serde` structs with error messages that name the
//! file, the key path and the line, plus small validation helpers for scenario values.
//!
//! Scenario structs are plain `serde` structs with `#[serde(deny_unknown_fields)]`; a
//! typo, a wrong type or a missing field gives one [`SimError::Toml`] such as
//!
//! ```text
//! noise.toml: key `noise.range_sigma`: line 3, column 15: invalid type: string "x", expected f64
//! ```

use std::path::Path;

use serde::de::DeserializeOwned;

use crate::error::SimError;

/// Read a TOML file and deserialize it into `T`.
///
/// The file label used in error messages is the path as given.
///
/// # Errors
/// [`SimError::Io`] if the file cannot be read, [`SimError::Toml`] if it does not parse
/// or does not match `T`.
pub fn load_toml<T: DeserializeOwned>(path: impl AsRef<Path>) -> Result<T, SimError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| SimError::io("read", path, e))?;
    parse_toml(&text, &path.display().to_string())
}

/// Deserialize TOML `text` into `T`; `file_label` names the source in error messages.
///
/// # Errors
/// [`SimError::Toml`] with the key path (when it can be determined) and the 1-based
/// line and column of the offending text.
pub fn parse_toml<T: DeserializeOwned>(text: &str, file_label: &str) -> Result<T, SimError> {
    ScenarioDoc::parse(text, file_label)?.into_typed()
}

/// A scenario text parsed once: its TOML syntax tree, with the position of every key
/// and value, from which the experiment is picked ([`ScenarioDoc::peek`]), the magnitudes
/// are checked ([`ScenarioDoc::table`]) and the typed scenario is read
/// ([`ScenarioDoc::into_typed`]), each error naming the line of the user's text.
#[derive(Clone)]
pub struct ScenarioDoc<'a> {
    text: &'a str,
    file: &'a str,
    root: toml::Spanned<toml::de::DeTable<'a>>,
}

impl std::fmt::Debug for ScenarioDoc<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ScenarioDoc")
            .field("file", &self.file)
            .field("bytes", &self.text.len())
            .finish()
    }
}

impl<'a> ScenarioDoc<'a> {
    /// Parses `text` (the one TOML parse of a scenario); `file` labels errors.
    ///
    /// # Errors
    /// [`SimError::Toml`] for a syntax error, with its line and column.
    pub fn parse(text: &'a str, file: &'a str) -> Result<Self, SimError> {
        #[cfg(test)]
        PARSES.with(|p| p.borrow_mut().push(file.to_string()));
        let root = toml::de::DeTable::parse(text).map_err(|e| toml_error(&e, text, file))?;
        Ok(ScenarioDoc { text, file, root })
    }

    /// The text as the user wrote it.
    pub fn text(&self) -> &'a str {
        self.text
    }

    /// The label of the text in error messages.
    pub fn file(&self) -> &'a str {
        self.file
    }

    /// Some keys read leniently from the tree (the tree is kept).
    ///
    /// # Errors
    /// [`SimError::Toml`] when the keys do not match `T`.
    pub fn peek<T: DeserializeOwned>(&self) -> Result<T, SimError> {
        self.clone().into_typed()
    }

    /// The document as an untyped table (the magnitude checks walk it).
    ///
    /// # Errors
    /// [`SimError::Toml`] (not expected: the tree is valid TOML).
    pub fn table(&self) -> Result<toml::Table, SimError> {
        self.peek()
    }

    /// The typed scenario, read from the tree.
    ///
    /// # Errors
    /// [`SimError::Toml`] with the key path and the line and column of the offending text
    /// (an unknown key, a wrong type, a missing field).
    pub fn into_typed<T: DeserializeOwned>(self) -> Result<T, SimError> {
        let (text, file) = (self.text, self.file);
        T::deserialize(toml::de::Deserializer::from(self.root))
            .map_err(|e| toml_error(&e, text, file))
    }
}

#[cfg(test)]
thread_local! {
    /// The labels of the texts [`ScenarioDoc::parse`] parsed on this thread (tests count
    /// them: a scenario is parsed once per run).
    pub(crate) static PARSES: std::cell::RefCell<Vec<String>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// Convert a `toml` deserialization error into a [`SimError::Toml`].
fn toml_error(err: &toml::de::Error, text: &str, file_label: &str) -> SimError {
    let message = plain_types(err.message().trim());
    let table_keys = keys_from_error(err);
    // A missing field's span is its whole enclosing table: at the top level that is the
    // whole file, so a line number would only point at line 1; inside a table it is the
    // table's header, which is worth printing.
    let missing = missing_field_name(&message);
    let span = err
        .span()
        .filter(|_| !(missing.is_some() && table_keys.is_none()));
    let (line, column) = match &span {
        Some(s) => {
            let (l, c) = line_col(text, s.start);
            (Some(l), Some(c))
        }
        None => (None, None),
    };
    let field = unknown_field_name(&message).or_else(|| missing.clone());
    let key_path = match (table_keys, field) {
        // The deserializer records the enclosing table for an unknown or missing field;
        // add the field.
        (Some(table), Some(field)) if !table.ends_with(&field) => Some(format!("{table}.{field}")),
        (Some(keys), _) => Some(keys),
        (None, Some(field)) if missing.is_some() => Some(field),
        (None, _) => span
            .as_ref()
            .and_then(|s| key_path_at(text, s.start, &message)),
    };
    SimError::Toml {
        file: file_label.to_string(),
        key_path,
        line,
        column,
        message,
    }
}

/// The `toml` / serde message with Rust type names said in words ("integer `-5`,
/// expected usize" becomes "integer `-5`, expected a whole number >= 0").
fn plain_types(message: &str) -> String {
    let mut m = message.replace(" as i128", "").replace(" as u128", "");
    for (rust, plain) in [
        ("expected usize", "expected a whole number >= 0"),
        (
            "expected u64",
            "expected a whole number from 0 to 9223372036854775807 (2^63 - 1)",
        ),
        (
            "expected u32",
            "expected a whole number from 0 to 4294967295",
        ),
        ("expected u16", "expected a whole number from 0 to 65535"),
        ("expected u8", "expected a whole number from 0 to 255"),
        ("expected i64", "expected a whole number"),
        ("expected i32", "expected a whole number"),
        ("expected f64", "expected a number"),
        ("expected f32", "expected a number"),
    ] {
        m = m.replace(rust, plain);
    }
    m
}

/// The dotted key path the `toml` crate recorded for the error.
///
/// `toml::de::Error` keeps the key path private; its `Display` prints it as a last line
/// "in `a.b`" when the error carries no input text, so a copy without input is rendered
/// and that line is read back.
fn keys_from_error(err: &toml::de::Error) -> Option<String> {
    let mut bare = err.clone();
    bare.set_input(None);
    let rendered = bare.to_string();
    let last = rendered.trim_end().lines().last()?;
    let inner = last.strip_prefix("in `")?.strip_suffix('`')?;
    (!inner.is_empty()).then(|| inner.to_string())
}

/// 1-based (line, column in characters) of byte `offset` in `text`.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = text[line_start..offset].chars().count() + 1;
    (line, column)
}

/// Reconstruct the key path at byte `offset` from the text: the enclosing `[table]`
/// header plus the key on that line (or the unknown field named in `message`).
fn key_path_at(text: &str, offset: usize, message: &str) -> Option<String> {
    let offset = offset.min(text.len());
    let mut table = String::new();
    let mut line_key = None;
    let mut pos = 0usize;
    for raw in text.split_inclusive('\n') {
        let start = pos;
        pos += raw.len();
        let line = raw.trim();
        if line.starts_with('[') {
            let name = line.trim_start_matches('[');
            if let Some(end) = name.find(']') {
                table = clean_key(&name[..end]);
            }
            if start <= offset && offset < pos {
                break;
            }
        } else if start <= offset && offset < pos {
            if let Some(eq) = line.find('=') {
                line_key = Some(clean_key(&line[..eq]));
            }
            break;
        }
        if pos > offset {
            break;
        }
    }
    // An unknown field is named in the message; prefer it.
    let key = unknown_field_name(message).or(line_key);
    match (table.is_empty(), key) {
        (true, Some(k)) => Some(k),
        (false, Some(k)) => Some(format!("{table}.{k}")),
        (false, None) => Some(table),
        (true, None) => None,
    }
}

fn missing_field_name(message: &str) -> Option<String> {
    let rest = message.strip_prefix("missing field `")?;
    let end = rest.find('`')?;
    Some(rest[..end].to_string())
}

fn unknown_field_name(message: &str) -> Option<String> {
    let rest = message.strip_prefix("unknown field `")?;
    let end = rest.find('`')?;
    Some(rest[..end].to_string())
}

fn clean_key(k: &str) -> String {
    k.split('.')
        .map(|p| p.trim().trim_matches('"').trim_matches('\''))
        .collect::<Vec<_>>()
        .join(".")
}

/// Check that a scenario value is finite and `> 0`.
///
/// # Errors
/// [`SimError::Invalid`] such as `noise.toml: key `noise.range_sigma`: must be > 0, got -0.1`.
pub fn require_positive(file: &str, key_path: &str, value: f64) -> Result<f64, SimError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SimError::invalid(
            file,
            key_path,
            format!("must be > 0, got {value}"),
        ))
    }
}

/// Check that a scenario value is finite and `>= 0`.
///
/// # Errors
/// [`SimError::Invalid`] naming the file, key and value.
pub fn require_non_negative(file: &str, key_path: &str, value: f64) -> Result<f64, SimError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(SimError::invalid(
            file,
            key_path,
            format!("must be >= 0, got {value}"),
        ))
    }
}

/// Check that a scenario value is finite and within `[lo, hi]`.
///
/// # Errors
/// [`SimError::Invalid`] naming the file, key, range and value.
pub fn require_in_range(
    file: &str,
    key_path: &str,
    value: f64,
    lo: f64,
    hi: f64,
) -> Result<f64, SimError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(SimError::invalid(
            file,
            key_path,
            format!("must be in [{lo}, {hi}], got {value}"),
        ))
    }
}

/// Largest magnitude of a position or length (keys ending in `_m`, and
/// `positions`): 10⁷ m, beyond the Earth's radius, where ranges and their squares
/// stop being meaningful.
pub const MAX_LENGTH_M: f64 = 1e7;

/// Largest noise σ (keys containing `sigma`), in the key's unit: 10⁶. Beyond it no
/// sensor is described and σ² heads for overflow.
pub const MAX_SIGMA: f64 = 1e6;

/// Largest power spectral density (keys ending in `_psd`): 10¹², the square of
/// [`MAX_SIGMA`].
pub const MAX_PSD: f64 = 1e12;

/// Checks the magnitudes that hold for every scenario, whatever the experiment:
/// every number with a decimal point or exponent finite, within [`MAX_ANY`] and 0 or
/// at least [`MIN_ANY`],
/// positions and lengths within [`MAX_LENGTH_M`], noise σ within [`MAX_SIGMA`], PSDs
/// within [`MAX_PSD`] (by key name, see the units table of `docs/scenarios.md`).
/// Values beyond them would make the geometry or the noise meaningless (a beacon at
/// 10³⁰⁸ m gives non-finite ranges), so they are refused when the file is checked.
///
/// `table` is the scenario as the user wrote it ([`ScenarioDoc::table`]).
///
/// # Errors
/// [`SimError::Invalid`] naming the key (with its array index) and the value.
pub fn check_magnitudes(table: &toml::Table, file: &str) -> Result<(), SimError> {
    walk_table(table, "", file)
}

fn walk_table(table: &toml::Table, prefix: &str, file: &str) -> Result<(), SimError> {
    for (k, v) in table {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        walk_value(v, k, &path, file)?;
    }
    Ok(())
}

fn walk_value(v: &toml::Value, key: &str, path: &str, file: &str) -> Result<(), SimError> {
    match v {
        toml::Value::Table(t) => walk_table(t, path, file),
        toml::Value::Array(a) => {
            for (i, item) in a.iter().enumerate() {
                walk_value(item, key, &format!("{path}[{i}]"), file)?;
            }
            Ok(())
        }
        // the magnitude (the key's own limit, else MAX_ANY), then finite and not tiny
        toml::Value::Float(x) => {
            check_magnitude(*x, key, true, path, file)?;
            check_any_number(*x, path, file)
        }
        toml::Value::Integer(i) => check_magnitude(*i as f64, key, false, path, file),
        _ => Ok(()),
    }
}

/// Largest magnitude of any number written with a decimal point or exponent in a
/// scenario, whatever its unit: 10¹². No quantity of fathom's scenarios comes near
/// it (the GNSS orbits are 2.7·10⁷ m, a week is 6·10⁵ s); beyond it a value is a
/// slip, and one that overflows what it is multiplied with. Whole numbers (seeds,
/// counts) have their own checks.
pub const MAX_ANY: f64 = 1e12;

/// Smallest magnitude of a nonzero number with a decimal point or exponent in a
/// scenario: 10⁻¹⁰⁰. The smallest quantities of fathom's scenarios (spectral
/// densities of bias random walks) are near 10⁻¹⁴; below 10⁻¹⁰⁰ a value is a slip, and
/// its square (a variance) underflows towards 0. Zero itself is left to the keys'
/// own checks.
pub const MIN_ANY: f64 = 1e-100;

/// Every number with a decimal point or exponent: finite (no scenario value means
/// NaN or infinity) and 0 or at least [`MIN_ANY`] (its upper limit is
/// [`check_magnitude`]'s).
fn check_any_number(x: f64, path: &str, file: &str) -> Result<(), SimError> {
    if !x.is_finite() {
        return Err(SimError::invalid(
            file,
            path,
            format!("must be finite, got {x}"),
        ));
    }
    if x != 0.0 && x.abs() < MIN_ANY {
        return Err(SimError::invalid(
            file,
            path,
            format!(
                "must be 0 or at least {MIN_ANY:e} in magnitude, got {}: its square \
                 underflows (write 0 where zero is meant)",
                crate::cost::short(x)
            ),
        ));
    }
    Ok(())
}

/// The largest magnitude of the value at `key`: by the key's name, else, for a number
/// with a decimal point or exponent (`float`), [`MAX_ANY`]; whole numbers (seeds,
/// counts) have their own checks.
fn check_magnitude(x: f64, key: &str, float: bool, path: &str, file: &str) -> Result<(), SimError> {
    let (limit, what) = if key.contains("sigma") {
        (
            MAX_SIGMA,
            "a noise σ beyond 1e6 (in the key's unit) describes no sensor",
        )
    } else if key.ends_with("_psd") {
        (
            MAX_PSD,
            "a spectral density beyond 1e12 describes no sensor",
        )
    } else if key.ends_with("_m") || key == "positions" {
        (
            MAX_LENGTH_M,
            "positions and lengths beyond 1e7 m (more than the Earth's radius) make ranges meaningless",
        )
    } else if float {
        (MAX_ANY, "no quantity of a scenario is that large")
    } else {
        return Ok(());
    };
    if x.is_finite() && x.abs() > limit {
        return Err(SimError::invalid(
            file,
            path,
            format!(
                "must be at most {limit:e} in magnitude, got {}: {what}",
                crate::cost::short(x)
            ),
        ));
    }
    Ok(())
}

/// Check the top-level `experiment` key of a scenario file names `expected`.
///
/// # Errors
/// [`SimError::Invalid`] naming the key `experiment`.
pub fn require_experiment(file: &str, value: &str, expected: &str) -> Result<(), SimError> {
    if value == expected {
        Ok(())
    } else {
        Err(SimError::invalid(
            file,
            "experiment",
            format!("this is a `{expected}` scenario, so it must be \"{expected}\", got {value:?}"),
        ))
    }
}

/// Serialize a (resolved) scenario back to TOML.
///
/// # Errors
/// [`SimError::InvalidArgument`] if the value cannot be written as TOML.
pub fn to_toml<T: serde::Serialize>(value: &T, file: &str) -> Result<String, SimError> {
    toml::to_string(value)
        .map_err(|e| SimError::invalid_argument(format!("scenario `{file}`"), e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Demo {
        name: String,
        noise: Noise,
    }

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Noise {
        range_sigma: f64,
        runs: usize,
    }

    fn err_text(text: &str) -> (SimError, String) {
        let e = parse_toml::<Demo>(text, "demo.toml").unwrap_err();
        let s = e.to_string();
        (e, s)
    }

    #[test]
    fn parses_valid_file() {
        let d: Demo = parse_toml(
            "name = \"a\"\n[noise]\nrange_sigma = 0.5\nruns = 3\n",
            "demo.toml",
        )
        .unwrap();
        assert_eq!(d.noise.runs, 3);
        assert_eq!(d.noise.range_sigma, 0.5);
    }

    #[test]
    fn unknown_key_names_file_key_and_line() {
        let (e, s) = err_text("name = \"a\"\n[noise]\nrange_sigma = 0.5\nrunz = 3\n");
        println!("{s}");
        assert!(s.starts_with("demo.toml"), "{s}");
        assert!(s.contains("`noise.runz`"), "{s}");
        assert!(s.contains("line 4"), "{s}");
        assert!(s.contains("unknown field `runz`"), "{s}");
        assert!(matches!(e, SimError::Toml { line: Some(4), .. }));
    }

    #[test]
    fn messages_say_types_in_words() {
        assert_eq!(
            plain_types("invalid type: integer `99999999999999999999` as i128, expected u64"),
            "invalid type: integer `99999999999999999999`, expected a whole number from 0 to \
             9223372036854775807 (2^63 - 1)"
        );
        assert_eq!(
            plain_types("invalid value: integer `-5`, expected usize"),
            "invalid value: integer `-5`, expected a whole number >= 0"
        );
        assert_eq!(
            plain_types("invalid type: string \"a\", expected f64"),
            "invalid type: string \"a\", expected a number"
        );
    }

    #[test]
    fn wrong_type_names_file_key_and_line() {
        let (_, s) = err_text("name = \"a\"\n[noise]\nrange_sigma = \"x\"\nruns = 3\n");
        println!("{s}");
        assert!(s.starts_with("demo.toml"), "{s}");
        assert!(s.contains("`noise.range_sigma`"), "{s}");
        assert!(s.contains("line 3"), "{s}");
        assert!(s.contains("invalid type"), "{s}");
    }

    #[test]
    fn missing_field_names_file_and_field() {
        let (_, s) = err_text("name = \"a\"\n[noise]\nrange_sigma = 0.5\n");
        println!("{s}");
        assert!(s.starts_with("demo.toml"), "{s}");
        assert!(s.contains("missing field `runs`"), "{s}");
        assert!(s.contains("key `noise.runs`"), "{s}");
        assert!(s.contains("line 2"), "{s}");
    }

    #[test]
    fn missing_top_level_field_names_the_field_not_line_one() {
        // Before: the key path was taken from whatever stood on line 1 (`name`).
        let (e, s) = err_text("name = \"a\"\n");
        println!("{s}");
        assert!(
            s.starts_with("demo.toml: key `noise`: missing field `noise`"),
            "{s}"
        );
        assert!(matches!(e, SimError::Toml { line: None, .. }), "{e:?}");
    }

    #[test]
    fn top_level_unknown_key_and_file_label() {
        let (_, s) = err_text("nam = \"a\"\n[noise]\nrange_sigma = 0.5\nruns = 3\n");
        assert!(s.starts_with("demo.toml: key `nam`: line 1"), "{s}");
        let dir = std::env::temp_dir()
            .join("fathom-sim-tests")
            .join("scenario");
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("bad.toml");
        std::fs::write(&p, "name = 3\n").unwrap();
        let s = load_toml::<Demo>(&p).unwrap_err().to_string();
        assert!(
            s.starts_with(&format!("{}: key `name`: line 1", p.display())),
            "{s}"
        );
    }

    #[test]
    fn syntax_error_gives_line() {
        let (_, s) = err_text("name = \"a\"\n[noise]\nrange_sigma = = 0.5\nruns = 3\n");
        println!("{s}");
        assert!(s.starts_with("demo.toml"), "{s}");
        assert!(s.contains("line 3"), "{s}");
    }

    #[test]
    fn load_missing_file_is_io_error() {
        let e = load_toml::<Demo>("/nonexistent/fathom/demo.toml").unwrap_err();
        assert!(matches!(e, SimError::Io { .. }));
        assert!(e.to_string().contains("/nonexistent/fathom/demo.toml"));
    }

    #[test]
    fn line_col_counts_from_one() {
        assert_eq!(line_col("ab\ncd", 0), (1, 1));
        assert_eq!(line_col("ab\ncd", 4), (2, 2));
        assert_eq!(line_col("ab\ncd", 99), (2, 3));
    }

    #[test]
    fn magnitudes_beyond_any_sensor_or_place_are_refused_with_their_key() {
        let check_magnitudes = |text: &str, file: &str| {
            let table = ScenarioDoc::parse(text, file).unwrap().table().unwrap();
            check_magnitudes(&table, file)
        };
        let ok = "[a]\nx_m = 1e6\nsigma_m = 3.0\npositions = [[1.0, 2.0, 3.0]]\nn = 1e12\n";
        assert!(check_magnitudes(ok, "f").is_ok());
        // any other number: finite and within MAX_ANY
        for (text, key) in [
            ("[a]\nn = 1.5e12\n", "a.n"),
            ("[a]\nn = nan\n", "a.n"),
            ("[a]\nn = -1e-300\n", "a.n"),
            ("n = [1.0, -inf]\n", "n[1]"),
        ] {
            match check_magnitudes(text, "f") {
                Err(SimError::Invalid { key_path, .. }) => assert_eq!(key_path, key, "{text}"),
                other => panic!("{text}: {other:?}"),
            }
        }
        for (text, key) in [
            (
                "[beacons]\npositions = [[0.0, 1e308, 0.0]]\n",
                "beacons.positions[0][1]",
            ),
            ("[noise]\nrange_sigma_m = 1e200\n", "noise.range_sigma_m"),
            ("velocity_sigma = [0.1, -2e6]\n", "velocity_sigma[1]"),
            ("[f]\naccel_psd = 1e13\n", "f.accel_psd"),
            ("[m]\nsearch_depth_m = -2e7\n", "m.search_depth_m"),
        ] {
            let e = check_magnitudes(text, "f.toml").unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("f.toml: key `{key}`: must be at most")),
                "{e}"
            );
            // The value is shown short (`1.0e308`), not as 309 digits.
            assert!(e.len() < 200, "{e}");
        }
        // Non-finite values are refused here too, naming the key.
        let e = check_magnitudes("x_m = nan\n", "f")
            .unwrap_err()
            .to_string();
        assert!(e.contains("key `x_m`: must be finite"), "{e}");
    }

    #[test]
    fn validation_helpers() {
        let e = require_positive("noise.toml", "noise.range_sigma", -0.1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "noise.toml: key `noise.range_sigma`: must be > 0, got -0.1"
        );
        assert!(require_positive("f", "k", f64::NAN).is_err());
        assert_eq!(require_positive("f", "k", 2.0).unwrap(), 2.0);
        assert!(require_non_negative("f", "k", -1e-9).is_err());
        assert_eq!(require_non_negative("f", "k", 0.0).unwrap(), 0.0);
        assert!(require_in_range("f", "k", 1.5, 0.0, 1.0).is_err());
        assert_eq!(require_in_range("f", "k", 1.0, 0.0, 1.0).unwrap(), 1.0);
    }
}
