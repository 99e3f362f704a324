//! [`Analysis`]: what an experiment's analysis hands to the driver (rows, claims,
//! extra `summary.json` keys, report text, figures and CSV files).

use std::path::Path;

use crate::SimError;
use crate::output::{Claim, CsvCell, Row, csv_columns_text, csv_records_text};
use crate::plot::Figure;

/// One output file, held in memory until the driver writes it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputFile {
    /// File name inside the output directory (no directory part).
    pub name: String,
    /// File content.
    pub content: String,
}

/// The file names the driver writes itself.
pub const RESERVED_FILE_NAMES: [&str; 5] = [
    "summary.json",
    "report.md",
    "scenario.toml",
    "scenario.resolved.toml",
    "run_info.json",
];

/// Collects an experiment's results; the driver turns it into `summary.json`,
/// `report.md` and the figure and CSV files.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Analysis {
    pub(crate) rows: Vec<Row>,
    pub(crate) claims: Vec<Claim>,
    pub(crate) extra: serde_json::Map<String, serde_json::Value>,
    pub(crate) report: String,
    pub(crate) files: Vec<OutputFile>,
    pub(crate) skipped: Option<String>,
    pub(crate) units: std::collections::BTreeMap<String, String>,
}

impl Analysis {
    /// An empty analysis.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends a row of `summary.json`.
    pub fn row(&mut self, row: Row) {
        self.rows.push(row);
    }

    /// Appends a claim.
    pub fn claim(&mut self, claim: Claim) {
        self.claims.push(claim);
    }

    /// Declares the unit of every row with metric `metric` (`"m"`, `"m/s"`, `"%"`,
    /// `"m²"`; `"count"` for counts, `"count/run"` for a count averaged over runs,
    /// `"1"` for ratios and fractions). The console and `report.md` tables show it;
    /// `summary.json` does not carry it (its rows keep the contract's shape).
    pub fn unit(&mut self, metric: impl Into<String>, unit: impl Into<String>) {
        self.units.insert(metric.into(), unit.into());
    }

    /// The declared unit of `metric`, if any.
    pub fn unit_of(&self, metric: &str) -> Option<&str> {
        self.units.get(metric).map(String::as_str)
    }

    /// Adds an extra `summary.json` key.
    pub fn extra(&mut self, key: impl Into<String>, value: serde_json::Value) {
        self.extra.insert(key.into(), value);
    }

    /// The rows so far (for claims computed from rows).
    pub fn rows(&self) -> &[Row] {
        &self.rows
    }

    /// The row of `method` / `metric`, if pushed.
    pub fn find_row(&self, method: &str, metric: &str) -> Option<&Row> {
        self.rows
            .iter()
            .find(|r| r.method == method && r.metric == metric)
    }

    /// Appends Markdown to the report's notes section (use `###` or deeper headings;
    /// the generated sections use `##`).
    pub fn report(&mut self, markdown: &str) {
        self.report.push_str(markdown);
    }

    /// Marks the experiment as skipped (e.g. its data folder is absent), with the
    /// reason; the driver prints it and the report says so.
    pub fn skip(&mut self, reason: impl Into<String>) {
        self.skipped = Some(reason.into());
    }

    /// Renders `figure` as the SVG file `name`.
    ///
    /// # Errors
    /// A bad name, or the figure's own errors (empty or non-finite data, ...).
    pub fn figure(&mut self, name: &str, figure: &impl Figure) -> Result<(), SimError> {
        let content = figure.to_svg(Path::new(name))?;
        self.file(name, "svg", content)
    }

    /// Adds the CSV file `name` from equal-length numeric columns
    /// ([`crate::output::csv_columns_text`]).
    ///
    /// # Errors
    /// A bad name, bad headers or columns of different lengths.
    pub fn csv_columns(
        &mut self,
        name: &str,
        headers: &[&str],
        columns: &[&[f64]],
    ) -> Result<(), SimError> {
        let content = csv_columns_text(Path::new(name), headers, columns)?;
        self.file(name, "csv", content)
    }

    /// Adds the CSV file `name` from mixed text/number records
    /// ([`crate::output::csv_records_text`]).
    ///
    /// # Errors
    /// A bad name, bad headers or a record of the wrong length.
    pub fn csv_records(
        &mut self,
        name: &str,
        headers: &[&str],
        records: &[Vec<CsvCell>],
    ) -> Result<(), SimError> {
        let content = csv_records_text(Path::new(name), headers, records)?;
        self.file(name, "csv", content)
    }

    /// The files added so far.
    pub fn files(&self) -> &[OutputFile] {
        &self.files
    }

    fn file(&mut self, name: &str, extension: &str, content: String) -> Result<(), SimError> {
        let bad = |reason: String| SimError::Output {
            path: name.into(),
            reason,
        };
        let stem_ok = name
            .strip_suffix(&format!(".{extension}"))
            .is_some_and(|stem| {
                !stem.is_empty()
                    && stem
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
            });
        if !stem_ok {
            return Err(bad(format!(
                "output file names are [A-Za-z0-9_.-]+ ending in .{extension}"
            )));
        }
        if RESERVED_FILE_NAMES.contains(&name) {
            return Err(bad("the driver writes this file itself".into()));
        }
        if self.files.iter().any(|f| f.name == name) {
            return Err(bad("written twice".into()));
        }
        self.files.push(OutputFile {
            name: name.to_string(),
            content,
        });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_names_are_checked() {
        let mut a = Analysis::new();
        a.csv_columns("a.csv", &["x_m"], &[&[1.0]]).unwrap();
        assert!(a.csv_columns("a.csv", &["x_m"], &[&[1.0]]).is_err());
        assert!(a.csv_columns("../b.csv", &["x_m"], &[&[1.0]]).is_err());
        assert!(a.csv_columns("b.svg", &["x_m"], &[&[1.0]]).is_err());
        assert!(a.csv_columns("summary.json", &["x_m"], &[&[1.0]]).is_err());
        assert_eq!(a.files().len(), 1);
        assert_eq!(a.files()[0].content, "x_m\n1\n");
    }
}
