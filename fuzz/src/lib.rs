//! Fuzz harnesses of fathom: what each cargo-fuzz target in `fuzz_targets/` does with
//! its input bytes, kept in plain functions so that the root e2e test
//! (`crates/fathom-cli/tests/e2e/fuzz_corpus.rs`, which includes this file as a module) replays every
//! committed corpus and regression file through exactly the same code without
//! cargo-fuzz or libFuzzer.
//!
//! Each harness panics only when fathom misbehaves (a panic inside fathom, or an
//! `Ok` result that breaks the reader's documented guarantees); bad input must come
//! back as an error. Each returns its outcome as text lines (`ok ...` or the error's
//! message), which the regression test compares with the `.expected` file stored
//! beside each regression input.

#[cfg(fuzzing)]
pub mod heap_cap;

use fathom_core::{Material, RayCaster};
use fathom_data::layout::gnss_ins::GnssInsLog;
use fathom_data::layout::{FileSet, LogKind, Manifest};
use fathom_data::matv5::mat_v5_bytes;
use fathom_data::plaza::{
    BeaconSite, PlazaMat, RangeOrder, parse_mat, parse_odometry, parse_ranges,
};
use fathom_experiments::registry;
use fathom_map::mesh::{MAX_COORD, is_degenerate};
use fathom_map::{
    AxisConvention, BruteForceCaster, BvhCaster, ImportReport, ImportSettings, MapError,
    MaterialTable, TriMesh, obj, stl,
};
use fathom_sim::SimError;
use fathom_sim::cost::Limits;
use fathom_sim::user_run::{check_scenario_text, one_line, peek_experiment};

/// Target `scenario`: the bytes (lossy UTF-8) as a scenario file through
/// [`check_scenario_text`] (what `fathom check` does).
///
/// A scenario that checks OK must resolve to a TOML text that checks OK again and
/// resolves to itself.
pub fn scenario(data: &[u8]) -> Vec<String> {
    check_text(&String::from_utf8_lossy(data))
}

/// The [`scenario`] check on a text.
pub fn check_text(text: &str) -> Vec<String> {
    let reg = registry();
    match check_scenario_text(text, "fuzz.toml", &reg) {
        Ok(c) => {
            let again = check_scenario_text(&c.resolved_toml, "resolved.toml", &reg)
                .unwrap_or_else(|e| {
                    panic!(
                        "the resolved scenario does not check again: {}\n{}",
                        fathom_sim::error_chain(&e),
                        c.resolved_toml
                    )
                });
            assert_eq!(
                again.resolved_toml, c.resolved_toml,
                "resolving is not idempotent"
            );
            vec![format!(
                "ok: experiment `{}`, {} keys in {} tables",
                c.experiment, c.keys, c.tables
            )]
        }
        Err(e) => vec![one_line(&fathom_sim::error_chain(&e))],
    }
}

/// The valid presets (`scenarios/*.toml`, one per registered experiment) that
/// [`scenario_edit`] starts from.
pub fn presets() -> Vec<&'static str> {
    registry().iter().map(|e| e.preset()).collect()
}

/// Values that validation must handle (non-finite, signed zero, extremes, wrong types).
const SPECIAL_VALUES: [&str; 24] = [
    "nan",
    "inf",
    "-inf",
    "0",
    "0.0",
    "-0.0",
    "-1",
    "-1.0",
    "1",
    "2",
    "1e308",
    "-1e308",
    "5e-324",
    "1e-9",
    "9223372036854775807",
    "-9223372036854775808",
    "4294967296",
    "true",
    "\"\"",
    "[]",
    "[0.0, 1.0]",
    "[[0.0, 1.0], [2.0, 3.0]]",
    "{}",
    "1979-05-27T07:32:00Z",
];

/// Reads the input bytes one decision at a time; an exhausted input reads as zeros.
struct Decisions<'a> {
    bytes: &'a [u8],
}

impl Decisions<'_> {
    fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    fn byte(&mut self) -> u8 {
        match self.bytes.split_first() {
            Some((&b, rest)) => {
                self.bytes = rest;
                b
            }
            None => 0,
        }
    }

    fn index(&mut self, len: usize) -> usize {
        let v = usize::from(u16::from_le_bytes([self.byte(), self.byte()]));
        if len == 0 { 0 } else { v % len }
    }

    fn u64(&mut self) -> u64 {
        let mut b = [0u8; 8];
        for x in &mut b {
            *x = self.byte();
        }
        u64::from_le_bytes(b)
    }

    fn take(&mut self, n: usize) -> &[u8] {
        let n = n.min(self.bytes.len());
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        head
    }
}

/// `key = value` lines of the presets: (key, value text).
fn assignments() -> Vec<(&'static str, &'static str)> {
    presets()
        .into_iter()
        .flat_map(|p| p.lines())
        .filter_map(|l| {
            let l = l.trim();
            if l.starts_with('#') || l.starts_with('[') {
                return None;
            }
            let (k, v) = l.split_once('=')?;
            let v = v.split(" #").next().unwrap_or(v);
            Some((k.trim(), v.trim()))
        })
        .collect()
}

/// A TOML value chosen by the input: a special value, one of the presets' own values
/// (so enum strings and arrays of the right shape occur), a float from raw bits or a
/// small integer.
fn value(d: &mut Decisions<'_>, known: &[(&str, &str)]) -> String {
    match d.byte() % 4 {
        0 => SPECIAL_VALUES[d.index(SPECIAL_VALUES.len())].to_string(),
        1 => known[d.index(known.len())].1.to_string(),
        2 => {
            let v = f64::from_bits(d.u64());
            if v.is_nan() {
                "nan".into()
            } else if v.is_infinite() {
                if v > 0.0 { "inf".into() } else { "-inf".into() }
            } else {
                // `{:?}` prints a float TOML reads back exactly (`1e300`, `0.5`, `-0.0`).
                format!("{v:?}")
            }
        }
        _ => format!("{}", i64::from(d.byte() as i8)),
    }
}

/// The scenario text that [`scenario_edit`] builds from `data`: a preset (first byte)
/// edited line by line (each later decision: replace a value, delete, duplicate or
/// move a line, insert a known key with a value, or insert a few raw bytes).
pub fn edited_preset(data: &[u8]) -> String {
    let mut d = Decisions { bytes: data };
    let known = assignments();
    let presets = presets();
    let preset = presets[usize::from(d.byte()) % presets.len()];
    let mut lines: Vec<String> = preset.lines().map(str::to_string).collect();
    for _ in 0..32 {
        if d.is_empty() {
            break;
        }
        let op = d.byte() % 6;
        let at = d.index(lines.len() + 1);
        match op {
            0 => {
                if let Some(line) = lines.get(at)
                    && let Some((k, _)) = line.split_once('=')
                    && !line.trim_start().starts_with(['#', '['])
                {
                    let new = format!("{k}= {}", value(&mut d, &known));
                    lines[at] = new;
                }
            }
            1 => {
                if at < lines.len() {
                    lines.remove(at);
                }
            }
            2 => {
                if let Some(line) = lines.get(at).cloned() {
                    lines.insert(at, line);
                }
            }
            3 => {
                let key = known[d.index(known.len())].0;
                let new = format!("{key} = {}", value(&mut d, &known));
                lines.insert(at, new);
            }
            4 => {
                let to = d.index(lines.len());
                if at < lines.len() {
                    let line = lines.remove(at);
                    lines.insert(to.min(lines.len()), line);
                }
            }
            _ => {
                let n = usize::from(d.byte() % 16);
                let raw = String::from_utf8_lossy(d.take(n)).into_owned();
                lines.insert(at, raw);
            }
        }
    }
    let mut text = lines.join("\n");
    text.push('\n');
    text
}

/// Target `scenario_edit`: [`edited_preset`] through the [`scenario`] check. Starting
/// from valid presets, most inputs parse, so the fuzzer spends its time in each
/// experiment's validation rather than in the TOML syntax.
pub fn scenario_edit(data: &[u8]) -> Vec<String> {
    check_text(&edited_preset(data))
}

/// Target `cost`: [`edited_preset`] through its experiment's cost estimate
/// ([`fathom_sim::cost`], what `fathom check` and `fathom run` refuse a scenario by).
///
/// For a scenario that checks, the estimate (per term and in total) must never be NaN
/// or negative, memory must not shrink and time not grow with more worker threads,
/// the limit check must agree with the totals, and a refusal must name a key the
/// estimate lists (or `runs`).
pub fn cost(data: &[u8]) -> Vec<String> {
    let text = edited_preset(data);
    let reg = registry();
    let exp = match peek_experiment(&text, "fuzz.toml", &reg) {
        Ok(e) => e,
        Err(e) => return vec![one_line(&fathom_sim::error_chain(&e))],
    };
    let limits = Limits::default();
    let mut outcome = Vec::new();
    let mut previous: Option<(f64, f64)> = None;
    for threads in [1, 3, 64] {
        let c = match exp.cost(&text, "fuzz.toml", None, None, Some(threads)) {
            Ok(c) => c,
            Err(e) => return vec![one_line(&fathom_sim::error_chain(&e))],
        };
        assert!(c.is_known(), "{}: no estimate", exp.name());
        for t in &c.terms {
            for v in [t.samples, t.bytes, t.seconds_per_sample, t.seconds()] {
                assert!(v >= 0.0, "term `{}`: {v}\n{text}", t.what);
            }
        }
        let (m, s) = (c.memory_bytes(), c.seconds());
        assert!(
            m >= 0.0 && s >= 0.0 && c.samples() >= 0.0,
            "{m} B, {s} s\n{text}"
        );
        if let Some((m0, s0)) = previous {
            assert!(
                m >= m0 && s <= s0,
                "{threads} threads: {m0} -> {m} B, {s0} -> {s} s"
            );
        }
        previous = Some((m, s));
        let fits = m <= limits.memory_bytes && s <= limits.seconds;
        match c.check(&limits, "fuzz.toml") {
            Ok(()) => assert!(fits, "accepted beyond the limits: {m} B, {s} s"),
            Err(SimError::Invalid { key_path, .. }) => {
                assert!(!fits, "refused within the limits: {m} B, {s} s");
                let listed = c
                    .terms
                    .iter()
                    .any(|t| t.keys.iter().any(|k| k.key == key_path));
                assert!(key_path == "runs" || listed, "refusal names `{key_path}`");
            }
            Err(e) => panic!("unexpected error kind: {e:?}"),
        }
        if threads == 1 {
            outcome.push(format!(
                "{}: {}",
                if fits { "fits" } else { "refused" },
                c.summary()
            ));
        }
    }
    outcome
}

/// The beacon survey that [`plaza_text`] checks range files against (the ids of
/// Plaza1's `TL`).
pub const BEACONS: [BeaconSite; 4] = [
    BeaconSite {
        id: 0,
        x: 0.0,
        y: 0.0,
    },
    BeaconSite {
        id: 1,
        x: 10.0,
        y: 0.0,
    },
    BeaconSite {
        id: 5,
        x: 0.0,
        y: 10.0,
    },
    BeaconSite {
        id: 6,
        x: 10.0,
        y: 10.0,
    },
];

/// Target `plaza_text`: the bytes (lossy UTF-8) as a Plaza odometry file
/// ([`parse_odometry`]) and as a range file ([`parse_ranges`], strict and sorting).
/// Accepted files must hold finite values, strictly increasing odometry times, known
/// beacons, non-negative ranges sorted by time.
pub fn plaza_text(data: &[u8]) -> Vec<String> {
    let text = String::from_utf8_lossy(data);
    let mut out = Vec::new();
    match parse_odometry(&text, "fuzz_DR.txt") {
        Ok(steps) => {
            for w in steps.windows(2) {
                assert!(w[1].time > w[0].time, "odometry times must increase");
            }
            for s in &steps {
                assert!(
                    s.time.is_finite()
                        && s.delta_distance.is_finite()
                        && s.delta_heading.is_finite()
                );
            }
            out.push(format!("odometry: ok, {} steps", steps.len()));
        }
        Err(e) => out.push(format!("odometry: {e}")),
    }
    for (name, order) in [("strict", RangeOrder::Strict), ("sort", RangeOrder::Sort)] {
        match parse_ranges(&text, "fuzz_TD.txt", &BEACONS, order) {
            Ok((ranges, breaks)) => {
                assert!(order == RangeOrder::Sort || breaks.is_empty());
                assert!(breaks.windows(2).all(|w| w[0] < w[1]));
                for w in ranges.windows(2) {
                    assert!(w[0].time <= w[1].time, "ranges must be sorted by time");
                }
                for r in &ranges {
                    assert!(r.time.is_finite() && r.range.is_finite() && r.range >= 0.0);
                    assert_eq!(BEACONS[r.beacon].id, r.beacon_id);
                }
                out.push(format!(
                    "ranges {name}: ok, {} ranges, {} order breaks",
                    ranges.len(),
                    breaks.len()
                ));
            }
            Err(e) => out.push(format!("ranges {name}: {e}")),
        }
    }
    out
}

/// Target `plaza_mat`: the bytes as a Plaza `.mat` file ([`parse_mat`]). An accepted
/// file must hold finite values, strictly increasing times and unique beacon ids, and
/// must survive a round trip through the MAT v5 writer ([`mat_v5_bytes`]).
pub fn plaza_mat(data: &[u8]) -> Vec<String> {
    match parse_mat(data, "fuzz_.mat") {
        Ok(mat) => {
            for poses in [&mat.ground_truth, &mat.dr_path] {
                for w in poses.windows(2) {
                    assert!(w[1].time > w[0].time, "times must increase");
                }
                for p in poses.iter() {
                    assert!(p.time.is_finite() && p.x.is_finite());
                    assert!(p.y.is_finite() && p.heading.is_finite());
                }
            }
            for (i, b) in mat.beacons.iter().enumerate() {
                assert!(b.x.is_finite() && b.y.is_finite());
                assert!(mat.beacons[..i].iter().all(|o| o.id != b.id));
            }
            let bytes =
                mat_v5_bytes(&mat.to_matrices()).expect("an accepted file can be written back");
            let again: PlazaMat =
                parse_mat(&bytes, "again_.mat").expect("the written file reads back");
            assert_eq!(again, mat, "MAT v5 round trip changed the data");
            vec![format!(
                "ok: GT {} rows, TL {} beacons, DRp {} rows",
                mat.ground_truth.len(),
                mat.beacons.len(),
                mat.dr_path.len()
            )]
        }
        Err(e) => vec![e.to_string()],
    }
}

/// The import settings of the mesh targets: NED axes, a material table with two
/// custom names (those of `crates/fathom-map/tests/data/house.obj`), opaque faces without `usemtl`, inputs up to 4 MiB.
fn mesh_settings() -> ImportSettings {
    let mut materials = MaterialTable::default();
    materials
        .insert("concrete", Material::Other(1))
        .insert("roof_tiles", Material::Other(2));
    ImportSettings {
        axes: AxisConvention::Ned,
        materials,
        max_bytes: 4 << 20,
        ..ImportSettings::default()
    }
}

/// What an accepted mesh promises: finite vertices within `MAX_COORD`, valid indices,
/// one material per triangle, no degenerate or duplicate triangle, counts that add
/// up; and on small meshes the BVH caster agrees with the brute-force oracle on a fan
/// of rays from the mesh's corners and centre.
fn check_mesh(file: &str, result: Result<(TriMesh, ImportReport), MapError>) -> Vec<String> {
    let (mesh, report) = match result {
        Ok(ok) => ok,
        Err(e) => return vec![e.in_file(file).to_string()],
    };
    let r = report.mesh;
    assert_eq!(r.triangles_kept, mesh.len());
    assert_eq!(
        r.triangles_in,
        r.triangles_kept + r.degenerate_skipped + r.duplicate_skipped
    );
    assert_eq!(mesh.materials().len(), mesh.len());
    for v in mesh.vertices() {
        assert!(v.iter().all(|c| c.abs() <= MAX_COORD), "vertex {v:?}");
    }
    let mut seen = std::collections::HashSet::new();
    for (i, t) in mesh.triangles().iter().enumerate() {
        assert!(t.iter().all(|&k| (k as usize) < mesh.vertices().len()));
        let [a, b, c] = mesh.corners(i);
        assert!(!is_degenerate(&a, &b, &c), "degenerate triangle {i} kept");
        let mut key = *t;
        key.sort_unstable();
        assert!(seen.insert(key), "duplicate triangle {i} kept");
    }
    if let Some((lo, hi)) = mesh.bounds()
        && mesh.len() <= 2000
    {
        let (bvh, oracle) = (BvhCaster::new(&mesh), BruteForceCaster::new(&mesh));
        let center = (lo + hi) / 2.0;
        let span = (hi - lo).norm().max(1.0);
        for o in [lo, hi, center, center + (hi - lo) * 0.3] {
            for k in 0..26u32 {
                let d = nalgebra::Vector3::new(
                    f64::from(k % 3) - 1.0,
                    f64::from(k / 3 % 3) - 1.0,
                    f64::from(k / 9 % 3) - 1.0,
                );
                let (h, g) = (
                    bvh.cast(&o, &d, 2.0 * span),
                    oracle.cast(&o, &d, 2.0 * span),
                );
                assert_eq!(
                    h.map(|x| (x.triangle, x.range.to_bits())),
                    g.map(|x| (x.triangle, x.range.to_bits())),
                    "BVH and oracle disagree from {o:?} along {d:?}"
                );
            }
        }
    }
    vec![format!(
        "ok: {} triangles kept of {} ({} degenerate, {} duplicate), {} non-manifold edges",
        mesh.len(),
        r.triangles_in,
        r.degenerate_skipped,
        r.duplicate_skipped,
        r.non_manifold_edges
    )]
}

/// Target `map_obj`: the bytes as a Wavefront OBJ file ([`obj::parse_obj`]); an
/// accepted mesh is checked as [`check_mesh`] says.
pub fn map_obj(data: &[u8]) -> Vec<String> {
    check_mesh("fuzz.obj", obj::parse_obj(data, &mesh_settings()))
}

/// Target `map_stl`: the bytes as an STL file, binary or ASCII ([`stl::parse_stl`]);
/// an accepted mesh is checked as [`check_mesh`] says.
pub fn map_stl(data: &[u8]) -> Vec<String> {
    check_mesh("fuzz.stl", stl::parse_stl(data, &mesh_settings()))
}

/// Target `ulog`: the bytes as a PX4 ULog converted into a `gnss-ins` log
/// ([`fathom_data::ulog::convert_bytes`], the streaming reader fed from memory). An
/// error must be one line; an accepted log must have strictly increasing, finite time
/// stamps and finite values in every file, and its CSV files must read back to the
/// same log.
pub fn ulog(data: &[u8]) -> Vec<String> {
    match fathom_data::ulog::convert_bytes(data, std::path::Path::new("fuzz.ulg")) {
        Err(e) => {
            let text = e.to_string();
            assert_eq!(text.lines().count(), 1, "a ULog error is one line: {text}");
            vec![text]
        }
        Ok(c) => {
            let log = &c.log;
            let times = [
                log.imu.iter().map(|r| r.time).collect::<Vec<_>>(),
                log.gnss.iter().map(|r| r.time).collect(),
            ];
            for t in &times {
                assert!(t.iter().all(|x| x.is_finite()));
                assert!(t.windows(2).all(|w| w[1] > w[0]), "times must increase");
            }
            for r in &log.imu {
                assert!(
                    r.gyro_in_body
                        .iter()
                        .chain(&r.accel_in_body)
                        .all(|x| x.is_finite())
                );
            }
            let files = log.to_files();
            let set = FileSet {
                dir: "fuzz".into(),
                manifest: Manifest::new(LogKind::GnssIns, ""),
                files: files
                    .iter()
                    .map(|(n, t)| (*n, t.as_bytes().to_vec()))
                    .collect(),
            };
            // values beyond the layout's plausibility bounds are refused on reading
            // back (one line); what reads back must be the same log
            match GnssInsLog::parse(&set) {
                Ok(back) => assert_eq!(&back, log, "CSV round trip changed the log"),
                Err(e) => assert_eq!(e.to_string().lines().count(), 1),
            }
            vec![format!(
                "ok: {} IMU rows, {} GNSS rows, reference {}, truth {}",
                log.imu.len(),
                log.gnss.len(),
                log.reference.as_ref().map_or(0, Vec::len),
                log.truth.as_ref().map_or(0, Vec::len)
            )]
        }
    }
}
