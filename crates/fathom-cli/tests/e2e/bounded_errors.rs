//! Error messages echo the user's input bounded (issue #38): 100 kB material names,
//! 20 kB paths, 100 kB CSV column names, scenario names and keys, and a list of
//! 200,000 beacon ids through the real `fathom` binary, each refused with exit 2 and
//! one line of at most 1 kB in which no run of the input is longer than 200
//! characters. World and log files that are not regular files are refused without
//! being opened.

use std::path::Path;
use std::time::{Duration, Instant};

use crate::support::{fathom, preset, read, scratch};

/// The character the oversized inputs are made of (absent from fathom's own text).
const BOMB: char = 'Q';

/// The longest run of [`BOMB`] in `text`.
fn longest_bomb_run(text: &str) -> usize {
    text.split(|c| c != BOMB)
        .map(|run| run.chars().count())
        .max()
        .unwrap_or(0)
}

fn bomb(n: usize) -> String {
    BOMB.to_string().repeat(n)
}

/// `fathom args` in `dir` is refused with exit 2 and one bounded line naming `want`.
fn bounded_usage_error(dir: &Path, args: &[&str], want: &str) {
    let ran = fathom(dir, args);
    assert_eq!(
        ran.code,
        2,
        "{args:?}: {}",
        &ran.stderr[..ran.stderr.len().min(2000)]
    );
    let msg = ran.stderr.trim_end();
    assert_eq!(
        msg.lines().count(),
        1,
        "{args:?}: {} lines",
        msg.lines().count()
    );
    assert!(
        msg.len() <= 1024,
        "{args:?}: {} bytes: {}",
        msg.len(),
        &msg[..2000.min(msg.len())]
    );
    assert!(longest_bomb_run(msg) <= 200, "{args:?}: {msg}");
    assert!(msg.contains(want), "{args:?}: want `{want}` in {msg}");
}

/// An `urban` file flying the world file `world` (as written in the TOML string).
fn urban_with_world(world: &str) -> String {
    let text = preset("urban.toml").replace("runs = 50 ", "runs = 2 ");
    let head = text.split("[[scenarios]]").next().unwrap();
    format!(
        "{head}\n[[scenarios]]\nname = \"block\"\nranging = \"rangefinders\"\n\n\
         [scenarios.world]\nfile = \"{world}\"\naxes = \"enu_z_up\"\n\n\
         [scenarios.path]\nwaypoints = [[0.0, -30.0, 0.5], [0.0, -30.0, 10.0], [0.0, 30.0, 10.0]]\n\
         start_height_m = 0.5\n"
    )
}

#[test]
fn world_names_paths_and_scenario_values_are_echoed_bounded() {
    let dir = scratch("bounded-world");
    let name = bomb(100_000);
    std::fs::write(
        dir.join("mtl.obj"),
        format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl {name}\nf 1 2 3\n"),
    )
    .unwrap();
    std::fs::write(dir.join("mtl.toml"), urban_with_world("mtl.obj")).unwrap();
    bounded_usage_error(&dir, &["check", "mtl.toml"], "unknown material");

    // A 20 kB path (in folders of 200 characters, so that the OS could hold it).
    let long = (0..100).map(|_| bomb(199)).collect::<Vec<_>>().join("/") + "/w.obj";
    std::fs::write(dir.join("path.toml"), urban_with_world(&long)).unwrap();
    bounded_usage_error(&dir, &["check", "path.toml"], "cannot read");

    // A 100 kB scenario name and a 100 kB unknown key.
    let text =
        urban_with_world("w.obj").replace("name = \"block\"", &format!("name = \"{name}!\""));
    std::fs::write(dir.join("name.toml"), text).unwrap();
    bounded_usage_error(&dir, &["check", "name.toml"], "name");
    let text = format!("{name} = 1\n{}", urban_with_world("w.obj"));
    std::fs::write(dir.join("key.toml"), text).unwrap();
    bounded_usage_error(&dir, &["check", "key.toml"], "key.toml");
    // A 20 kB output folder (the output crate's own message, bounded where printed).
    let out = format!("{}/o", bomb(20_000));
    std::fs::write(dir.join("b.toml"), preset("beacons.toml")).unwrap();
    let ran = fathom(&dir, &["run", "b.toml", "--runs", "2", "--out", &out]);
    assert_ne!(ran.code, 0, "{ran:?}");
    let msg = ran.stderr.trim_end();
    assert!(msg.len() <= 1024 && longest_bomb_run(msg) <= 200, "{msg}");
    assert!(msg.contains("QQQ"), "{msg}");
    // A 20 kB scenario file name on the command line.
    bounded_usage_error(
        &dir,
        &["check", &format!("{}.toml", bomb(20_000))],
        "cannot read",
    );
}

/// World files that are not regular files are refused at once, naming the file.
#[cfg(unix)]
#[test]
fn world_fifo_and_device_are_refused_unopened() {
    let dir = scratch("bounded-world-special");
    let made = std::process::Command::new("mkfifo")
        .arg(dir.join("fifo.obj"))
        .status()
        .unwrap();
    assert!(made.success());
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.obj")).unwrap();
    for world in ["fifo.obj", "zero.obj"] {
        let file = format!("{world}.toml");
        std::fs::write(dir.join(&file), urban_with_world(world)).unwrap();
        let start = Instant::now();
        bounded_usage_error(&dir, &["check", &file], "is not a regular file");
        assert!(start.elapsed() < Duration::from_secs(10), "{world}");
    }
}

#[test]
fn log_columns_beacon_lists_and_quotes_are_echoed_bounded() {
    let root = scratch("bounded-log");
    let made = fathom(
        &root,
        &[
            "log",
            "example",
            "range-beacon",
            "--out",
            "good",
            "--duration",
            "30",
        ],
    );
    assert_eq!(made.code, 0, "{made:?}");
    let copy = |name: &str, file: &str, text: &str| {
        let dir = root.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        for f in std::fs::read_dir(root.join("good")).unwrap() {
            let f = f.unwrap();
            std::fs::copy(f.path(), dir.join(f.file_name())).unwrap();
        }
        std::fs::write(dir.join(file), text).unwrap();
    };
    let column = bomb(100_000);
    copy(
        "column",
        "ranges.csv",
        &format!("time[s],beacon,range[m],{column}\n"),
    );
    bounded_usage_error(&root, &["log", "check", "column"], "unknown column");
    copy(
        "cell",
        "ranges.csv",
        &format!("time[s],beacon,range[m]\n1,1,{column}\n"),
    );
    bounded_usage_error(&root, &["log", "check", "cell"], "is not a number");
    copy(
        "quote",
        "ranges.csv",
        &format!("time[s],beacon,range[m]\n1,1,\"{column}\n2,1,3\n{column}\n"),
    );
    bounded_usage_error(&root, &["log", "check", "quote"], "ranges.csv");

    // 200,000 surveyed beacons and a range to one that is not among them.
    let beacons = read(&root.join("good"), "beacons.csv");
    let mut lines = beacons.lines();
    let header = lines.next().unwrap();
    let first = lines.next().unwrap();
    let (_, rest) = first.split_once(',').unwrap();
    let mut many = format!("{header}\n");
    for id in 0..200_000 {
        many.push_str(&format!("{},{rest}\n", 1000 + id));
    }
    copy("ids", "beacons.csv", &many);
    bounded_usage_error(&root, &["log", "check", "ids"], "unknown beacon id");
}

/// A log file that is a FIFO is refused, not waited on.
#[cfg(unix)]
#[test]
fn log_fifo_is_refused_unopened() {
    let root = scratch("bounded-log-fifo");
    let made = fathom(&root, &["log", "example", "range-beacon", "--out", "fifo"]);
    assert_eq!(made.code, 0, "{made:?}");
    std::fs::remove_file(root.join("fifo").join("ranges.csv")).unwrap();
    let made = std::process::Command::new("mkfifo")
        .arg(root.join("fifo").join("ranges.csv"))
        .status()
        .unwrap();
    assert!(made.success());
    let start = Instant::now();
    bounded_usage_error(&root, &["log", "check", "fifo"], "not a regular file");
    assert!(start.elapsed() < Duration::from_secs(10));
}
