//! The one CSV writer of fathom: every CSV file fathom writes (an experiment's series
//! and tables, a PILS session's solutions, the PILS study's per-run table) goes
//! through [`CsvWriter`], a `csv::Writer` with fathom's settings: `,` between cells,
//! `\n` after each record, a cell quoted only when it holds a comma, a quote or a line
//! break (quotes doubled). Cells arrive as text that fathom formatted itself (numbers
//! with [`csv_float`]), so the csv crate only quotes and joins; `serialize` is never
//! used (it would print `1.0` for `1` and `1e-7` for `0.0000001`). The one quirk of
//! the csv crate: a record of a single empty cell is written as `""` (an empty line
//! would read back as no record).

use std::fmt::Write as _;
use std::io;

/// Appends `x` in the CSV number format to `buf` (see [`csv_float`]).
fn push_float(buf: &mut String, x: f64) {
    // Writing into a String cannot fail.
    let _ = write!(buf, "{x}");
}

/// Format a float for CSV: shortest round-trip representation (`{}`: `0.1`,
/// `0.0000001`, `NaN`, `inf`; never exponent notation), deterministic and exact.
pub fn csv_float(x: f64) -> String {
    let mut s = String::new();
    push_float(&mut s, x);
    s
}

/// A CSV writer into `W` with fathom's settings (see the module docs). Write a
/// record at once with [`CsvWriter::record`], or cell by cell ([`CsvWriter::text`],
/// [`CsvWriter::float`], [`CsvWriter::display`]) closed by
/// [`CsvWriter::end_record`]; [`CsvWriter::finish`] flushes. Every record must have
/// as many cells as the first one.
#[derive(Debug)]
pub struct CsvWriter<W: io::Write> {
    inner: csv::Writer<W>,
    /// Reused for formatting number cells (no allocation per cell).
    scratch: String,
}

impl<W: io::Write> CsvWriter<W> {
    /// A writer into `out`.
    pub fn new(out: W) -> Self {
        let inner = csv::WriterBuilder::new()
            .delimiter(b',')
            .terminator(csv::Terminator::Any(b'\n'))
            .quote_style(csv::QuoteStyle::Necessary)
            .double_quote(true)
            .flexible(false)
            .from_writer(out);
        Self {
            inner,
            scratch: String::new(),
        }
    }

    /// Writes a whole record of pre-formatted cells (a header row, a text record).
    ///
    /// # Errors
    /// The output's I/O error, or a record whose length differs from the first.
    pub fn record<I, T>(&mut self, cells: I) -> io::Result<()>
    where
        I: IntoIterator<Item = T>,
        T: AsRef<str>,
    {
        for c in cells {
            self.text(c.as_ref())?;
        }
        self.end_record()
    }

    /// Appends a text cell to the current record (quoted when needed).
    ///
    /// # Errors
    /// The output's I/O error.
    pub fn text(&mut self, cell: &str) -> io::Result<()> {
        self.inner.write_field(cell).map_err(io::Error::from)
    }

    /// Appends a number cell in the [`csv_float`] format.
    ///
    /// # Errors
    /// The output's I/O error.
    pub fn float(&mut self, x: f64) -> io::Result<()> {
        self.scratch.clear();
        push_float(&mut self.scratch, x);
        self.inner
            .write_field(self.scratch.as_bytes())
            .map_err(io::Error::from)
    }

    /// Appends a cell formatted with `Display` (integers, booleans).
    ///
    /// # Errors
    /// The output's I/O error.
    pub fn display(&mut self, v: impl std::fmt::Display) -> io::Result<()> {
        self.scratch.clear();
        // Writing into a String cannot fail.
        let _ = write!(self.scratch, "{v}");
        self.inner
            .write_field(self.scratch.as_bytes())
            .map_err(io::Error::from)
    }

    /// Ends the current record (`\n`).
    ///
    /// # Errors
    /// The output's I/O error, or a record whose length differs from the first.
    pub fn end_record(&mut self) -> io::Result<()> {
        self.inner
            .write_record(None::<&[u8]>)
            .map_err(io::Error::from)
    }

    /// Flushes and returns the output.
    ///
    /// # Errors
    /// The output's I/O error.
    pub fn finish(self) -> io::Result<W> {
        self.inner.into_inner().map_err(|e| e.into_error())
    }
}

/// CSV text written in memory by `body` (for files handed back as text).
///
/// # Errors
/// What `body` returns (a record of the wrong length, say).
pub fn csv_string(
    body: impl FnOnce(&mut CsvWriter<Vec<u8>>) -> io::Result<()>,
) -> io::Result<String> {
    let mut w = CsvWriter::new(Vec::new());
    body(&mut w)?;
    let bytes = w.finish()?;
    // Every cell came in as `str`: the bytes are UTF-8.
    String::from_utf8(bytes).map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting_line_ends_and_numbers() {
        let text = csv_string(|w| {
            w.record(["a", "b", "c"])?;
            w.text("x,y")?;
            w.float(1e-7)?;
            w.display(3u64)?;
            w.end_record()?;
            w.record(["q\"uote", "line\nbreak", "cr\r"])?;
            w.float(f64::NAN)?;
            w.float(f64::NEG_INFINITY)?;
            w.display(true)?;
            w.end_record()
        })
        .unwrap();
        assert_eq!(
            text,
            "a,b,c\n\"x,y\",0.0000001,3\n\"q\"\"uote\",\"line\nbreak\",\"cr\r\"\nNaN,-inf,true\n"
        );
        assert_eq!(csv_float(0.1), "0.1");
        assert_eq!(csv_float(1.0), "1");
        // A ragged record is refused.
        assert!(
            csv_string(|w| {
                w.record(["a", "b"])?;
                w.record(["c"])
            })
            .is_err()
        );
    }
}
