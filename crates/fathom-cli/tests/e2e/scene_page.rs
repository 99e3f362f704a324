//! End-to-end tests of the 3D scene page (issue 40) through the `fathom` binary: a run
//! with a world writes `scene.html` (self-contained: three.js, its licence and the
//! data inlined, no `src=` or `href=` to fetch), its embedded data is consistent (every
//! method of the run, the world's triangles, arrays inside the binary block), the
//! output folder lists it as fathom's own file, `fathom view` prints its path, and
//! `--no-scene` skips it (then `view` is a usage error). The page drawn in a real
//! browser is checked by `.ci/browser.sh`.

use crate::support::{fathom, read, scratch};
use crate::urban::{GOOD_PATH, METHODS, block, setup};

/// The text of the `<script>` element with id `id`.
fn script<'a>(page: &'a str, id: &str) -> &'a str {
    let open = format!("id=\"{id}\">");
    let start = page.find(&open).unwrap_or_else(|| panic!("no #{id}")) + open.len();
    let len = page[start..].find("</script>").unwrap();
    &page[start..start + len]
}

/// Largest end of an array reference `{o, n, t}` anywhere in `v`, bytes.
fn max_end(v: &serde_json::Value) -> usize {
    match v {
        serde_json::Value::Object(m) if m.get("t").is_some_and(serde_json::Value::is_string) => {
            let size = match m["t"].as_str().unwrap() {
                "f32" | "u32" => 4,
                _ => 1,
            };
            m["o"].as_u64().unwrap() as usize + size * m["n"].as_u64().unwrap() as usize
        }
        serde_json::Value::Object(m) => m.values().map(max_end).max().unwrap_or(0),
        serde_json::Value::Array(a) => a.iter().map(max_end).max().unwrap_or(0),
        _ => 0,
    }
}

#[test]
fn a_run_with_a_world_writes_its_scene_page_and_view_finds_it() {
    let dir = scratch("scene-page");
    setup(&dir);
    std::fs::write(dir.join("u.toml"), block("block.obj", GOOD_PATH)).unwrap();
    let ran = fathom(&dir, &["run", "u.toml", "--runs", "2", "--out", "o"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let page = read(&dir, "o/scene.html");
    assert!(page.starts_with("<!DOCTYPE html>"));
    // Self-contained: nothing to fetch from disk or a network.
    for fetch in ["src=", "href=", "import "] {
        assert!(!page.contains(fetch), "the page loads `{fetch}`");
    }
    assert!(script(&page, "three-license").contains("three.js authors"));
    let header: serde_json::Value = serde_json::from_str(script(&page, "fathom-header")).unwrap();
    let scene = &header["scenes"][0];
    assert_eq!(scene["name"], "block");
    let names: Vec<&str> = scene["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, METHODS);
    assert!(scene["mesh"]["i"]["n"].as_u64().unwrap() >= 3);
    let epochs = scene["times"]["n"].as_u64().unwrap();
    assert!(epochs > 10, "{epochs} epochs");
    assert_eq!(scene["truth"]["n"].as_u64().unwrap(), 3 * epochs);
    assert!(
        scene["sky"]["t"]["n"].as_u64().unwrap() > 0,
        "no GNSS epoch"
    );
    assert!(scene["scans"]["t"]["n"].as_u64().unwrap() > 0, "no scan");
    // Every array lies inside the base64 block, which ends with the last one.
    let b64 = script(&page, "fathom-data").trim();
    let pad = b64.chars().rev().take_while(|c| *c == '=').count();
    let bytes = b64.len() / 4 * 3 - pad;
    let end = max_end(&header);
    assert!(end <= bytes && bytes < end + 4, "{end} vs {bytes}");
    // fathom's own file, listed in run_info.json.
    assert!(read(&dir, "o/run_info.json").contains("scene.html"));

    let view = fathom(&dir, &["view", "o", "--no-open"]);
    assert_eq!(view.code, 0, "{view:?}");
    assert!(view.stdout.trim_end().ends_with("scene.html"), "{view:?}");
    assert!(std::path::Path::new(view.stdout.trim_end()).is_file());

    let ran = fathom(
        &dir,
        &["run", "u.toml", "--runs", "2", "--out", "n", "--no-scene"],
    );
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(dir.join("n/summary.json").is_file());
    assert!(!dir.join("n/scene.html").exists());
    let view = fathom(&dir, &["view", "n", "--no-open"]);
    assert_eq!(view.code, 2, "{view:?}");
    assert!(view.stderr.contains("scene.html"), "{view:?}");
}

/// `fathom pils` writes the session's page into `sim/` (the link's solutions and the
/// offline reference), `fathom view` finds it there, and `--no-scene` skips it.
#[test]
fn a_pils_session_writes_its_scene_page_into_sim() {
    let dir = scratch("scene-page-pils");
    setup(&dir);
    std::fs::write(dir.join("u.toml"), block("block.obj", GOOD_PATH)).unwrap();
    let r = fathom(&dir, &["pils", "u.toml", "--method", "GREKF", "--out", "p"]);
    assert_eq!(r.code, 0, "{r:?}");
    let page = read(&dir, "p/sim/scene.html");
    let header: serde_json::Value = serde_json::from_str(script(&page, "fathom-header")).unwrap();
    let names: Vec<&str> = header["scenes"][0]["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["PILS GREKF", "offline GREKF"]);
    assert_eq!(header["scenes"][0]["name"], "block");
    let view = fathom(&dir, &["view", "p", "--no-open"]);
    assert_eq!(view.code, 0, "{view:?}");
    assert!(
        view.stdout.trim_end().ends_with("sim/scene.html"),
        "{view:?}"
    );

    let r = fathom(
        &dir,
        &[
            "pils",
            "u.toml",
            "--method",
            "GREKF",
            "--out",
            "q",
            "--no-scene",
        ],
    );
    assert_eq!(r.code, 0, "{r:?}");
    assert!(dir.join("q/sim/pils.json").is_file());
    assert!(!dir.join("q/sim/scene.html").exists());
}
