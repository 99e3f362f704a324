//! Is a scenario the paper's setup? The resolved scenario is compared key by key
//! with the experiment's resolved preset (`scenarios/<experiment>.toml`, the setup
//! under which the paper's numbers are compared). Keys that choose how much is
//! computed or shown, not what is simulated, are left out: `experiment`, run counts
//! (`runs`, `*_runs`), `base_seed`, the `[figures]` table and the data folder
//! `data.dir` (the same data set can live anywhere).

use crate::experiment::DynExperiment;

/// How a scenario relates to its experiment's paper setup.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum Setup {
    /// The paper's setup (the preset, up to run counts, seeds and figure settings).
    #[default]
    Paper,
    /// A user's variant: the keys (dotted paths) whose values differ from the preset.
    Variant(Vec<String>),
}

impl Setup {
    /// Compares the resolved scenario text `resolved_toml` of `exp` with its preset.
    pub fn of(exp: &dyn DynExperiment, resolved_toml: &str) -> Setup {
        match resolved_toml.parse::<toml::Table>() {
            Ok(mine) => Setup::of_table(exp, &mine),
            Err(_) => Setup::Variant(vec!["(no preset to compare with)".into()]),
        }
    }

    /// Compares the resolved scenario `mine` (an [`Assessed`](crate::experiment::Assessed)
    /// job's table) of `exp` with its preset.
    pub fn of_table(exp: &dyn DynExperiment, mine: &toml::Table) -> Setup {
        let Some(preset) = exp.preset_table() else {
            // An experiment without a usable preset has no paper setup to compare with.
            return Setup::Variant(vec!["(no preset to compare with)".into()]);
        };
        Setup::between(&preset, mine)
    }

    /// Compares the resolved scenario `mine` with the resolved `preset`.
    pub fn between(preset: &toml::Table, mine: &toml::Table) -> Setup {
        let mut differs = Vec::new();
        diff_tables(preset, mine, "", &ignored, &mut differs);
        if differs.is_empty() {
            Setup::Paper
        } else {
            Setup::Variant(differs)
        }
    }

    /// Whether this is the paper's setup.
    pub fn is_paper(&self) -> bool {
        matches!(self, Setup::Paper)
    }

    /// "`a.b`, `c`" (at most `max` keys, then "and N more").
    pub fn keys_text(&self, max: usize) -> String {
        let Setup::Variant(keys) = self else {
            return String::new();
        };
        let mut shown: Vec<String> = keys.iter().take(max).map(|k| format!("`{k}`")).collect();
        if keys.len() > max {
            shown.push(format!("{} more", keys.len() - max));
        }
        shown.join(", ")
    }
}

/// Keys left out of the comparison.
fn ignored(path: &str, key: &str) -> bool {
    matches!(path, "experiment" | "base_seed" | "data.dir")
        || key == "runs"
        || key.ends_with("_runs")
        || path == "figures"
        || path.starts_with("figures.")
}

/// The keys (dotted paths, array items with their index) whose values differ between
/// two resolved scenarios, every key compared (e.g. two shards of one campaign).
pub fn differing_keys(a: &toml::Table, b: &toml::Table) -> Vec<String> {
    let mut out = Vec::new();
    diff_tables(a, b, "", &|_, _| false, &mut out);
    out
}

fn diff_tables(
    a: &toml::Table,
    b: &toml::Table,
    prefix: &str,
    skip: &dyn Fn(&str, &str) -> bool,
    out: &mut Vec<String>,
) {
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    for k in keys {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        if skip(&path, k) {
            continue;
        }
        match (a.get(k), b.get(k)) {
            (Some(toml::Value::Table(x)), Some(toml::Value::Table(y))) => {
                diff_tables(x, y, &path, skip, out);
            }
            (Some(toml::Value::Array(x)), Some(toml::Value::Array(y)))
                if x.len() == y.len()
                    && x.iter().chain(y).all(toml::Value::is_table)
                    && !x.is_empty() =>
            {
                for (i, (p, q)) in x.iter().zip(y).enumerate() {
                    if let (toml::Value::Table(p), toml::Value::Table(q)) = (p, q) {
                        diff_tables(p, q, &format!("{path}[{i}]"), skip, out);
                    }
                }
            }
            (x, y) if x != y => out.push(path),
            _ => {}
        }
    }
}
