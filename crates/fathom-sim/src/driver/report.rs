//! The Markdown and console text the driver writes around an experiment's own
//! analysis: the per-experiment `report.md`, the console section, and the collected
//! `REPORT.md` of `cargo xtask paper`.

use std::path::{Path, PathBuf};

use super::ExperimentResult;
use crate::experiment::Analysis;
use crate::output::{
    Summary, claims_md_table, fmt_ci, fmt_num, fmt_opt, holds_word, summary_md_table, text_table,
};

/// Decimals used for numbers in the printed and Markdown tables.
pub const TABLE_DECIMALS: usize = 4;

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The per-experiment `report.md`.
pub(crate) fn experiment_report(
    s: &Summary,
    scenario_label: &str,
    analysis: &Analysis,
    figures: &[PathBuf],
) -> String {
    let mut md = format!(
        "# {}\n\nSeed paper: `{}` · Monte Carlo runs: {} · base seed: {} · scenario: `{}`\n\n",
        s.experiment, s.seed_doc, s.runs, s.base_seed, scenario_label,
    );
    if let Some(reason) = &analysis.skipped {
        md.push_str(&format!("**Skipped:** {reason}\n\n"));
    }
    md.push_str("## Paper versus reproduced\n\n");
    md.push_str(&summary_md_table(s, TABLE_DECIMALS));
    md.push_str("\n## Claims\n\n");
    if s.claims.is_empty() {
        md.push_str("(no claims evaluated)\n");
    } else {
        md.push_str(&claims_md_table(s));
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

/// The console section of one experiment: run count, seed, time, the table of rows
/// and the claims.
pub fn console_section(r: &ExperimentResult) -> String {
    let s = &r.summary;
    let mut t = format!(
        "{} runs, base seed {}, {:.1} s\n",
        s.runs,
        s.base_seed,
        r.elapsed.as_secs_f64()
    );
    if let Some(reason) = &r.skipped {
        t.push_str(&format!("skipped: {reason}\n"));
    }
    let rows: Vec<Vec<String>> = s
        .rows
        .iter()
        .map(|row| {
            vec![
                row.method.clone(),
                row.metric.clone(),
                fmt_opt(row.paper, TABLE_DECIMALS),
                fmt_num(row.value, TABLE_DECIMALS),
                fmt_ci(row.ci95, TABLE_DECIMALS),
            ]
        })
        .collect();
    t.push_str(&text_table(
        &["method", "metric", "paper", "reproduced", "95% CI"],
        &rows,
    ));
    if !s.claims.is_empty() {
        t.push_str("claims:\n");
        for c in &s.claims {
            t.push_str(&format!(
                "  [{}] {}: {} ({})\n",
                holds_word(c.holds),
                c.id,
                c.text,
                c.detail
            ));
        }
    }
    t.push('\n');
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
