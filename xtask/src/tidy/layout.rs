//! Tidy checks of the source layout (ARCHITECTURE.md, "Invariants"):
//!
//! - every `.rs` file belongs to a module tree (no dead file beside the code);
//! - no import circle between the files of one module folder (an experiment folder
//!   goes scenario -> run -> analysis -> figures -> report, never back);
//! - no non-test part of a file above [`MAX_FILE_LINES`] lines, no crate above
//!   [`MAX_CRATE_SHARE`] of the workspace's lines;
//! - the codemap of ARCHITECTURE.md names only paths that exist, and every crate and
//!   every top-level module of a crate;
//! - no test returns early or prints "skipped" when data is missing (a test that needs
//!   data the repository does not hold is `#[ignore]`d with the reason);
//! - nothing in the repository reads the sibling folder of the team's specs
//!   ([`SIBLING_FOLDER`]): users do not have it.
//!
//! Each check is a function of its inputs, run on the workspace and on a broken input
//! (negative controls).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use super::{non_test_part, root, rust_files};

/// The most lines the non-test part of a source file may have.
const MAX_FILE_LINES: usize = 900;
/// The largest share of the workspace's Rust lines one crate may hold.
const MAX_CRATE_SHARE: f64 = 0.25;

/// The folder beside the checkout that holds the team's specs and seeds (CI has it,
/// users do not).
const SIBLING_FOLDER: &str = "shared";

/// How a path into [`SIBLING_FOLDER`] looks in a file (built here so that this file
/// does not name the folder itself).
fn sibling_needles() -> [String; 2] {
    [
        format!("../{SIBLING_FOLDER}"),
        // Any path inside it (data, specs, the benchmark scripts).
        format!("{SIBLING_FOLDER}/"),
    ]
}

/// Whether `text` names a path into [`SIBLING_FOLDER`].
fn names_sibling(text: &str) -> bool {
    sibling_needles().iter().any(|n| text.contains(n.as_str()))
}

/// Folders holding Rust code, relative to the root.
const CODE_DIRS: [&str; 6] = ["crates", "xtask", "src", "tests", "examples", "fuzz"];

fn rel(path: &Path) -> String {
    path.strip_prefix(root())
        .unwrap_or(path)
        .to_string_lossy()
        .replace('\\', "/")
}

/// Every `.rs` file of the workspace (build outputs left out).
fn all_rust_files() -> Vec<PathBuf> {
    let mut out = Vec::new();
    for d in CODE_DIRS {
        rust_files(&root().join(d), &mut out);
    }
    out.retain(|p| !rel(p).split('/').any(|c| c == "target"));
    out.sort();
    out
}

/// The files a crate is compiled from: `src/lib.rs`, `src/main.rs`, and every file of
/// `benches/`, `examples/`, `tests/` (or a `main.rs` one folder down), `fuzz_targets/`.
fn crate_roots(files: &[PathBuf]) -> Vec<PathBuf> {
    files
        .iter()
        .filter(|p| {
            let r = rel(p);
            let parts: Vec<&str> = r.split('/').collect();
            let n = parts.len();
            let parent = parts.get(n.wrapping_sub(2)).copied().unwrap_or("");
            let grand = parts.get(n.wrapping_sub(3)).copied().unwrap_or("");
            let name = parts[n - 1];
            (parent == "src" && (name == "lib.rs" || name == "main.rs"))
                || matches!(parent, "benches" | "examples" | "tests" | "fuzz_targets")
                || (grand == "tests" && name == "main.rs")
        })
        .cloned()
        .collect()
}

/// The `mod name;` declarations of a file with their `#[path = "..."]`, if any.
fn mod_decls(text: &str) -> Vec<(String, Option<String>)> {
    let mut out = Vec::new();
    let mut path_attr: Option<String> = None;
    for line in text.lines() {
        let t = line.trim();
        if let Some(rest) = t.strip_prefix("#[path = \"") {
            path_attr = rest.split('"').next().map(str::to_string);
            continue;
        }
        if t.starts_with("#[") {
            continue;
        }
        let decl = t
            .strip_prefix("pub(crate) ")
            .or_else(|| t.strip_prefix("pub(super) "))
            .or_else(|| t.strip_prefix("pub "))
            .unwrap_or(t);
        if let Some(name) = decl.strip_prefix("mod ").and_then(|r| r.strip_suffix(';')) {
            out.push((name.trim().to_string(), path_attr.take()));
        } else {
            path_attr = None;
        }
    }
    out
}

/// The files reachable from `roots` through `mod` declarations (`read` gives a file's
/// text).
fn reachable(roots: &[PathBuf], read: &dyn Fn(&Path) -> Option<String>) -> BTreeSet<PathBuf> {
    let mut seen = BTreeSet::new();
    let mut todo: Vec<(PathBuf, bool)> = roots.iter().map(|r| (r.clone(), true)).collect();
    while let Some((file, is_root)) = todo.pop() {
        if !seen.insert(file.clone()) {
            continue;
        }
        let Some(text) = read(&file) else { continue };
        let parent = file.parent().unwrap_or(Path::new("")).to_path_buf();
        let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned());
        let owns_dir = is_root || matches!(stem.as_deref(), Some("mod" | "lib" | "main"));
        let dir = if owns_dir {
            parent.clone()
        } else {
            parent.join(stem.unwrap_or_default())
        };
        for (name, path) in mod_decls(&text) {
            let child = match path {
                Some(p) => parent.join(p),
                None => {
                    let flat = dir.join(format!("{name}.rs"));
                    if read(&flat).is_some() {
                        flat
                    } else {
                        dir.join(&name).join("mod.rs")
                    }
                }
            };
            todo.push((child, false));
        }
    }
    seen
}

/// Files of `files` that no module tree of `roots` reaches.
fn orphans(
    files: &[PathBuf],
    roots: &[PathBuf],
    read: &dyn Fn(&Path) -> Option<String>,
) -> Vec<PathBuf> {
    let seen: BTreeSet<PathBuf> = reachable(roots, read)
        .into_iter()
        .map(|p| normalize(&p))
        .collect();
    files
        .iter()
        .filter(|f| !seen.contains(&normalize(f)))
        .cloned()
        .collect()
}

/// `a/b/../c` -> `a/c` (a `#[path]` may climb).
fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// Code without line comments and without its test part.
fn code_of(text: &str) -> String {
    non_test_part(text)
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The names a `super::` / `crate::` path starts with: `super::a::X` -> `a`,
/// `super::{a, b::Y}` -> `a`, `b`.
fn referenced(code: &str, prefix: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        let before = rest[..i].chars().last();
        rest = &rest[i + prefix.len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 0usize;
            let mut cur = String::new();
            for ch in group.chars() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        out.insert(first_segment(&cur));
                        cur.clear();
                        continue;
                    }
                    _ => {}
                }
                cur.push(ch);
            }
            out.insert(first_segment(&cur));
        } else {
            out.insert(first_segment(rest));
        }
    }
    out
}

fn first_segment(s: &str) -> String {
    s.trim()
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// The import circles among sibling files: `files` maps a file's module name to its
/// code; `crate_level` when the files are a crate's `src/` (siblings are `crate::x`).
fn import_cycles(files: &BTreeMap<String, String>, crate_level: bool) -> Vec<Vec<String>> {
    let names: BTreeSet<&String> = files.keys().collect();
    let graph: BTreeMap<&String, Vec<&String>> = files
        .iter()
        .map(|(name, code)| {
            let mut refs = referenced(code, "super::");
            if crate_level {
                refs.extend(referenced(code, "crate::"));
            }
            let deps = names
                .iter()
                .filter(|n| ***n != *name && refs.contains(n.as_str()))
                .copied()
                .collect();
            (name, deps)
        })
        .collect();
    strongly_connected(&graph)
        .into_iter()
        .filter(|c| c.len() > 1)
        .collect()
}

/// Tarjan's strongly connected components of a small graph.
fn strongly_connected(graph: &BTreeMap<&String, Vec<&String>>) -> Vec<Vec<String>> {
    struct State<'a> {
        index: BTreeMap<&'a String, usize>,
        low: BTreeMap<&'a String, usize>,
        stack: Vec<&'a String>,
        on_stack: BTreeSet<&'a String>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(v: &'a String, g: &BTreeMap<&'a String, Vec<&'a String>>, s: &mut State<'a>) {
        let i = s.index.len();
        s.index.insert(v, i);
        s.low.insert(v, i);
        s.stack.push(v);
        s.on_stack.insert(v);
        for &w in g.get(v).map(Vec::as_slice).unwrap_or(&[]) {
            if !s.index.contains_key(w) {
                visit(w, g, s);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on_stack.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack.remove(w);
                comp.push(w.clone());
                if w == v {
                    break;
                }
            }
            comp.sort();
            s.out.push(comp);
        }
    }
    let mut s = State {
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in graph.keys() {
        if !s.index.contains_key(v) {
            visit(v, graph, &mut s);
        }
    }
    s.out
}

/// Module folders: every folder holding two or more `.rs` files besides
/// `mod.rs` / `lib.rs` / `main.rs`, with the files' code by module name.
fn module_folders(files: &[PathBuf]) -> BTreeMap<PathBuf, BTreeMap<String, String>> {
    let mut out: BTreeMap<PathBuf, BTreeMap<String, String>> = BTreeMap::new();
    for f in files {
        let stem = f.file_stem().unwrap().to_string_lossy().into_owned();
        if matches!(stem.as_str(), "mod" | "lib" | "main") {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap();
        out.entry(f.parent().unwrap().to_path_buf())
            .or_default()
            .insert(stem, code_of(&text));
    }
    out.retain(|_, m| m.len() >= 2);
    out
}

/// The codemap's entries: the paths named at the start of its lines (a line's path
/// continues the nearest entry above with less indentation whose path is a folder).
fn codemap_paths(architecture: &str) -> Vec<String> {
    let Some(start) = architecture.find("## Codemap") else {
        return Vec::new();
    };
    let section = &architecture[start..];
    let Some(open) = section.find("```text\n") else {
        return Vec::new();
    };
    let body = &section[open + 8..];
    let body = &body[..body.find("```").unwrap_or(body.len())];
    let mut stack: Vec<(usize, String)> = Vec::new();
    let mut out = Vec::new();
    for line in body.lines() {
        let indent = line.len() - line.trim_start().len();
        let token = line.split_whitespace().next().unwrap_or("");
        let is_path = indent < 20
            && !token.is_empty()
            && token
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "_-./".contains(c))
            && (token.ends_with('/') || token.contains('.'));
        if !is_path {
            continue;
        }
        while stack.last().is_some_and(|(i, _)| *i >= indent) {
            stack.pop();
        }
        let full = match stack.last() {
            Some((_, parent)) => format!("{parent}{token}"),
            None => token.to_string(),
        };
        if token.ends_with('/') {
            stack.push((indent, full.clone()));
        }
        out.push(full);
    }
    out
}

/// What the codemap must name: every crate folder and every top-level module of a
/// crate's `src/` (its files and folders but `lib.rs` / `main.rs`).
fn codemap_required() -> Vec<String> {
    let mut out = Vec::new();
    let crates = root().join("crates");
    let mut names: Vec<_> = std::fs::read_dir(&crates)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    for c in names {
        out.push(format!("crates/{c}/"));
        let src = crates.join(&c).join("src");
        let mut entries: Vec<_> = std::fs::read_dir(&src)
            .into_iter()
            .flatten()
            .flatten()
            .collect();
        entries.sort_by_key(std::fs::DirEntry::file_name);
        for e in entries {
            let name = e.file_name().to_string_lossy().into_owned();
            if name == "lib.rs" || name == "main.rs" {
                continue;
            }
            let slash = if e.path().is_dir() { "/" } else { "" };
            out.push(format!("crates/{c}/src/{name}{slash}"));
        }
    }
    out
}

/// Test code that gives up quietly: `skipped` printed, or a `return` right after a
/// look for a file or folder.
fn silent_skips(path: &str, text: &str) -> Vec<String> {
    let test_code = if path.starts_with("tests/") || path.contains("/tests/") {
        text
    } else {
        text.find("#[cfg(test)]").map_or("", |i| &text[i..])
    };
    let lines: Vec<&str> = test_code.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let code = l.split("//").next().unwrap_or("");
        let printed_skip = (code.contains("eprintln!") || code.contains("println!"))
            && code.to_lowercase().contains("skip");
        let early_return = code.contains("return")
            && lines[i.saturating_sub(3)..=i].iter().any(|p| {
                [
                    ".exists()",
                    ".is_dir()",
                    ".is_file()",
                    "find_data_dir",
                    "read_to_string(",
                    "fs::read(",
                ]
                .iter()
                .any(|n| p.contains(n))
            });
        if printed_skip || early_return {
            out.push(format!("{path}: a test gives up quietly: `{}`", l.trim()));
        }
    }
    out
}

#[test]
fn every_rust_file_is_in_a_module_tree() {
    let files = all_rust_files();
    let roots = crate_roots(&files);
    let read = |p: &Path| std::fs::read_to_string(p).ok();
    let dead: Vec<String> = orphans(&files, &roots, &read)
        .iter()
        .map(|p| rel(p))
        .collect();
    assert!(dead.is_empty(), "files outside every module tree: {dead:?}");

    // Negative control: a file no `mod` names is found; a `#[path]` one is not.
    let fake: BTreeMap<PathBuf, &str> = [
        (
            "c/src/lib.rs",
            "//! x\nmod a;\n#[path = \"../other/p.rs\"]\nmod p;\n",
        ),
        ("c/src/a.rs", "//! a\npub mod b;\n"),
        ("c/src/a/b.rs", "//! b\n"),
        ("c/other/p.rs", "//! p\n"),
        ("c/src/dead.rs", "//! dead\n"),
    ]
    .into_iter()
    .map(|(p, t)| (PathBuf::from(p), t))
    .collect();
    let files: Vec<PathBuf> = fake.keys().cloned().collect();
    let read = |p: &Path| fake.get(&normalize(p)).map(|t| t.to_string());
    let found = orphans(&files, &[PathBuf::from("c/src/lib.rs")], &read);
    assert_eq!(found, [PathBuf::from("c/src/dead.rs")]);
}

#[test]
fn no_import_circle_between_the_files_of_a_module_folder() {
    let files = all_rust_files();
    let mut problems = Vec::new();
    for (dir, modules) in module_folders(&files) {
        let crate_level = dir.file_name().is_some_and(|n| n == "src");
        for cycle in import_cycles(&modules, crate_level) {
            problems.push(format!("{}: {}", rel(&dir), cycle.join(" <-> ")));
        }
    }
    assert!(
        problems.is_empty(),
        "import circles:\n{}",
        problems.join("\n")
    );

    // Negative control: analysis -> figures -> analysis is a circle, a one-way chain
    // and a name in a comment are not.
    let m = |pairs: &[(&str, &str)]| -> BTreeMap<String, String> {
        pairs
            .iter()
            .map(|(a, b)| (a.to_string(), code_of(b)))
            .collect()
    };
    let circle = m(&[
        ("analysis", "use super::{figures, report};"),
        ("figures", "use super::analysis::Table;"),
        ("report", "// super::analysis\n"),
    ]);
    assert_eq!(import_cycles(&circle, false), [vec!["analysis", "figures"]]);
    let chain = m(&[
        ("analysis", "use super::run::X;"),
        ("figures", "use super::{analysis::T, run};"),
        ("run", "fn f() {}"),
    ]);
    assert!(import_cycles(&chain, false).is_empty());
    let top = m(&[("a", "use crate::b::X;"), ("b", "fn f() { crate::a::g() }")]);
    assert_eq!(import_cycles(&top, true).len(), 1);
    assert!(import_cycles(&top, false).is_empty());
}

#[test]
fn files_and_crates_stay_small() {
    let files = all_rust_files();
    let mut problems = Vec::new();
    let mut per_crate: BTreeMap<String, usize> = BTreeMap::new();
    let mut total = 0usize;
    for f in &files {
        let r = rel(f);
        let text = std::fs::read_to_string(f).unwrap();
        let lines = text.lines().count();
        total += lines;
        if let Some(c) = r.strip_prefix("crates/").and_then(|s| s.split('/').next()) {
            *per_crate.entry(c.to_string()).or_default() += lines;
        }
        let is_test_file =
            r.starts_with("tests/") || r.contains("/tests/") || r.ends_with("tests.rs");
        let code = non_test_part(&text).lines().count();
        if !is_test_file && code > MAX_FILE_LINES {
            problems.push(format!(
                "{r}: {code} lines outside its tests (at most {MAX_FILE_LINES})"
            ));
        }
    }
    for (c, n) in &per_crate {
        let share = *n as f64 / total as f64;
        if share > MAX_CRATE_SHARE {
            problems.push(format!(
                "crate {c}: {n} of the workspace's {total} lines ({:.0} %, at most {:.0} %)",
                100.0 * share,
                100.0 * MAX_CRATE_SHARE
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(per_crate.len() >= 10 && total > 10_000, "{per_crate:?}");
}

#[test]
fn the_codemap_names_what_exists_and_everything_that_does() {
    let architecture = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let paths = codemap_paths(&architecture);
    let mut problems: Vec<String> = paths
        .iter()
        .filter(|p| !root().join(p).exists())
        .map(|p| format!("the codemap names `{p}`, which does not exist"))
        .collect();
    let named: BTreeSet<&str> = paths.iter().map(String::as_str).collect();
    for r in codemap_required() {
        if !named.contains(r.as_str()) {
            problems.push(format!("the codemap does not name `{r}`"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));

    // Negative control: nesting by indentation; a description line is not a path.
    let fake = "## Codemap\n\n```text\ncrates/\n  fathom-x/          what it is\n    src/a.rs         the a\n                     more words.rs here\nxtask/               tasks\n```\n";
    assert_eq!(
        codemap_paths(fake),
        [
            "crates/",
            "crates/fathom-x/",
            "crates/fathom-x/src/a.rs",
            "xtask/"
        ]
    );
}

#[test]
fn no_test_gives_up_quietly_and_nothing_reads_the_sibling_folder() {
    let mut problems = Vec::new();
    for f in all_rust_files() {
        let r = rel(&f);
        if r.starts_with("xtask/src/tidy/") {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        problems.extend(silent_skips(&r, &text));
        if names_sibling(&text) {
            problems.push(format!(
                "{r}: names the sibling `{SIBLING_FOLDER}` folder (data lives in the repository)"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));

    // Negative controls: both quiet skips are found, a test that fails loudly is not.
    let quiet =
        "#[test]\nfn t() {\n    let p = dir();\n    if !p.exists() {\n        return;\n    }\n}\n";
    assert_eq!(silent_skips("tests/e2e/x.rs", quiet).len(), 1);
    let printed = "#[cfg(test)]\nmod t { fn f() { eprintln!(\"skipped: no data\"); } }\n";
    assert_eq!(silent_skips("crates/a/src/x.rs", printed).len(), 1);
    let loud = "#[test]\nfn t() {\n    assert!(dir().exists(), \"missing\");\n}\n";
    assert!(silent_skips("tests/e2e/x.rs", loud).is_empty());
    // A path into the sibling folder is found; the repository's own data is not.
    let outside = format!("let d = Path::new(\"../{SIBLING_FOLDER}/plaza1\");");
    assert!(names_sibling(&outside));
    assert!(!names_sibling("let d = repo_root().join(\"data/plaza1\");"));
    assert!(names_sibling(&format!(
        "//! see `{SIBLING_FOLDER}/bench/x.py`"
    )));
}
