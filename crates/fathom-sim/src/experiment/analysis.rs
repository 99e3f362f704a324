//! [`Analysis`]: what an experiment's analysis hands to the driver (rows, claims,
//! extra `summary.json` keys, report text, figures and CSV files).

use std::path::Path;

use crate::SimError;
use fathom_report::output::{
    Claim, CsvCell, Row, check_csv_columns, check_csv_records, stream_csv_columns,
    stream_csv_records,
};
use fathom_report::plot::Figure;

/// One output file, held in memory until the driver writes it.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputFile {
    /// File name inside the output directory (no directory part).
    pub name: String,
    /// File content.
    pub content: FileContent,
}

/// What an output file holds until it is written.
#[derive(Debug, Clone, PartialEq)]
pub enum FileContent {
    /// Finished text (figures, small tables).
    Text(String),
    /// A numeric table, formatted only while it is streamed to disk: a per-run
    /// table of a large campaign is held as numbers (8 bytes a value), not as text.
    Columns {
        /// Column headers.
        headers: Vec<String>,
        /// Equal-length columns (checked when added).
        columns: Vec<Vec<f64>>,
    },
    /// A table of text and number cells, formatted only while it is streamed.
    Records {
        /// Column headers.
        headers: Vec<String>,
        /// Records of one cell per header (checked when added).
        records: Vec<Vec<CsvCell>>,
    },
}

/// One column of a CSV output file as values (what the Python bindings turn into an
/// array without reading the CSV text back).
#[derive(Debug, Clone, PartialEq)]
pub enum ColumnValues {
    /// Every cell is a number (integer cells as `f64`).
    Numbers(Vec<f64>),
    /// Some cell is text: every cell's text as the file shows it (unquoted).
    Text(Vec<String>),
}

impl FileContent {
    /// Streams the content into `w`.
    ///
    /// # Errors
    /// The writer's I/O error.
    pub fn write_to(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        match self {
            Self::Text(text) => w.write_all(text.as_bytes()),
            Self::Columns { headers, columns } => stream_csv_columns(w, headers, columns),
            Self::Records { headers, records } => stream_csv_records(w, headers, records),
        }
    }

    /// The columns of a CSV file, `(header, values)` in file order; `None` for a
    /// text file (a figure).
    pub fn csv_columns(&self) -> Option<Vec<(&str, ColumnValues)>> {
        match self {
            Self::Text(_) => None,
            Self::Columns { headers, columns } => Some(
                headers
                    .iter()
                    .zip(columns)
                    .map(|(h, c)| (h.as_str(), ColumnValues::Numbers(c.clone())))
                    .collect(),
            ),
            Self::Records { headers, records } => Some(
                headers
                    .iter()
                    .enumerate()
                    .map(|(j, h)| {
                        let numbers: Option<Vec<f64>> =
                            records.iter().map(|r| r[j].number()).collect();
                        let values = numbers.map_or_else(
                            || {
                                ColumnValues::Text(
                                    records
                                        .iter()
                                        .map(|r| r[j].to_text().into_owned())
                                        .collect(),
                                )
                            },
                            ColumnValues::Numbers,
                        );
                        (h.as_str(), values)
                    })
                    .collect(),
            ),
        }
    }

    /// The content as text.
    pub fn to_text(&self) -> String {
        match self {
            Self::Text(text) => text.clone(),
            Self::Columns { .. } | Self::Records { .. } => {
                let mut out = Vec::new();
                // Writing into a Vec cannot fail and the cells are UTF-8.
                let _ = self.write_to(&mut out);
                String::from_utf8_lossy(&out).into_owned()
            }
        }
    }
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
    pub(crate) units: std::collections::BTreeMap<String, String>,
    /// Metrics declared signed (their mean's interval is Student-t).
    pub(crate) signed: std::collections::BTreeSet<String>,
    /// How rows summarize runs; `None`: the defaults with seed 0 (unit tests).
    pub(crate) statistics: Option<fathom_stats::SummarySettings>,
    /// A user's variant of the paper's setup, run without the paper's extras
    /// ([`super::Extras`]).
    pub(crate) user_variant: bool,
}

impl Analysis {
    /// An empty analysis.
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether the paper's extras run ([`super::Extras`]): the scenario is the paper's
    /// setup, or the user asked for them. Paper-only report text (errata, the paper's
    /// references) is written only then; claims are dropped by the driver otherwise.
    pub fn paper_extras(&self) -> bool {
        !self.user_variant
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
    /// `"1"` for ratios and fractions). Every row of `summary.json` carries it
    /// (`unit`), and the console and `report.md` tables show it; a row whose metric
    /// has no declared unit is refused.
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

    /// Renders `figure` as the SVG file `name`.
    ///
    /// # Errors
    /// A bad name, or the figure's own errors (empty or non-finite data, ...).
    pub fn figure(&mut self, name: &str, figure: &impl Figure) -> Result<(), SimError> {
        let content = figure.to_svg(Path::new(name))?;
        self.file(name, "svg", FileContent::Text(content))
    }

    /// Adds the self-contained HTML page `name` (the 3D scene page).
    ///
    /// # Errors
    /// A bad name.
    pub fn page(&mut self, name: &str, html: String) -> Result<(), SimError> {
        self.file(name, "html", FileContent::Text(html))
    }

    /// Adds the CSV file `name` from equal-length numeric columns
    /// ([`fathom_report::output::csv_columns_text`]).
    ///
    /// # Errors
    /// A bad name, bad headers or columns of different lengths.
    pub fn csv_columns(
        &mut self,
        name: &str,
        headers: &[&str],
        columns: &[&[f64]],
    ) -> Result<(), SimError> {
        self.csv_owned_columns(name, headers, columns.iter().map(|c| c.to_vec()).collect())
    }

    /// As [`Analysis::csv_columns`], taking the columns by value (no copy of a
    /// large per-run table).
    ///
    /// # Errors
    /// A bad name, bad headers or columns of different lengths.
    pub fn csv_owned_columns(
        &mut self,
        name: &str,
        headers: &[&str],
        columns: Vec<Vec<f64>>,
    ) -> Result<(), SimError> {
        let slices: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
        check_csv_columns(Path::new(name), headers, &slices)?;
        self.file(
            name,
            "csv",
            FileContent::Columns {
                headers: headers.iter().map(|h| (*h).to_owned()).collect(),
                columns,
            },
        )
    }

    /// Adds the CSV file `name` from mixed text/number records
    /// ([`fathom_report::output::csv_records_text`]).
    ///
    /// # Errors
    /// A bad name, bad headers or a record of the wrong length.
    pub fn csv_records(
        &mut self,
        name: &str,
        headers: &[&str],
        records: &[Vec<CsvCell>],
    ) -> Result<(), SimError> {
        check_csv_records(Path::new(name), headers, records)?;
        self.file(
            name,
            "csv",
            FileContent::Records {
                headers: headers.iter().map(|h| (*h).to_owned()).collect(),
                records: records.to_vec(),
            },
        )
    }

    /// The files added so far.
    pub fn files(&self) -> &[OutputFile] {
        &self.files
    }

    fn file(&mut self, name: &str, extension: &str, content: FileContent) -> Result<(), SimError> {
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
        assert_eq!(a.files()[0].content.to_text(), "x_m\n1\n");
    }

    /// The columns handed on as values: numbers stay numbers (integers too), a
    /// column with a text cell is text as the file shows it; figures have none.
    #[test]
    fn csv_columns_as_values() {
        let mut a = Analysis::new();
        a.csv_columns("c.csv", &["t_s", "e_m"], &[&[0.0, 0.5], &[1.0, f64::NAN]])
            .unwrap();
        a.csv_records(
            "r.csv",
            &["name", "run", "v", "gap"],
            &[
                vec!["a,b".into(), 3usize.into(), 0.25.into(), 1.0.into()],
                vec!["c".into(), 4usize.into(), 1e-7.into(), "".into()],
            ],
        )
        .unwrap();
        let c = a.files()[0].content.csv_columns().unwrap();
        assert_eq!(c[0], ("t_s", ColumnValues::Numbers(vec![0.0, 0.5])));
        assert!(matches!(&c[1].1, ColumnValues::Numbers(v) if v[1].is_nan()));
        let r = &a.files()[1].content;
        assert_eq!(
            r.to_text(),
            "name,run,v,gap\n\"a,b\",3,0.25,1\nc,4,0.0000001,\n"
        );
        let r = r.csv_columns().unwrap();
        let names: Vec<&str> = r.iter().map(|c| c.0).collect();
        assert_eq!(names, ["name", "run", "v", "gap"]);
        assert_eq!(r[0].1, ColumnValues::Text(vec!["a,b".into(), "c".into()]));
        assert_eq!(r[1].1, ColumnValues::Numbers(vec![3.0, 4.0]));
        assert_eq!(r[2].1, ColumnValues::Numbers(vec![0.25, 1e-7]));
        assert_eq!(r[3].1, ColumnValues::Text(vec!["1".into(), String::new()]));
        assert!(FileContent::Text("<svg/>".into()).csv_columns().is_none());
    }
}
