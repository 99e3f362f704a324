//! Checks `docs/scenarios.md` against the scenario schemas so that the documentation
//! of the scenario format cannot drift from the code (test-only module).
//!
//! For every preset in `scenarios/` the check resolves the file with
//! [`crate::user_run::check_scenario_text`] (what `fathom check` prints) and
//! - walks every leaf key path of the resolved TOML (arrays of tables as `name[]`);
//! - asks every table of the schema for its complete field list by inserting an
//!   unknown probe key (`deny_unknown_fields` answers "expected one of ..."), so an
//!   optional key that the preset leaves out and the resolution does not write still
//!   needs a row; a table that accepts the probe is reported (it lacks
//!   `deny_unknown_fields`);
//! - requires one row per key in the experiment's section of the document, and no
//!   row for a key that does not exist (stale rows);
//! - compares each row's type with the resolved value's TOML type;
//! - for a row with a default, removes the key from the preset, resolves again and
//!   compares the resolved value with the documented default (`unset`: the key stays
//!   absent); for a `required` row, checks that removing the key fails with an error
//!   naming it.
//!
//! The row format is documented in the HTML comment at the top of the document.

use std::collections::{BTreeMap, BTreeSet};

use toml::{Table, Value};

/// The unknown key inserted into every table to learn its schema's field list.
const PROBE: &str = "zz_scenario_docs_probe";

/// The documented default of a key.
#[derive(Debug, Clone, PartialEq)]
enum DocDefault {
    /// The key must be given.
    Required,
    /// Optional; absent from the resolved scenario when not given.
    Unset,
    /// Filled in with this value when not given.
    Value(Value),
}

/// One documented key (a table row).
#[derive(Debug, Clone, PartialEq)]
struct DocRow {
    /// Dotted key path, arrays of tables as `name[]`.
    key: String,
    /// First word of the type column (`float`, `integer`, `string`, `bool`, `array`).
    ty: String,
    /// The default column.
    default: DocDefault,
    /// 1-based line in the document.
    line: usize,
}

/// Rows per experiment section, in document order.
type DocSections = BTreeMap<String, Vec<DocRow>>;

/// Splits a Markdown table row into trimmed cells; `\|` is a literal pipe.
fn split_cells(line: &str) -> Vec<String> {
    let inner = line.trim();
    let inner = inner.strip_prefix('|').unwrap_or(inner);
    let inner = inner.strip_suffix('|').unwrap_or(inner);
    let mut cells = vec![String::new()];
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                chars.next();
                cells.last_mut().unwrap().push('|');
            }
            '|' => cells.push(String::new()),
            _ => cells.last_mut().unwrap().push(c),
        }
    }
    cells.iter().map(|c| c.trim().to_string()).collect()
}

/// The text between one pair of backticks that makes up the whole cell.
fn backticked(cell: &str) -> Option<&str> {
    let inner = cell.strip_prefix('`')?.strip_suffix('`')?;
    (!inner.is_empty() && !inner.contains('`')).then_some(inner)
}

fn parse_default(cell: &str) -> Result<DocDefault, String> {
    match cell {
        "required" => return Ok(DocDefault::Required),
        "unset" => return Ok(DocDefault::Unset),
        _ => {}
    }
    let inner = backticked(cell).ok_or_else(|| {
        format!("default must be `required`, `unset` or a TOML value in backticks, got {cell:?}")
    })?;
    let table: Table = toml::from_str(&format!("v = {inner}"))
        .map_err(|e| format!("default {cell:?} is not a TOML value: {}", e.message()))?;
    Ok(DocDefault::Value(table["v"].clone()))
}

/// Parses the experiment sections of the document (format: see the HTML comment at
/// the top of `docs/scenarios.md`).
fn parse_doc(doc: &str) -> Result<DocSections, Vec<String>> {
    let mut sections = DocSections::new();
    let mut errors = Vec::new();
    let mut section: Option<String> = None;
    let mut fenced = false;
    let mut comment = false;
    for (i, raw) in doc.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        if comment {
            comment = !line.contains("-->");
            continue;
        }
        if line.starts_with("<!--") {
            comment = !line.contains("-->");
            continue;
        }
        if line.starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        if let Some(title) = raw.strip_prefix("## ") {
            section = title
                .strip_prefix('`')
                .and_then(|t| t.split_once('`'))
                .map(|(name, _)| name.to_string());
            if let Some(name) = &section
                && sections.insert(name.clone(), Vec::new()).is_some()
            {
                errors.push(format!("line {line_no}: second section for `{name}`"));
            }
            continue;
        }
        let Some(name) = &section else { continue };
        if !line.starts_with('|') {
            continue;
        }
        let cells = split_cells(line);
        let first = cells[0].as_str();
        if first == "key" || first.starts_with("---") || first.starts_with(":--") {
            continue;
        }
        let Some(key) = backticked(first) else {
            errors.push(format!(
                "line {line_no}: a row of section `{name}` must start with a key in backticks, got {first:?}"
            ));
            continue;
        };
        if cells.len() != 6 {
            errors.push(format!(
                "line {line_no}: row `{key}` has {} cells, expected 6 (key | type | unit | default | range | meaning)",
                cells.len()
            ));
            continue;
        }
        let ty = cells[1]
            .split_whitespace()
            .next()
            .unwrap_or("")
            .to_lowercase();
        if !["float", "integer", "string", "bool", "array"].contains(&ty.as_str()) {
            errors.push(format!(
                "line {line_no}: row `{key}`: type must start with float, integer, string, bool or array, got {:?}",
                cells[1]
            ));
            continue;
        }
        match parse_default(&cells[3]) {
            Ok(default) => {
                let rows = sections.get_mut(name).unwrap();
                if rows.iter().any(|r| r.key == key) {
                    errors.push(format!(
                        "line {line_no}: row `{key}` appears twice in `{name}`"
                    ));
                }
                rows.push(DocRow {
                    key: key.to_string(),
                    ty,
                    default,
                    line: line_no,
                });
            }
            Err(e) => errors.push(format!("line {line_no}: row `{key}`: {e}")),
        }
    }
    if errors.is_empty() {
        Ok(sections)
    } else {
        Err(errors)
    }
}

/// The TOML type name used in the type column.
fn type_name(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "string",
        Value::Integer(_) => "integer",
        Value::Float(_) => "float",
        Value::Boolean(_) => "bool",
        Value::Datetime(_) => "datetime",
        Value::Array(_) => "array",
        Value::Table(_) => "table",
    }
}

fn is_table_array(v: &Value) -> bool {
    matches!(v, Value::Array(a) if !a.is_empty() && a.iter().all(Value::is_table))
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

/// Leaf key paths of `t` with the TOML types seen there, and the paths of its tables
/// (`""` for the root, `name[]` for arrays of tables).
fn walk(
    t: &Table,
    prefix: &str,
    leaves: &mut BTreeMap<String, BTreeSet<&'static str>>,
    tables: &mut BTreeSet<String>,
) {
    tables.insert(prefix.to_string());
    for (k, v) in t {
        let path = join(prefix, k);
        match v {
            Value::Table(sub) => walk(sub, &path, leaves, tables),
            Value::Array(a) if is_table_array(v) => {
                let path = format!("{path}[]");
                for sub in a.iter().filter_map(Value::as_table) {
                    walk(sub, &path, leaves, tables);
                }
            }
            _ => {
                leaves.entry(path).or_default().insert(type_name(v));
            }
        }
    }
}

/// Path segments of a documented key path.
fn segments(path: &str) -> Vec<&str> {
    if path.is_empty() {
        Vec::new()
    } else {
        path.split('.').collect()
    }
}

/// The tables at `segs` (through `name[]`: every element, or only the first).
fn tables_mut<'a>(t: &'a mut Table, segs: &[&str], every: bool) -> Vec<&'a mut Table> {
    let Some((head, rest)) = segs.split_first() else {
        return vec![t];
    };
    let (name, array) = match head.strip_suffix("[]") {
        Some(n) => (n, true),
        None => (*head, false),
    };
    match t.get_mut(name) {
        Some(Value::Table(sub)) if !array => tables_mut(sub, rest, every),
        Some(Value::Array(a)) if array => {
            let n = if every { a.len() } else { a.len().min(1) };
            a.iter_mut()
                .take(n)
                .filter_map(Value::as_table_mut)
                .flat_map(|sub| tables_mut(sub, rest, every))
                .collect()
        }
        _ => Vec::new(),
    }
}

/// The values at a documented key path (one per array-of-tables element).
fn values_at<'a>(t: &'a Table, path: &str) -> Vec<Option<&'a Value>> {
    fn go<'a>(t: &'a Table, segs: &[&str], out: &mut Vec<Option<&'a Value>>) {
        let Some((head, rest)) = segs.split_first() else {
            return;
        };
        if rest.is_empty() {
            out.push(t.get(*head));
            return;
        }
        match (head.strip_suffix("[]"), t.get(head.trim_end_matches("[]"))) {
            (None, Some(Value::Table(sub))) => go(sub, rest, out),
            (Some(_), Some(Value::Array(a))) => {
                for sub in a.iter().filter_map(Value::as_table) {
                    go(sub, rest, out);
                }
            }
            _ => out.push(None),
        }
    }
    let mut out = Vec::new();
    go(t, &segments(path), &mut out);
    out
}

/// Field names listed by a `deny_unknown_fields` error for [`PROBE`], if the error is
/// one.
fn probe_fields(err: &str) -> Option<Vec<String>> {
    let rest = &err[err.find(&format!("unknown field `{PROBE}`"))?..];
    let rest = rest.split_once(", expected").map_or("", |(_, r)| r);
    Some(
        rest.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect(),
    )
}

/// Resolves a scenario text: the resolved TOML, or the error message.
type Resolve<'a> = &'a dyn Fn(&str) -> Result<String, String>;

/// One preset to check against its experiment's section.
struct Preset<'a> {
    experiment: String,
    text: String,
    resolve: Resolve<'a>,
}

fn to_text(t: &Table) -> String {
    toml::to_string(t).expect("a parsed TOML table serializes")
}

/// Every problem found between `doc` and the presets (empty = in sync).
fn check_docs(doc: &str, presets: &[Preset<'_>]) -> Vec<String> {
    let sections = match parse_doc(doc) {
        Ok(s) => s,
        Err(e) => return e,
    };
    let mut problems = Vec::new();
    for p in presets {
        let exp = &p.experiment;
        let Some(rows) = sections.get(exp) else {
            problems.push(format!("no section \"## `{exp}`\" for experiment `{exp}`"));
            continue;
        };
        let base: Table = match toml::from_str(&p.text) {
            Ok(t) => t,
            Err(e) => {
                problems.push(format!("{exp}: preset does not parse: {e}"));
                continue;
            }
        };
        let resolved: Table = match (p.resolve)(&p.text).and_then(|r| {
            toml::from_str(&r).map_err(|e| format!("resolved TOML does not parse: {e}"))
        }) {
            Ok(t) => t,
            Err(e) => {
                problems.push(format!("{exp}: preset does not resolve: {e}"));
                continue;
            }
        };

        // The keys of the schema: leaves of the resolved scenario plus the fields every
        // table declares (an optional key may be absent from both preset and resolution).
        let mut leaves = BTreeMap::new();
        let mut tables = BTreeSet::new();
        walk(&resolved, "", &mut leaves, &mut tables);
        let mut keys: BTreeSet<String> = leaves.keys().cloned().collect();
        for table in &tables {
            let mut probed = base.clone();
            let targets = tables_mut(&mut probed, &segments(table), false);
            if targets.is_empty() {
                continue; // a table the preset leaves out (filled in by resolution)
            }
            for t in targets {
                t.insert(PROBE.into(), Value::Integer(0));
            }
            let shown = if table.is_empty() { "top level" } else { table };
            match (p.resolve)(&to_text(&probed)) {
                Ok(_) => problems.push(format!(
                    "{exp}: table `{shown}` accepts the unknown key `{PROBE}` (no deny_unknown_fields?)"
                )),
                Err(e) => match probe_fields(&e) {
                    Some(fields) => {
                        for f in fields {
                            let path = join(table, &f);
                            let nested = tables.contains(&path)
                                || tables.contains(&format!("{path}[]"));
                            if !nested {
                                keys.insert(path);
                            }
                        }
                    }
                    None => problems.push(format!(
                        "{exp}: probing table `{shown}` gave an unexpected error: {e}"
                    )),
                },
            }
        }

        let documented: BTreeMap<&str, &DocRow> =
            rows.iter().map(|r| (r.key.as_str(), r)).collect();
        for key in &keys {
            if !documented.contains_key(key.as_str()) {
                problems.push(format!(
                    "{exp}: key `{key}` is not documented in docs/scenarios.md (section `{exp}`)"
                ));
            }
        }
        for row in rows {
            let key = row.key.as_str();
            if !keys.contains(key) {
                problems.push(format!(
                    "{exp}: line {}: documented key `{key}` does not exist in the schema (stale row)",
                    row.line
                ));
                continue;
            }
            if let Some(types) = leaves.get(key)
                && types.iter().any(|t| *t != row.ty)
            {
                problems.push(format!(
                    "{exp}: line {}: key `{key}` is documented as {} but resolves to {}",
                    row.line,
                    row.ty,
                    types.iter().copied().collect::<Vec<_>>().join(", ")
                ));
            }
            check_default(exp, row, &base, p.resolve, &mut problems);
        }
    }
    problems
}

/// Removes `row.key` from the preset and checks the documented default behaviour.
fn check_default(
    exp: &str,
    row: &DocRow,
    base: &Table,
    resolve: Resolve<'_>,
    problems: &mut Vec<String>,
) {
    let key = row.key.as_str();
    let (parent, leaf) = key.rsplit_once('.').unwrap_or(("", key));
    let mut reduced = base.clone();
    let every = row.default != DocDefault::Required;
    let mut removed = false;
    for t in tables_mut(&mut reduced, &segments(parent), every) {
        removed |= t.remove(leaf).is_some();
    }
    let outcome = resolve(&to_text(&reduced));
    let line = row.line;
    match (&row.default, outcome) {
        (DocDefault::Required, Err(e)) => {
            let names_key = e.contains(&format!("`{leaf}`")) && e.contains("missing");
            let top = parent.split('.').next().unwrap_or(parent);
            let names_table =
                parent.is_empty() || e.contains(&format!("`{}", top.trim_end_matches("[]")));
            if !(names_key && names_table) {
                problems.push(format!(
                    "{exp}: line {line}: without required key `{key}` the check fails, but its error does not name the key: {e}"
                ));
            }
        }
        (DocDefault::Required, Ok(_)) => problems.push(if removed {
            format!(
                "{exp}: line {line}: key `{key}` is documented as required, but the scenario checks without it (document its default)"
            )
        } else {
            format!(
                "{exp}: line {line}: key `{key}` is documented as required, but the preset does not give it"
            )
        }),
        (_, Err(e)) => problems.push(format!(
            "{exp}: line {line}: key `{key}` is documented with a default, but the scenario fails without it: {e}"
        )),
        (default, Ok(text)) => {
            let resolved: Table = match toml::from_str(&text) {
                Ok(t) => t,
                Err(e) => {
                    problems.push(format!("{exp}: resolved TOML does not parse: {e}"));
                    return;
                }
            };
            let expected = match default {
                DocDefault::Value(v) => Some(v),
                _ => None,
            };
            for got in values_at(&resolved, key) {
                if got != expected {
                    let show = |v: Option<&Value>| v.map_or("(absent)".into(), Value::to_string);
                    problems.push(format!(
                        "{exp}: line {line}: key `{key}` is documented with default {}, but resolves to {} when left out",
                        show(expected),
                        show(got)
                    ));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::registry;
    use serde::{Deserialize, Serialize};
    use std::path::{Path, PathBuf};

    fn root() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
    }

    fn doc() -> String {
        std::fs::read_to_string(root().join("docs/scenarios.md")).unwrap()
    }

    fn real_resolve(text: &str) -> Result<String, String> {
        crate::user_run::check_scenario_text(text, "preset.toml", &registry())
            .map(|c| c.resolved_toml)
            .map_err(|e| crate::error_chain(&e))
    }

    /// Every registered experiment's preset, resolved by `fathom check`.
    fn presets() -> Vec<Preset<'static>> {
        registry()
            .iter()
            .map(|e| Preset {
                experiment: e.name().to_string(),
                text: std::fs::read_to_string(root().join(e.default_scenario())).unwrap(),
                resolve: &real_resolve,
            })
            .collect()
    }

    fn only(name: &str) -> Vec<Preset<'static>> {
        presets()
            .into_iter()
            .filter(|p| p.experiment == name)
            .collect()
    }

    #[test]
    fn every_scenario_key_is_documented_with_its_type_and_default() {
        let problems = check_docs(&doc(), &presets());
        assert!(
            problems.is_empty(),
            "docs/scenarios.md is out of sync with the scenario schemas:\n  {}",
            problems.join("\n  ")
        );
        // Every registered experiment has a section, and nothing else does.
        let sections = parse_doc(&doc()).unwrap();
        let names: BTreeSet<String> = registry().iter().map(|e| e.name().to_string()).collect();
        assert_eq!(sections.keys().cloned().collect::<BTreeSet<_>>(), names);
    }

    /// The document with the row of `key` in section `exp` removed.
    fn without_row(doc: &str, exp: &str, key: &str) -> String {
        let row = format!("| `{key}` |");
        let start = doc.find(&format!("## `{exp}`")).unwrap();
        let at = start + doc[start..].find(&row).unwrap();
        let end = at + doc[at..].find('\n').unwrap() + 1;
        format!("{}{}", &doc[..at], &doc[end..])
    }

    #[test]
    fn negative_control_missing_stale_and_wrong_rows_are_reported() {
        let doc = doc();
        let noise = only("noise");
        assert!(check_docs(&doc, &noise).is_empty());

        // A key without a row.
        let p = check_docs(&without_row(&doc, "noise", "noise.corr_gap_s"), &noise);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(
            p[0].contains("key `noise.corr_gap_s` is not documented"),
            "{p:?}"
        );
        // The same key documented only in another experiment's section does not count.
        assert!(without_row(&doc, "noise", "motion.step_s").contains("| `motion.step_s` |"));
        let p = check_docs(&without_row(&doc, "noise", "motion.step_s"), &noise);
        assert!(
            p.len() == 1 && p[0].contains("key `motion.step_s` is not documented"),
            "{p:?}"
        );

        // A stale row.
        let stale = doc.replacen(
            "| `noise.corr_gap_s` |",
            "| `noise.corr_gap_old_s` | float | s | required | > 0 | gone |\n| `noise.corr_gap_s` |",
            1,
        );
        let p = check_docs(&stale, &noise);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(
            p[0].contains("`noise.corr_gap_old_s` does not exist") && p[0].contains("stale"),
            "{p:?}"
        );

        // A default documented for a required key.
        let wrong = doc.replacen(
            "| `noise.range_sigma_m` | float | m | required |",
            "| `noise.range_sigma_m` | float | m | `0.1` |",
            1,
        );
        let p = check_docs(&wrong, &noise);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(
            p[0].contains("`noise.range_sigma_m` is documented with a default")
                && p[0].contains("missing field `range_sigma_m`"),
            "{p:?}"
        );

        // A wrong type.
        let wrong = doc.replacen(
            "| `long_run.max_rel_dev` | float |",
            "| `long_run.max_rel_dev` | integer |",
            1,
        );
        let p = check_docs(&wrong, &noise);
        assert!(
            p.len() == 1 && p[0].contains("documented as integer but resolves to float"),
            "{p:?}"
        );

        // A malformed row is a parse error naming its line.
        let bad = doc.replacen(
            "| `noise.depth_sigma_m` | float | m | required | > 0 |",
            "| `noise.depth_sigma_m` | float | m | required |",
            1,
        );
        let p = check_docs(&bad, &noise);
        assert!(p.len() == 1 && p[0].contains("has 5 cells"), "{p:?}");

        // A missing section.
        let p = check_docs(&doc.replace("## `noise`", "## noise"), &noise);
        assert!(p.len() == 1 && p[0].contains("no section"), "{p:?}");
    }

    // A small schema with defaults exercises the default checks that the real
    // schemas (all keys required today) do not reach.

    fn default_gain() -> f64 {
        1.5
    }

    #[derive(Debug, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Demo {
        experiment: String,
        runs: usize,
        #[serde(default = "default_gain")]
        gain: f64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        note: Option<String>,
        filter: DemoFilter,
        items: Vec<DemoItem>,
    }

    #[derive(Debug, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct DemoFilter {
        #[serde(default)]
        order: u32,
        window_s: f64,
    }

    #[derive(Debug, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct DemoItem {
        name: String,
        #[serde(default)]
        on: bool,
    }

    fn demo_resolve(text: &str) -> Result<String, String> {
        let d: Demo = crate::scenario::parse_toml(text, "demo.toml").map_err(|e| e.to_string())?;
        Ok(toml::to_string(&d).unwrap())
    }

    const DEMO_PRESET: &str = "experiment = \"demo\"\nruns = 3\n\
        [filter]\norder = 2\nwindow_s = 0.5\n[[items]]\nname = \"a\"\non = true\n";

    const DEMO_DOC: &str = "\
## `demo`: a test schema

| key | type | unit | default | range | meaning |
| --- | --- | --- | --- | --- | --- |
| `experiment` | string | - | required | `\"demo\"` | the experiment |
| `runs` | integer | - | required | ≥ 2 | runs |
| `gain` | float | - | `1.5` | > 0 | a gain \\| with a pipe |
| `note` | string | - | unset | - | a note |
| `filter.order` | integer | - | `0` | ≥ 0 | order |
| `filter.window_s` | float | s | required | > 0 | window |
| `items[].name` | string | - | required | - | name |
| `items[].on` | bool | - | `false` | - | switch |
";

    fn demo(doc: &str) -> Vec<String> {
        check_docs(
            doc,
            &[Preset {
                experiment: "demo".into(),
                text: DEMO_PRESET.into(),
                resolve: &demo_resolve,
            }],
        )
    }

    #[test]
    fn defaults_unset_keys_and_open_tables_are_checked() {
        assert_eq!(demo(DEMO_DOC), Vec::<String>::new());

        // The optional `note` is in neither the preset nor the resolution: the probe
        // of the top-level table still finds it.
        let p = demo(&DEMO_DOC.replace("| `note` | string | - | unset | - | a note |\n", ""));
        assert!(
            p.len() == 1 && p[0].contains("key `note` is not documented"),
            "{p:?}"
        );

        // Wrong defaults.
        let p = demo(&DEMO_DOC.replace("| `1.5` |", "| `2.5` |"));
        assert!(
            p.len() == 1 && p[0].contains("default 2.5, but resolves to 1.5"),
            "{p:?}"
        );
        let p = demo(&DEMO_DOC.replace("| `false` |", "| `true` |"));
        assert!(p.len() == 1 && p[0].contains("`items[].on`"), "{p:?}");
        let p = demo(&DEMO_DOC.replace("| `0` |", "| required |"));
        assert!(
            p.len() == 1 && p[0].contains("checks without it (document its default)"),
            "{p:?}"
        );
        let p = demo(&DEMO_DOC.replace("| unset |", "| `\"x\"` |"));
        assert!(
            p.len() == 1 && p[0].contains("resolves to (absent)"),
            "{p:?}"
        );

        // A schema that ignores unknown keys (as without deny_unknown_fields) is
        // reported table by table instead of passing unchecked.
        let lenient = |text: &str| {
            let kept: Vec<&str> = text.lines().filter(|l| !l.contains(PROBE)).collect();
            demo_resolve(&kept.join("\n"))
        };
        let p = check_docs(
            DEMO_DOC,
            &[Preset {
                experiment: "demo".into(),
                text: DEMO_PRESET.into(),
                resolve: &lenient,
            }],
        );
        // ... and the optional `note`, absent from preset and resolution, can then no
        // longer be seen at all: its row looks stale.
        assert_eq!(p.len(), 4, "{p:?}");
        assert!(p[3].contains("`note` does not exist"), "{p:?}");
        for table in ["top level", "filter", "items[]"] {
            let found = p
                .iter()
                .any(|m| m.contains(&format!("table `{table}` accepts the unknown key")));
            assert!(found, "{table}: {p:?}");
        }
    }

    #[test]
    fn parsing_rows_and_cells() {
        assert_eq!(
            split_cells("| `a` | b \\| c | d |"),
            vec!["`a`", "b | c", "d"]
        );
        assert_eq!(parse_default("required"), Ok(DocDefault::Required));
        assert_eq!(
            parse_default("`[1.0, 2.0]`"),
            Ok(DocDefault::Value(Value::Array(vec![
                Value::Float(1.0),
                Value::Float(2.0)
            ])))
        );
        assert!(parse_default("0.5").is_err());
        assert!(parse_default("`0.5 m`").is_err());
        let sections = parse_doc(DEMO_DOC).unwrap();
        assert_eq!(sections["demo"].len(), 8);
        // Rows in comments, code fences and non-experiment sections are ignored.
        let doc = format!(
            "<!--\n| `x` | float |\n-->\n## Units\n| `_s` | seconds |\n```\n| `y` |\n```\n{DEMO_DOC}"
        );
        assert_eq!(parse_doc(&doc).unwrap()["demo"].len(), 8);
        let e = parse_doc("## `demo`\n| runs | integer | - | required | - | x |\n").unwrap_err();
        assert!(e[0].contains("must start with a key in backticks"), "{e:?}");
        assert_eq!(
            values_at(&toml::from_str(DEMO_PRESET).unwrap(), "items[].name"),
            vec![Some(&Value::String("a".into()))]
        );
    }
}
