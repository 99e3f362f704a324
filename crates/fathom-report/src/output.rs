//! Output files of an experiment: the `summary.json` contract types, CSV series and
//! Markdown tables.
//!
//! # `summary.json`
//! [`Summary`] serializes with the field order of the output contract
//! (`experiment, seed_doc, runs, base_seed, rows, claims`, then any extra keys in
//! alphabetical order). JSON has no NaN or infinity (serde_json would silently write
//! `null`), so [`Summary::check`] / [`write_summary_json`] **refuse** non-finite numbers
//! with [`ReportError::NonFinite`] naming the row; `paper` and `ci95` may be `null`
//! (absent) but never NaN. A diverging method should be reported with a finite value
//! and a claim, not with NaN.
//!
//! # CSV
//! Plain comma-separated text, one header row whose column names carry the unit
//! (`time_s,err_3d_m`), `\n` line ends, floats written with Rust's shortest round-trip
//! formatting (`{}`: `0.1`, `0.0000001`, `NaN`, `inf`; never exponent notation), which is deterministic and exact.
//! Every CSV goes through [`CsvWriter`] (`csv::Writer`, RFC 4180 quoting of text cells).

use std::borrow::Cow;
use std::fmt::Write as _;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::ReportError;
pub use crate::csv_writer::{CsvWriter, csv_float, csv_string};

/// One compared quantity: a method's metric, the paper's number and the reproduced one.
///
/// Fields in `summary.json` order: `method`, `metric`, `unit`, `paper`, `value`,
/// `ci95`, then, for a value over Monte Carlo runs, `ci_method` (how `ci95` was
/// computed), `median` and `median_ci95` (order-statistic interval), and `divergence`
/// (the runs beyond a threshold). See docs/reading-the-numbers.md.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Method or case name (e.g. `MF`, `SC/high`, `corr_low`).
    pub method: String,
    /// Metric name (e.g. `mean_3d`, `cov_12`).
    pub metric: String,
    /// Unit of `value` (`m`, `m/s`, `deg`, `s`, `1` for a ratio or a count per run);
    /// set by the driver from the experiment's declaration, never empty when written.
    #[serde(default)]
    pub unit: String,
    /// The number printed in the paper, `None` (JSON `null`) where the paper gives none.
    pub paper: Option<f64>,
    /// The value measured by this project (never copied from the paper).
    pub value: f64,
    /// 95 % confidence interval over Monte Carlo runs; `None` only for single
    /// deterministic quantities.
    pub ci95: Option<[f64; 2]>,
    /// How `ci95` was computed (`bootstrap-bca`, `student-t`, `clopper-pearson`, ...);
    /// present whenever `ci95` is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ci_method: Option<String>,
    /// Median over runs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub median: Option<f64>,
    /// Order-statistic interval of the median (at least 95 %).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub median_ci95: Option<[f64; 2]>,
    /// The runs beyond the divergence threshold of this metric.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub divergence: Option<RowDivergence>,
}

/// The runs of a row beyond its divergence threshold ("2 of 50 runs diverged").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RowDivergence {
    /// The threshold, in the row's unit (a factor times the median).
    pub threshold: f64,
    /// Runs whose value exceeds it.
    pub runs: usize,
    /// `runs` over the number of runs.
    pub fraction: f64,
}

impl Row {
    /// A row with no paper number and no confidence interval (its unit is set by the
    /// driver from the experiment's declaration).
    pub fn new(method: impl Into<String>, metric: impl Into<String>, value: f64) -> Self {
        Row {
            method: method.into(),
            metric: metric.into(),
            unit: String::new(),
            paper: None,
            value,
            ci95: None,
            ci_method: None,
            median: None,
            median_ci95: None,
            divergence: None,
        }
    }

    /// Set the paper's number (`None` leaves it absent).
    pub fn with_paper(mut self, paper: impl Into<Option<f64>>) -> Self {
        self.paper = paper.into();
        self
    }

    /// Set the 95 % confidence interval `[lo, hi]` and the name of the method that
    /// computed it.
    pub fn with_ci95(mut self, lo: f64, hi: f64, method: &str) -> Self {
        self.ci95 = Some([lo, hi]);
        self.ci_method = Some(method.to_owned());
        self
    }

    /// Set the unit.
    pub fn with_unit(mut self, unit: impl Into<String>) -> Self {
        self.unit = unit.into();
        self
    }

    /// Check that every number is finite, intervals are ordered, an interval names its
    /// method, and the unit is set.
    ///
    /// # Errors
    /// [`ReportError::NonFinite`] or [`ReportError::InvalidArgument`] naming the row.
    pub fn check(&self) -> Result<(), ReportError> {
        let name = format!("summary row `{}` / `{}`", self.method, self.metric);
        finite(&name, "value", self.value)?;
        if let Some(p) = self.paper {
            finite(&name, "paper", p)?;
        }
        if self.unit.is_empty() {
            return Err(ReportError::invalid_argument(
                name,
                "no unit (the experiment declares the unit of every metric)",
            ));
        }
        for (field, interval) in [("ci95", self.ci95), ("median_ci95", self.median_ci95)] {
            if let Some([lo, hi]) = interval {
                finite(&name, &format!("{field}[0]"), lo)?;
                finite(&name, &format!("{field}[1]"), hi)?;
                if lo > hi {
                    return Err(ReportError::invalid_argument(
                        name,
                        format!("{field} lower bound {lo} exceeds upper bound {hi}"),
                    ));
                }
            }
        }
        if self.ci95.is_some() && self.ci_method.as_deref().is_none_or(str::is_empty) {
            return Err(ReportError::invalid_argument(
                name,
                "ci95 without ci_method (every interval names its method)",
            ));
        }
        if let Some(m) = self.median {
            finite(&name, "median", m)?;
        }
        if let Some(d) = self.divergence {
            finite(&name, "divergence.threshold", d.threshold)?;
            if !(0.0..=1.0).contains(&d.fraction) {
                return Err(ReportError::invalid_argument(
                    name,
                    format!("divergence fraction {} outside [0, 1]", d.fraction),
                ));
            }
        }
        Ok(())
    }
}

fn finite(name: &str, field: &str, v: f64) -> Result<(), ReportError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(ReportError::NonFinite {
            what: format!("{name}: {field}"),
            value: v,
        })
    }
}

/// A claim of the paper, evaluated on the reproduced numbers.
///
/// A claim that compares a reproduced interval with a paper's number carries the
/// equivalence `verdict` (`agrees`, `differs` or `inconclusive`) and the tolerance
/// `band`; its `holds` is true only for `agrees` ([`Summary::check`] refuses
/// anything else).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Claim {
    /// Stable identifier (e.g. `eff_best_3d_mean`).
    pub id: String,
    /// The claim in words.
    pub text: String,
    /// Whether the reproduced numbers support it.
    pub holds: bool,
    /// The numbers behind the verdict (e.g. "EFF 1.12 < T2T 1.80 < MF 2.31").
    pub detail: String,
    /// The equivalence verdict against a paper's value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verdict: Option<String>,
    /// The tolerance band `[paper - tol, paper + tol]` of the verdict.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band: Option<[f64; 2]>,
}

/// The verdicts a claim may carry.
pub const VERDICTS: [&str; 3] = ["agrees", "differs", "inconclusive"];

impl Claim {
    /// Build a claim.
    pub fn new(
        id: impl Into<String>,
        text: impl Into<String>,
        holds: bool,
        detail: impl Into<String>,
    ) -> Self {
        Claim {
            id: id.into(),
            text: text.into(),
            holds,
            detail: detail.into(),
            verdict: None,
            band: None,
        }
    }

    /// Build a claim judged by equivalence: `verdict` is one of [`VERDICTS`], `band`
    /// the tolerance band; `holds` is `verdict == "agrees"`.
    pub fn equivalence(
        id: impl Into<String>,
        text: impl Into<String>,
        verdict: &str,
        band: [f64; 2],
        detail: impl Into<String>,
    ) -> Self {
        Claim {
            verdict: Some(verdict.to_owned()),
            band: Some(band),
            ..Claim::new(id, text, verdict == "agrees", detail)
        }
    }

    /// Check the verdict: a known word, a finite ordered band, and `holds` only for
    /// `agrees`.
    ///
    /// # Errors
    /// [`ReportError::InvalidArgument`] naming the claim.
    pub fn check(&self) -> Result<(), ReportError> {
        let name = format!("claim `{}`", self.id);
        if let Some(v) = &self.verdict {
            if !VERDICTS.contains(&v.as_str()) {
                return Err(ReportError::invalid_argument(
                    name,
                    format!("verdict `{v}` is none of agrees, differs, inconclusive"),
                ));
            }
            if self.holds != (v == "agrees") {
                return Err(ReportError::invalid_argument(
                    name,
                    format!("holds = {} with verdict `{v}`", self.holds),
                ));
            }
            let Some([lo, hi]) = self.band else {
                return Err(ReportError::invalid_argument(
                    name,
                    "a verdict without its band",
                ));
            };
            finite(&name, "band[0]", lo)?;
            finite(&name, "band[1]", hi)?;
        }
        Ok(())
    }
}

/// The content of `target/paper/<experiment>/summary.json` (see the spec README).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Experiment name (`fusion`, `noise`, ...); equals the directory name.
    pub experiment: String,
    /// The seed paper's file name (e.g. `000_777a2c84247a6c44.txt`).
    pub seed_doc: String,
    /// Number of Monte Carlo runs behind the values.
    pub runs: usize,
    /// Base seed of the runs (see `fathom_sim::montecarlo`).
    pub base_seed: u64,
    /// The compared quantities.
    pub rows: Vec<Row>,
    /// The evaluated claims.
    pub claims: Vec<Claim>,
    /// Extra keys (written after the contract keys, sorted by name).
    #[serde(flatten)]
    pub extra: serde_json::Map<String, serde_json::Value>,
}

impl Summary {
    /// An empty summary (no rows, no claims, no extra keys).
    pub fn new(
        experiment: impl Into<String>,
        seed_doc: impl Into<String>,
        runs: usize,
        base_seed: u64,
    ) -> Self {
        Summary {
            experiment: experiment.into(),
            seed_doc: seed_doc.into(),
            runs,
            base_seed,
            rows: Vec::new(),
            claims: Vec::new(),
            extra: serde_json::Map::new(),
        }
    }

    /// Append a row.
    pub fn push_row(&mut self, row: Row) -> &mut Self {
        self.rows.push(row);
        self
    }

    /// Append a claim.
    pub fn push_claim(&mut self, claim: Claim) -> &mut Self {
        self.claims.push(claim);
        self
    }

    /// Find the row of `method` / `metric`.
    pub fn row(&self, method: &str, metric: &str) -> Option<&Row> {
        self.rows
            .iter()
            .find(|r| r.method == method && r.metric == metric)
    }

    /// Check every row (finite numbers, ordered CI) and that claim ids are unique.
    ///
    /// # Errors
    /// The first offending row or duplicate claim id.
    pub fn check(&self) -> Result<(), ReportError> {
        for r in &self.rows {
            r.check()?;
        }
        for (i, c) in self.claims.iter().enumerate() {
            c.check()?;
            if self.claims[..i].iter().any(|d| d.id == c.id) {
                return Err(ReportError::invalid_argument(
                    format!("summary `{}` claims", self.experiment),
                    format!("duplicate claim id `{}`", c.id),
                ));
            }
        }
        Ok(())
    }

    /// Pretty JSON text (2-space indent, trailing newline) after [`Summary::check`].
    ///
    /// # Errors
    /// As [`Summary::check`].
    pub fn to_json_pretty(&self) -> Result<String, ReportError> {
        self.check()?;
        let mut s = serde_json::to_string_pretty(self).map_err(|e| ReportError::Json {
            path: "<summary>".into(),
            source: e,
        })?;
        s.push('\n');
        Ok(s)
    }
}

/// Write `summary` as pretty JSON to `path` (parent directories are created).
///
/// # Errors
/// Non-finite numbers ([`ReportError::NonFinite`]), I/O errors.
pub fn write_summary_json(path: impl AsRef<Path>, summary: &Summary) -> Result<(), ReportError> {
    let path = path.as_ref();
    let text = summary.to_json_pretty()?;
    write_text(path, &text)
}

/// Read a `summary.json` back.
///
/// # Errors
/// I/O errors, [`ReportError::Json`] if it does not match the contract.
pub fn read_summary_json(path: impl AsRef<Path>) -> Result<Summary, ReportError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| ReportError::io("read", path, e))?;
    serde_json::from_str(&text).map_err(|e| ReportError::Json {
        path: path.to_path_buf(),
        source: e,
    })
}

/// Write `text` to `path`, creating parent directories.
///
/// # Errors
/// [`ReportError::Io`] naming the path.
pub fn write_text(path: impl AsRef<Path>, text: &str) -> Result<(), ReportError> {
    let path = path.as_ref();
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .map_err(|e| ReportError::io("create directory", parent, e))?;
    }
    std::fs::write(path, text).map_err(|e| ReportError::io("write", path, e))
}

/// Creates `path` (and its parent folders) and streams its content through a
/// buffered writer.
///
/// # Errors
/// [`ReportError::Io`] naming the path.
pub fn write_with(
    path: impl AsRef<Path>,
    body: impl FnOnce(&mut dyn std::io::Write) -> std::io::Result<()>,
) -> Result<(), ReportError> {
    use std::io::Write as _;
    let path = path.as_ref();
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .map_err(|e| ReportError::io("create directory", parent, e))?;
    }
    let file = std::fs::File::create(path).map_err(|e| ReportError::io("write", path, e))?;
    let mut w = std::io::BufWriter::new(file);
    body(&mut w)
        .and_then(|()| w.flush())
        .map_err(|e| ReportError::io("write", path, e))
}

fn check_headers(path: &Path, headers: &[&str]) -> Result<(), ReportError> {
    if headers.is_empty() {
        return Err(ReportError::Output {
            path: path.to_path_buf(),
            reason: "no columns".into(),
        });
    }
    for (i, h) in headers.iter().enumerate() {
        if h.is_empty() || h.contains([',', '"', '\n', '\r']) {
            return Err(ReportError::Output {
                path: path.to_path_buf(),
                reason: format!("header {i} `{h}` is empty or contains a comma, quote or newline"),
            });
        }
        if headers[..i].contains(h) {
            return Err(ReportError::Output {
                path: path.to_path_buf(),
                reason: format!("duplicate header `{h}`"),
            });
        }
    }
    Ok(())
}

/// Checks CSV headers and equal-length numeric columns (labelled with `path`).
///
/// # Errors
/// [`ReportError::Output`] if headers are bad or the number of columns or their
/// lengths differ.
pub fn check_csv_columns(
    path: &Path,
    headers: &[&str],
    columns: &[&[f64]],
) -> Result<(), ReportError> {
    check_headers(path, headers)?;
    if columns.len() != headers.len() {
        return Err(ReportError::Output {
            path: path.to_path_buf(),
            reason: format!("{} headers but {} columns", headers.len(), columns.len()),
        });
    }
    let n = columns[0].len();
    for (h, c) in headers.iter().zip(columns) {
        if c.len() != n {
            return Err(ReportError::Output {
                path: path.to_path_buf(),
                reason: format!(
                    "column `{h}` has {} values, column `{}` has {n}",
                    c.len(),
                    headers[0]
                ),
            });
        }
    }
    Ok(())
}

/// Streams checked columns as CSV text into `w` (the bytes of [`csv_columns_text`]),
/// one line at a time, so a large table is never held as text.
///
/// # Errors
/// The writer's I/O error.
pub fn stream_csv_columns<S: AsRef<str>>(
    w: &mut (impl std::io::Write + ?Sized),
    headers: &[S],
    columns: &[impl AsRef<[f64]>],
) -> std::io::Result<()> {
    let mut out = CsvWriter::new(w);
    out.record(headers)?;
    let n = columns.first().map_or(0, |c| c.as_ref().len());
    for i in 0..n {
        for c in columns {
            out.float(c.as_ref()[i])?;
        }
        out.end_record()?;
    }
    out.finish().map(drop)
}

/// Build CSV text from equal-length numeric columns (e.g. `time_s`, `err_3d_m`).
///
/// # Errors
/// [`ReportError::Output`] (labelled with `path`) if headers are bad or the number of
/// columns or their lengths differ.
pub fn csv_columns_text(
    path: &Path,
    headers: &[&str],
    columns: &[&[f64]],
) -> Result<String, ReportError> {
    check_csv_columns(path, headers, columns)?;
    let mut out = Vec::new();
    stream_csv_columns(&mut out, headers, columns)
        .map_err(|e| ReportError::io("format", path, e))?;
    String::from_utf8(out).map_err(|e| ReportError::Output {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}

/// Write equal-length numeric columns as CSV (see [`csv_columns_text`]).
///
/// # Errors
/// Bad headers / ragged columns ([`ReportError::Output`]), I/O errors.
pub fn write_csv_columns(
    path: impl AsRef<Path>,
    headers: &[&str],
    columns: &[&[f64]],
) -> Result<(), ReportError> {
    let path = path.as_ref();
    let text = csv_columns_text(path, headers, columns)?;
    write_text(path, &text)
}

/// One CSV cell: text (quoted when needed) or a number (shortest round-trip).
#[derive(Debug, Clone, PartialEq)]
pub enum CsvCell {
    /// A text cell (method name, case, ...).
    Text(String),
    /// A numeric cell.
    Num(f64),
    /// An integer cell (counts, run index).
    Int(i64),
}

impl From<f64> for CsvCell {
    fn from(v: f64) -> Self {
        CsvCell::Num(v)
    }
}
impl From<&str> for CsvCell {
    fn from(v: &str) -> Self {
        CsvCell::Text(v.to_string())
    }
}
impl From<String> for CsvCell {
    fn from(v: String) -> Self {
        CsvCell::Text(v)
    }
}
impl From<usize> for CsvCell {
    fn from(v: usize) -> Self {
        CsvCell::Int(i64::try_from(v).unwrap_or(i64::MAX))
    }
}
impl From<i64> for CsvCell {
    fn from(v: i64) -> Self {
        CsvCell::Int(v)
    }
}

impl CsvCell {
    /// The cell's text before quoting: a number in the [`csv_float`] format, an
    /// integer in decimal, a text cell as it is.
    pub fn to_text(&self) -> Cow<'_, str> {
        match self {
            CsvCell::Num(v) => Cow::Owned(csv_float(*v)),
            CsvCell::Int(v) => Cow::Owned(v.to_string()),
            CsvCell::Text(s) => Cow::Borrowed(s),
        }
    }

    /// The cell as a number: `Num` and `Int` cells (an integer beyond 2^53 rounded to
    /// the nearest `f64`), `None` for text.
    pub fn number(&self) -> Option<f64> {
        match self {
            CsvCell::Num(v) => Some(*v),
            CsvCell::Int(v) => Some(*v as f64),
            CsvCell::Text(_) => None,
        }
    }
}

/// Build CSV text from mixed text/number records (RFC 4180 quoting for text cells);
/// `path` labels errors.
///
/// # Errors
/// Bad headers or a record whose length differs from the header ([`ReportError::Output`]).
pub fn csv_records_text(
    path: &Path,
    headers: &[&str],
    records: &[Vec<CsvCell>],
) -> Result<String, ReportError> {
    check_csv_records(path, headers, records)?;
    let mut out = Vec::new();
    stream_csv_records(&mut out, headers, records)
        .map_err(|e| ReportError::io("format", path, e))?;
    String::from_utf8(out).map_err(|e| ReportError::Output {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}

/// Checks CSV headers and that every record has one cell per header (labelled with
/// `path`).
///
/// # Errors
/// [`ReportError::Output`] naming the bad header or the first record of the wrong
/// length.
pub fn check_csv_records(
    path: &Path,
    headers: &[&str],
    records: &[Vec<CsvCell>],
) -> Result<(), ReportError> {
    check_headers(path, headers)?;
    for (i, r) in records.iter().enumerate() {
        if r.len() != headers.len() {
            return Err(ReportError::Output {
                path: path.to_path_buf(),
                reason: format!(
                    "record {i} has {} cells, header has {}",
                    r.len(),
                    headers.len()
                ),
            });
        }
    }
    Ok(())
}

/// Streams checked records as CSV text into `w` (the bytes of [`csv_records_text`]).
///
/// # Errors
/// The writer's I/O error.
pub fn stream_csv_records<S: AsRef<str>>(
    w: &mut (impl std::io::Write + ?Sized),
    headers: &[S],
    records: &[Vec<CsvCell>],
) -> std::io::Result<()> {
    let mut out = CsvWriter::new(w);
    out.record(headers)?;
    for r in records {
        out.record(r.iter().map(CsvCell::to_text))?;
    }
    out.finish().map(drop)
}

/// Write mixed text/number records as CSV (see [`csv_records_text`]).
///
/// # Errors
/// As [`csv_records_text`], then I/O errors.
pub fn write_csv_records(
    path: impl AsRef<Path>,
    headers: &[&str],
    records: &[Vec<CsvCell>],
) -> Result<(), ReportError> {
    let path = path.as_ref();
    write_text(path, &csv_records_text(path, headers, records)?)
}

/// Format `x` with exactly `decimals` digits after the point (`fixed(0.5, 2)` =
/// `0.50`): the number format of report prose and tables.
pub fn fixed(x: f64, decimals: usize) -> String {
    format!("{x:.decimals$}")
}

/// Format `x` with `decimals` digits after the point; integers (|x| < 1e15) print
/// without decimals, NaN as `NaN`, infinities as `inf` / `-inf`.
pub fn fmt_num(x: f64, decimals: usize) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == x.trunc() && x.abs() < 1e15 {
        return format!("{x:.0}");
    }
    format!("{x:.decimals$}")
}

/// Format an optional number; `None` prints as an em dash `—`.
pub fn fmt_opt(x: Option<f64>, decimals: usize) -> String {
    x.map_or_else(|| "—".to_string(), |v| fmt_num(v, decimals))
}

/// Format an optional interval as `[lo, hi]`; `None` prints as `—`.
pub fn fmt_ci(ci: Option<[f64; 2]>, decimals: usize) -> String {
    ci.map_or_else(
        || "—".to_string(),
        |[lo, hi]| format!("[{}, {}]", fmt_num(lo, decimals), fmt_num(hi, decimals)),
    )
}

/// A GitHub-flavoured Markdown table. `|` in cells is escaped, newlines become spaces;
/// short rows are padded with empty cells.
pub fn md_table(headers: &[&str], rows: &[Vec<String>]) -> String {
    fn cell(s: &str) -> String {
        s.replace('|', "\\|").replace(['\n', '\r'], " ")
    }
    let mut out = String::new();
    let head: Vec<String> = headers.iter().map(|h| cell(h)).collect();
    let _ = writeln!(out, "| {} |", head.join(" | "));
    let _ = writeln!(out, "|{}", " --- |".repeat(headers.len().max(1)));
    for r in rows {
        let mut cells: Vec<String> = r.iter().map(|c| cell(c)).collect();
        while cells.len() < headers.len() {
            cells.push(String::new());
        }
        let _ = writeln!(out, "| {} |", cells.join(" | "));
    }
    out
}

/// A plain-text table with columns padded to equal width (`a | b` rows under a
/// `---` rule), for terminal output.
pub fn text_table(headers: &[&str], rows: &[Vec<String>]) -> String {
    let n = headers.len();
    let mut width: Vec<usize> = headers.iter().map(|h| h.chars().count()).collect();
    for r in rows {
        for (j, c) in r.iter().take(n).enumerate() {
            width[j] = width[j].max(c.chars().count());
        }
    }
    let line = |cells: Vec<&str>| -> String {
        let padded: Vec<String> = (0..n)
            .map(|j| {
                let c = cells.get(j).copied().unwrap_or("");
                format!("{c:<w$}", w = width[j])
            })
            .collect();
        format!("{}\n", padded.join(" | ").trim_end())
    };
    let mut out = line(headers.to_vec());
    let rule: Vec<String> = width.iter().map(|w| "-".repeat(*w)).collect();
    out.push_str(&format!("{}\n", rule.join("-+-")));
    for r in rows {
        out.push_str(&line(r.iter().map(String::as_str).collect()));
    }
    out
}

/// The side-by-side table `method | metric | paper | reproduced | 95% CI` of a summary.
pub fn summary_md_table(summary: &Summary, decimals: usize) -> String {
    let rows: Vec<Vec<String>> = summary
        .rows
        .iter()
        .map(|r| {
            vec![
                r.method.clone(),
                r.metric.clone(),
                fmt_opt(r.paper, decimals),
                fmt_num(r.value, decimals),
                fmt_ci(r.ci95, decimals),
            ]
        })
        .collect();
    md_table(
        &["method", "metric", "paper", "reproduced", "95% CI"],
        &rows,
    )
}

/// The claims of a summary as a Markdown table `claim | holds | detail`.
pub fn claims_md_table(summary: &Summary) -> String {
    let rows: Vec<Vec<String>> = summary
        .claims
        .iter()
        .map(|c| {
            vec![
                format!("`{}`: {}", c.id, c.text),
                holds_word(c.holds).to_string(),
                c.detail.clone(),
            ]
        })
        .collect();
    md_table(&["claim", "verdict", "detail"], &rows)
}

/// `"holds"` or `"does not hold"`.
pub fn holds_word(holds: bool) -> &'static str {
    if holds { "holds" } else { "does not hold" }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> std::path::PathBuf {
        std::env::temp_dir()
            .join("fathom-sim-tests")
            .join("output")
            .join(name)
    }

    fn demo() -> Summary {
        let mut s = Summary::new("fusion", "000_777a2c84247a6c44.txt", 200, 1);
        s.push_row(
            Row::new("MF", "mean_3d", 2.31)
                .with_unit("m")
                .with_paper(3.67)
                .with_ci95(2.25, 2.37, "bootstrap-bca"),
        );
        s.push_row(Row::new("EFF", "turn_ratio_3d", 1.0).with_unit("1"));
        s.push_claim(Claim::new(
            "eff_best_3d_mean",
            "EFF lowest",
            true,
            "EFF 1.12 < MF 2.31",
        ));
        s
    }

    #[test]
    fn summary_json_has_contract_shape_and_order() {
        let mut s = demo();
        s.extra.insert("zeta".into(), serde_json::json!(1));
        s.extra.insert("alpha".into(), serde_json::json!("x"));
        let text = s.to_json_pretty().unwrap();
        let keys = [
            "\"experiment\"",
            "\"seed_doc\"",
            "\"runs\"",
            "\"base_seed\"",
            "\"rows\"",
            "\"claims\"",
            "\"alpha\"",
            "\"zeta\"",
        ];
        let pos: Vec<usize> = keys.iter().map(|k| text.find(k).unwrap()).collect();
        assert!(pos.windows(2).all(|w| w[0] < w[1]), "{text}");
        assert!(text.contains("\"paper\": null"), "{text}");
        assert!(text.contains("\"ci95\": null"), "{text}");
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["rows"][0]["ci95"][1], 2.37);
        assert_eq!(v["claims"][0]["holds"], true);
    }

    #[test]
    fn summary_roundtrips_through_file() {
        let p = tmp("roundtrip/summary.json");
        let s = demo();
        write_summary_json(&p, &s).unwrap();
        let back = read_summary_json(&p).unwrap();
        assert_eq!(back, s);
        // Deterministic: writing twice gives identical bytes.
        let a = std::fs::read(&p).unwrap();
        write_summary_json(&p, &back).unwrap();
        assert_eq!(a, std::fs::read(&p).unwrap());
    }

    #[test]
    fn non_finite_values_are_refused() {
        let mut s = demo();
        s.rows[0].value = f64::NAN;
        let e = s.to_json_pretty().unwrap_err();
        assert!(e.to_string().contains("`MF` / `mean_3d`: value"), "{e}");
        let mut s = demo();
        s.rows[0].ci95 = Some([0.0, f64::INFINITY]);
        assert!(matches!(s.check(), Err(ReportError::NonFinite { .. })));
        let mut s = demo();
        s.rows[0].ci95 = Some([2.0, 1.0]);
        assert!(s.check().is_err());
        let mut s = demo();
        s.push_claim(Claim::new("eff_best_3d_mean", "dup", false, ""));
        assert!(s.check().is_err());
    }

    /// A row without its unit, an interval without its method, a verdict whose
    /// `holds` disagrees with it or without its band: all refused by name.
    #[test]
    fn units_methods_and_verdicts_are_checked() {
        let mut s = demo();
        s.rows[1].unit.clear();
        let e = s.check().unwrap_err().to_string();
        assert!(
            e.contains("`EFF` / `turn_ratio_3d`") && e.contains("no unit"),
            "{e}"
        );
        let mut s = demo();
        s.rows[0].ci_method = None;
        assert!(s.check().unwrap_err().to_string().contains("ci_method"));
        let mut s = demo();
        s.push_claim(Claim::equivalence(
            "eq",
            "t",
            "inconclusive",
            [1.0, 2.0],
            "d",
        ));
        s.check().unwrap();
        assert!(!s.claims[1].holds);
        s.claims[1].holds = true;
        assert!(s.check().is_err());
        s.claims[1].holds = false;
        s.claims[1].verdict = Some("maybe".into());
        assert!(s.check().is_err());
        s.claims[1].verdict = Some("differs".into());
        s.claims[1].band = None;
        assert!(s.check().is_err());
        let text = demo().to_json_pretty().unwrap();
        let row = &text[text.find("\"rows\"").unwrap()..];
        let order = [
            "\"method\"",
            "\"metric\"",
            "\"unit\"",
            "\"paper\"",
            "\"value\"",
            "\"ci95\"",
            "\"ci_method\"",
        ];
        let pos: Vec<usize> = order.iter().map(|k| row.find(k).unwrap()).collect();
        assert!(pos.windows(2).all(|w| w[0] < w[1]), "{text}");
    }

    #[test]
    fn csv_columns_format_and_errors() {
        let p = tmp("series.csv");
        write_csv_columns(&p, &["time_s", "err_3d_m"], &[&[0.0, 0.1], &[1.5, 1e-7]]).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert_eq!(text, "time_s,err_3d_m\n0,1.5\n0.1,0.0000001\n");
        let back: f64 = "0.1".parse().unwrap();
        assert_eq!(back, 0.1);
        assert!(write_csv_columns(&p, &["a", "b"], &[&[1.0], &[1.0, 2.0]]).is_err());
        assert!(write_csv_columns(&p, &["a"], &[&[1.0], &[1.0]]).is_err());
        assert!(write_csv_columns(&p, &["a,b"], &[&[1.0]]).is_err());
        assert!(write_csv_columns(&p, &["a", "a"], &[&[1.0], &[1.0]]).is_err());
    }

    #[test]
    fn csv_records_quote_text() {
        let p = tmp("records.csv");
        write_csv_records(
            &p,
            &["method", "run", "mean_m"],
            &[
                vec!["SC/high".into(), 3usize.into(), 0.25.into()],
                vec!["a,\"b\"".into(), 4usize.into(), f64::NAN.into()],
            ],
        )
        .unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert_eq!(
            text,
            "method,run,mean_m\nSC/high,3,0.25\n\"a,\"\"b\"\"\",4,NaN\n"
        );
        assert!(write_csv_records(&p, &["a", "b"], &[vec![1.0.into()]]).is_err());
    }

    #[test]
    fn markdown_helpers() {
        assert_eq!(fmt_num(1.23456, 3), "1.235");
        assert_eq!(fmt_num(276.0, 3), "276");
        assert_eq!(fmt_num(f64::NAN, 3), "NaN");
        assert_eq!(fmt_opt(None, 2), "—");
        assert_eq!(fmt_ci(Some([1.0, 2.5]), 2), "[1, 2.50]");
        let t = md_table(&["a", "b"], &[vec!["x|y".into()]]);
        assert_eq!(t, "| a | b |\n| --- | --- |\n| x\\|y |  |\n");
        let s = demo();
        let t = summary_md_table(&s, 2);
        assert!(t.starts_with("| method | metric | paper | reproduced | 95% CI |"));
        assert!(
            t.contains("| MF | mean_3d | 3.67 | 2.31 | [2.25, 2.37] |"),
            "{t}"
        );
        assert!(t.contains("| EFF | turn_ratio_3d | — | 1 | — |"), "{t}");
        let tt = text_table(&["a", "bbb"], &[vec!["xyz".into(), "1".into()]]);
        assert_eq!(tt, "a   | bbb\n----+----\nxyz | 1\n");
        let c = claims_md_table(&s);
        assert!(c.contains("| holds |"), "{c}");
    }
}
