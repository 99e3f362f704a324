//! The Markdown and console text the driver writes around an experiment's own
//! analysis: the per-experiment `report.md`, the console section, and the collected
//! `REPORT.md` of `cargo xtask paper`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::{ExperimentResult, Setup};
use crate::experiment::Analysis;
use fathom_report::output::{Claim, Row, Summary, md_table, text_table};

/// Significant digits of the numbers in the printed and Markdown tables.
pub const TABLE_DECIMALS: usize = 4;

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// How the numbers of one row are written: the same style for the value, the paper
/// number and both ends of the interval, so they line up.
#[derive(Debug, Clone, Copy)]
enum Style {
    /// Fixed decimals.
    Fixed(usize),
    /// Scientific with 3 decimals (very large or very small magnitudes).
    Scientific,
}

impl Style {
    /// [`TABLE_DECIMALS`] significant digits of `x` in unit `unit`; counts are
    /// integers (a count averaged over runs has one decimal).
    fn of(x: f64, unit: &str) -> Style {
        let whole = x == x.trunc();
        match unit {
            "count" | "count/run" if whole => return Style::Fixed(0),
            "count" | "count/run" => return Style::Fixed(1),
            _ => {}
        }
        let a = x.abs();
        if !a.is_finite() || a == 0.0 {
            return Style::Fixed(0);
        }
        if !(1e-3..1e6).contains(&a) {
            return Style::Scientific;
        }
        let digits = TABLE_DECIMALS as i32 - 1 - a.log10().floor() as i32;
        Style::Fixed(digits.clamp(0, 6) as usize)
    }

    fn fmt(self, x: f64) -> String {
        if !x.is_finite() {
            return format!("{x}");
        }
        match self {
            Style::Fixed(d) => format!("{x:.d$}"),
            Style::Scientific => format!("{x:.3e}"),
        }
    }
}

/// `x` written as in the tables: [`TABLE_DECIMALS`] significant digits, counts
/// (`unit` `count`, `count/run`) as integers or with one decimal.
pub fn fmt_value(x: f64, unit: &str) -> String {
    Style::of(x, unit).fmt(x)
}

/// What kind of job a report is about: one that reproduces a paper (its preset is the
/// paper's setup) or one on the user's own data (its preset is only the built-in
/// settings); a Monte Carlo experiment or a deterministic replay.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Framing {
    /// [`crate::experiment::DynExperiment::paper`].
    pub(crate) paper: bool,
    /// No Monte Carlo runs and no seed.
    pub(crate) deterministic: bool,
}

impl Framing {
    fn of(r: &ExperimentResult) -> Self {
        Framing {
            paper: r.paper,
            deterministic: r.deterministic,
        }
    }
}

/// Whether the results table has the interval column: a paper's job always shows it
/// (and the paper's number); a job on the user's own data shows the value, and the
/// interval only when a row has one.
fn with_ci_column(framing: Framing, rows: &[Row]) -> bool {
    framing.paper || rows.iter().any(|r| r.ci95.is_some())
}

/// Whether the table has the median and diverged-runs columns: some row summarizes
/// runs.
fn with_median_columns(rows: &[Row]) -> bool {
    rows.iter().any(|r| r.median.is_some())
}

/// The cells of one row: method, metric, unit, (paper,) value(, 95 % CI)(, median,
/// diverged runs).
fn row_cells(
    r: &Row,
    units: &BTreeMap<String, String>,
    paper: bool,
    ci: bool,
    median: bool,
) -> Vec<String> {
    let unit = if r.unit.is_empty() {
        units.get(&r.metric).map_or("", String::as_str)
    } else {
        r.unit.as_str()
    };
    let style = Style::of(r.value, unit);
    let mut cells = vec![
        r.method.clone(),
        r.metric.clone(),
        if unit.is_empty() {
            "-".into()
        } else {
            unit.into()
        },
    ];
    if paper {
        cells.push(r.paper.map_or_else(|| "—".into(), |p| style.fmt(p)));
    }
    cells.push(style.fmt(r.value));
    if ci {
        cells.push(r.ci95.map_or_else(
            || "—".into(),
            |[lo, hi]| format!("[{}, {}]", style.fmt(lo), style.fmt(hi)),
        ));
    }
    if median {
        cells.push(r.median.map_or_else(|| "—".into(), |m| style.fmt(m)));
        cells.push(match r.divergence {
            Some(d) if d.runs > 0 => format!("{} (> {})", d.runs, style.fmt(d.threshold)),
            Some(_) => "0".into(),
            None => "—".into(),
        });
    }
    cells
}

/// The legend under a results table: how each interval method in it was computed.
fn interval_legend(rows: &[Row]) -> String {
    let mut methods: Vec<&str> = rows.iter().filter_map(|r| r.ci_method.as_deref()).collect();
    methods.sort_unstable();
    methods.dedup();
    if methods.is_empty() {
        return String::new();
    }
    let explain = |m: &str| -> &'static str {
        match m {
            "bootstrap-bca" => "BCa bootstrap of the mean over runs (non-negative metric)",
            "student-t" => "Student-t interval of the mean (signed metric, paired difference)",
            "student-t-cut-at-0" => "Student-t over more than 20,000 runs, lower end cut at 0",
            "order-statistic" => "order-statistic interval of the median",
            "clopper-pearson" => "exact binomial interval of a proportion",
            _ => "see the experiment's notes",
        }
    };
    let parts: Vec<String> = methods
        .iter()
        .map(|m| format!("`{m}`: {}", explain(m)))
        .collect();
    format!(
        "Intervals: {}. \"diverged\": runs above the divergence threshold (a factor times \
         the median). See docs/reading-the-numbers.md.\n",
        parts.join("; ")
    )
}

/// Every row of `rows` as table cells, with the headers, for `setup` and `framing`.
fn table(
    rows: &[Row],
    units: &BTreeMap<String, String>,
    setup: &Setup,
    framing: Framing,
) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let (paper, ci) = (framing.paper, with_ci_column(framing, rows));
    let median = with_median_columns(rows);
    let cells = rows
        .iter()
        .map(|r| row_cells(r, units, paper, ci, median))
        .collect();
    (headers(setup, paper, ci, median), cells)
}

/// Column headers of the results table for `setup`.
fn headers(setup: &Setup, paper: bool, ci: bool, median: bool) -> Vec<&'static str> {
    let mut h = vec!["method", "metric", "unit"];
    match (paper, setup.is_paper()) {
        (true, true) => h.extend(["paper", "reproduced"]),
        (true, false) => h.extend(["paper's setup", "your scenario"]),
        (false, _) => h.push("value"),
    }
    if ci {
        h.push("95% CI");
    }
    if median {
        h.extend(["median", "diverged"]);
    }
    h
}

fn verdict(c: &Claim, setup: &Setup, framing: Framing) -> &'static str {
    // A claim judged by equivalence says which of the three outcomes it is.
    match c.verdict.as_deref() {
        Some("agrees") => return "agrees",
        Some("differs") => return "differs",
        Some("inconclusive") => return "inconclusive",
        _ => {}
    }
    match (c.holds, setup.is_paper() || !framing.paper) {
        (true, true) => "holds",
        (false, true) => "does not hold",
        (true, false) => "holds here",
        (false, false) => "does not hold here",
    }
}

/// The sentence that says which setup the numbers are for.
fn setup_sentence(s: &Summary, setup: &Setup, framing: Framing) -> String {
    let preset = format!("`scenarios/{}.toml`", s.experiment);
    if !framing.paper {
        return if setup.is_paper() {
            format!("Settings: the built-in ones ({preset}).")
        } else {
            format!(
                "Settings: yours; they differ from the built-in ones ({preset}) in {}.",
                setup.keys_text(usize::MAX)
            )
        };
    }
    if setup.is_paper() {
        format!("Setup: the paper's setup ({preset}).")
    } else {
        format!(
            "Setup: **your scenario**, which differs from the paper's setup ({preset}) in {}. \
             The \"paper's setup\" column is the paper's number for its own setup, shown for \
             reference only: a difference from it is expected and is not a failed \
             reproduction.",
            setup.keys_text(usize::MAX)
        )
    }
}

/// The per-experiment `report.md`.
pub(crate) fn experiment_report(
    s: &Summary,
    scenario_label: &str,
    analysis: &Analysis,
    setup: &Setup,
    framing: Framing,
    figures: &[PathBuf],
) -> String {
    let doc = if framing.paper {
        "Seed paper"
    } else {
        "Documentation"
    };
    let what = if framing.deterministic {
        "one deterministic replay (no Monte Carlo runs, no seed)".to_string()
    } else {
        format!("Monte Carlo runs: {} · base seed: {}", s.runs, s.base_seed)
    };
    let mut md = format!(
        "# {}\n\n{doc}: `{}` · {what} · scenario: `{}`\n\n",
        s.experiment, s.seed_doc, scenario_label,
    );
    md.push_str(&setup_sentence(s, setup, framing));
    md.push_str("\n\n");
    md.push_str(match (framing.paper, setup.is_paper()) {
        (false, _) => "## Results\n\n",
        (true, true) => "## Paper versus reproduced\n\n",
        (true, false) => "## Your scenario\n\n",
    });
    let (head, rows) = table(&s.rows, &analysis.units, setup, framing);
    md.push_str(&md_table(&head, &rows));
    let legend = interval_legend(&s.rows);
    if !legend.is_empty() {
        md.push('\n');
        md.push_str(&legend);
    }
    md.push_str(
        match (framing.paper, setup.is_paper(), s.claims.is_empty()) {
            (false, _, _) => "\n## Checks\n\n",
            (true, true, _) => "\n## Claims\n\n",
            (true, false, true) => {
                "\n## The paper's claims\n\nNot judged: they are about the paper's own setup \
             (`fathom run --paper-extras` judges them on your scenario).\n"
            }
            (true, false, false) => {
                "\n## The paper's claims on your scenario\n\nThe paper's claims are about its own \
             setup; here they are evaluated on your scenario's numbers (`--paper-extras`).\n\n"
            }
        },
    );
    if s.claims.is_empty() {
        if !framing.paper || setup.is_paper() {
            md.push_str("(no claims evaluated)\n");
        }
    } else {
        let rows: Vec<Vec<String>> = s
            .claims
            .iter()
            .map(|c| {
                vec![
                    format!("`{}`: {}", c.id, c.text),
                    verdict(c, setup, framing).to_string(),
                    c.detail.clone(),
                ]
            })
            .collect();
        let first = if framing.paper { "claim" } else { "check" };
        md.push_str(&md_table(&[first, "verdict", "detail"], &rows));
    }
    let section = analysis.report.trim();
    if !section.is_empty() {
        md.push_str("\n## Notes\n\n");
        md.push_str(section);
        md.push('\n');
    }
    md.push_str("\n## Figures\n\n");
    if figures.is_empty() {
        md.push_str("(none)\n");
    }
    for f in figures {
        let n = file_name(f);
        md.push_str(&format!("- [{n}]({n})\n"));
    }
    md
}

/// Every row of `r` as a console table (method, metric, unit, paper, value, 95 % CI),
/// headed for its setup.
pub fn console_rows(r: &ExperimentResult) -> String {
    let (head, rows) = table(&r.summary.rows, &r.units, &r.setup, Framing::of(r));
    text_table(&head, &rows)
}

/// The short console table of `fathom run`: the rows whose metric is one of
/// `metrics` (every row when empty), and a line counting the others, which are in
/// `report.md` and `summary.json`.
pub fn console_main_rows(r: &ExperimentResult, metrics: &[&str]) -> String {
    if metrics.is_empty() {
        return console_rows(r);
    }
    let main: Vec<Row> = r
        .summary
        .rows
        .iter()
        .filter(|row| metrics.contains(&row.metric.as_str()))
        .cloned()
        .collect();
    let (head, rows) = table(&main, &r.units, &r.setup, Framing::of(r));
    let mut t = text_table(&head, &rows);
    let rest = r.summary.rows.len() - main.len();
    if rest > 0 {
        t.push_str(&format!(
            "({rest} more row{} in report.md and summary.json)\n",
            if rest == 1 { "" } else { "s" }
        ));
    }
    t
}

/// The console section of one experiment: run count, seed, time, the setup, every
/// row with its unit and interval, and the claims.
pub fn console_section(r: &ExperimentResult) -> String {
    let s = &r.summary;
    let mut t = if r.deterministic {
        format!(
            "one deterministic replay, {:.1} s\n",
            r.elapsed.as_secs_f64()
        )
    } else {
        format!(
            "{} runs, base seed {}, {:.1} s\n",
            s.runs,
            s.base_seed,
            r.elapsed.as_secs_f64()
        )
    };
    t.push_str(&console_setup(r));
    t.push_str(&console_rows(r));
    t.push_str(&console_claims(r));
    t.push('\n');
    t
}

/// One line: the paper's setup, or the keys in which the scenario differs from it.
pub fn console_setup(r: &ExperimentResult) -> String {
    if !r.paper {
        return if r.setup.is_paper() {
            format!("settings: the built-in ones (scenarios/{}.toml)\n", r.name)
        } else {
            format!(
                "settings: yours, differ from the built-in ones in {}\n",
                r.setup.keys_text(6)
            )
        };
    }
    if r.setup.is_paper() {
        "setup: the paper's (paper | reproduced)\n".into()
    } else {
        format!(
            "setup: your scenario, differs from the paper's in {} (the paper column is the \
             paper's setup, for reference)\n",
            r.setup.keys_text(6)
        )
    }
}

/// The claims, one line each, with their verdict for the setup.
pub fn console_claims(r: &ExperimentResult) -> String {
    let mut t = String::new();
    if !r.summary.claims.is_empty() {
        t.push_str(match (r.paper, r.setup.is_paper()) {
            (false, _) => "checks:\n",
            (true, true) => "claims:\n",
            (true, false) => "the paper's claims on your scenario:\n",
        });
        for c in &r.summary.claims {
            t.push_str(&format!(
                "  [{}] {}: {} ({})\n",
                verdict(c, &r.setup, Framing::of(r)),
                c.id,
                c.text,
                c.detail
            ));
        }
    }
    t
}

/// Demote Markdown headings by one level (outside code fences).
pub(crate) fn demote_headings(md: &str) -> String {
    let mut out = String::new();
    let mut fenced = false;
    for line in md.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        }
        if !fenced && line.starts_with('#') {
            out.push('#');
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// Prefix relative Markdown link targets `](target)` with `prefix/`.
pub(crate) fn rebase_links(md: &str, prefix: &str) -> String {
    let mut out = String::with_capacity(md.len());
    let mut rest = md;
    while let Some(i) = rest.find("](") {
        out.push_str(&rest[..i + 2]);
        rest = &rest[i + 2..];
        let relative = !(rest.starts_with('/')
            || rest.starts_with('#')
            || rest.starts_with("http://")
            || rest.starts_with("https://")
            || rest.starts_with(')'));
        if relative {
            out.push_str(prefix);
            out.push('/');
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_have_four_significant_digits_and_counts_are_integers() {
        assert_eq!(fmt_value(2551.257, "m"), "2551");
        assert_eq!(fmt_value(0.075557, "m"), "0.07556");
        assert_eq!(fmt_value(9.69e-5, "m²"), "9.690e-5");
        assert_eq!(fmt_value(1.5e7, "m"), "1.500e7");
        assert_eq!(fmt_value(123.0, "count"), "123");
        assert_eq!(fmt_value(123.3333, "count/run"), "123.3");
        assert_eq!(fmt_value(0.0, "m"), "0");
        // The interval is written with the value's decimals.
        let row = Row::new("A", "mean", 0.0756).with_ci95(0.07, 0.081, "student-t");
        let units = BTreeMap::from([("mean".to_string(), "m".to_string())]);
        assert_eq!(
            row_cells(&row, &units, true, true, false),
            ["A", "mean", "m", "—", "0.07560", "[0.07000, 0.08100]"]
        );
        // A job on the user's own data: no paper column, the interval only if a row
        // has one.
        let own = Framing {
            paper: false,
            deterministic: true,
        };
        let plain = Row::new("A", "mean", 0.0756);
        let (head, cells) = table(std::slice::from_ref(&plain), &units, &Setup::Paper, own);
        assert_eq!(head, ["method", "metric", "unit", "value"]);
        assert_eq!(cells, [["A", "mean", "m", "0.07560"]]);
        let (head, _) = table(&[plain, row], &units, &Setup::Paper, own);
        assert_eq!(head, ["method", "metric", "unit", "value", "95% CI"]);
    }

    #[test]
    fn markdown_rewriting() {
        assert_eq!(
            demote_headings("# a\n```\n# b\n```\n"),
            "## a\n```\n# b\n```\n"
        );
        assert_eq!(
            rebase_links("[f](f.svg) [w](https://x) [h](#x)", "e"),
            "[f](e/f.svg) [w](https://x) [h](#x)"
        );
    }
}
