//! The paragraphs of `report.md` both own-log replays write under the driver's tables
//! (`###` headings: the driver's sections are `##`): the methods, how to read the NIS
//! rows and checks, the CSV files.

use std::fmt::Write as _;

/// `### Methods`: each method's name and what it runs.
pub fn methods<'a>(list: impl IntoIterator<Item = (&'a str, String)>) -> String {
    let mut md = String::from("### Methods\n\n");
    for (name, what) in list {
        let _ = writeln!(md, "- `{name}`: {what}");
    }
    md.push('\n');
    md
}

/// `### Innovations`: what the `nis_*` rows and the checks say, with and without
/// ground truth.
pub fn innovations(with_truth: bool) -> String {
    let mut md = String::from(
        "### Innovations\n\nThe rows `nis_<kind>_mean`, `nis_<kind>_median`, \
         `nis_<kind>_beyond_95` and `nis_<kind>_count` summarize the normalized innovation \
         squared (NIS) of each filter's measurements of one kind, divided by its degrees \
         of freedom: a consistent filter averages 1, inside the 95 % interval that its \
         check names, with about 5 % of values beyond the chi-square 95 % quantile \
         (`beyond_95` = 0.05). For ranges they cover the accepted ones: a range the \
         robust filter rejected (beyond `robust.reject_sigma`) is counted in `rejected` \
         instead. The figures `nis*.svg` show it over time against that \
         interval, `innovations*.svg` the innovations against the ±3√S the filter \
         predicted for them.\n",
    );
    if !with_truth {
        md.push_str(
            "\nThe log has no `truth.csv`: no errors can be scored. The innovations show \
             whether each filter's model fits the data. Much larger values: the filter \
             trusts its sensors or model too much; much smaller: too little.\n",
        );
    }
    md.push('\n');
    md
}

/// `### Files`: the CSV files (`tested` names what `innovations.csv` holds).
pub fn files(tested: &str) -> String {
    format!(
        "### Files\n\n`estimates.csv`: the estimates (and the truth, when the log has it) \
         at the recording instants; `innovations.csv`: {tested}, with its innovation, NIS \
         and whether it was accepted.\n"
    )
}
