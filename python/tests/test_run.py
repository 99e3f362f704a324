"""fathom.run / fathom.check against the real `fathom` binary."""

import json
import pathlib
import subprocess
import threading
import time

import numpy as np
import pytest

import fathom


def run_cli(fathom_bin, *args, cwd):
    return subprocess.run([str(fathom_bin), *args], cwd=cwd, capture_output=True, text=True)


def read_csv(path: pathlib.Path):
    """Columns of a CSV file written by `fathom run` (numbers as float arrays)."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    rows = [line.split(",") for line in lines[1:]]
    out = {}
    for j, h in enumerate(header):
        cells = [r[j] for r in rows]
        try:
            out[h] = np.array([float(c) for c in cells], dtype=float)
        except ValueError:
            out[h] = cells
    return out


def same_column(a, b):
    if isinstance(b, list):
        return a == b
    return a.dtype == np.float64 and a.shape == b.shape and np.array_equal(a, b, equal_nan=True)


@pytest.fixture(scope="module")
def cli_beacons(fathom_bin, root, tmp_path_factory):
    out = tmp_path_factory.mktemp("cli-beacons")
    p = run_cli(fathom_bin, "run", "scenarios/beacons.toml", "--runs", "4", "--out", str(out), cwd=root)
    assert p.returncode == 0, p.stderr
    return out


def test_run_beacons_equals_the_cli(cli_beacons, root, monkeypatch):
    monkeypatch.chdir(root)
    res = fathom.run("scenarios/beacons.toml", runs=4)
    summary = json.loads((cli_beacons / "summary.json").read_text())
    # every number of summary.json, exactly (floats compare bit for bit)
    assert res.summary == summary
    assert res.rows == summary["rows"] and res.claims == summary["claims"]
    assert (res.experiment, res.runs, res.base_seed) == ("beacons", 4, summary["base_seed"])
    assert len(res.rows) > 10 and len(res.claims) > 0
    # the per-time series: the CSV files of the run, as arrays
    csvs = sorted(p.name for p in cli_beacons.glob("*.csv"))
    assert sorted(res.series) == csvs and csvs
    for name in csvs:
        expected = read_csv(cli_beacons / name)
        got = res.series[name]
        assert list(got) == list(expected)
        for col in expected:
            assert same_column(got[col], expected[col]), (name, col)
    err = res.series["error_vs_time.csv"]
    assert all(isinstance(v, np.ndarray) for v in err.values())
    assert sorted(res.figures) == sorted(p.name for p in cli_beacons.glob("*.svg"))
    assert res.out_dir is None
    # negative control: another seed gives other numbers
    other = fathom.run("scenarios/beacons.toml", runs=4, seed=summary["base_seed"] + 1)
    assert other.summary != summary


def test_text_path_and_out_agree(cli_beacons, root, tmp_path, monkeypatch):
    monkeypatch.chdir(root)
    text = (root / "scenarios/beacons.toml").read_text()
    assert fathom.preset("beacons") == text
    res = fathom.run(text, runs=4, threads=1)
    summary = json.loads((cli_beacons / "summary.json").read_text())
    assert res.summary == summary
    out = tmp_path / "out"
    res2 = fathom.run(root / "scenarios/beacons.toml", runs=4, out=out)
    assert res2.out_dir == str(out)
    # same writer as `fathom run`: byte-identical summary.json
    assert (out / "summary.json").read_bytes() == (cli_beacons / "summary.json").read_bytes()
    assert (out / "run_info.json").is_file() and (out / "scenario.resolved.toml").is_file()
    assert res2.summary == summary


def test_check_messages_equal_the_cli(fathom_bin, root, tmp_path):
    good = fathom.check(root / "scenarios/beacons.toml")
    assert 'experiment = "beacons"' in good
    text = (root / "scenarios/beacons.toml").read_text()
    bad_cases = {
        "unknown_key.toml": text.replace("[motion]\n", "[motion]\nbogus_key = 3\n", 1),
        "bad_value.toml": text.replace("runs = 100", "runs = -5", 1),
        "no_experiment.toml": "runs = 3\n",
        "bad_toml.toml": "experiment = \n",
        "unknown_experiment.toml": 'experiment = "nope"\n',
    }
    for name, content in bad_cases.items():
        path = tmp_path / name
        path.write_text(content)
        p = run_cli(fathom_bin, "check", str(path), cwd=tmp_path)
        assert p.returncode == 2, (name, p.stdout)
        line = p.stderr.strip()
        assert line.startswith("error: ") and "\n" not in line
        with pytest.raises(ValueError) as e:
            fathom.check(str(path))
        assert str(e.value) == line[len("error: "):], name
        # run refuses it with the same message, before running
        with pytest.raises(ValueError) as e:
            fathom.run(str(path))
        assert str(e.value) == line[len("error: "):], name
    # as TOML text: the same message, labelled <scenario text>
    with pytest.raises(ValueError, match=r"^<scenario text>: .*bogus_key"):
        fathom.check(bad_cases["unknown_key.toml"])


def test_bad_arguments_raise(root, monkeypatch):
    monkeypatch.chdir(root)
    with pytest.raises(ValueError, match="--runs"):
        fathom.run("scenarios/beacons.toml", runs=0)
    with pytest.raises(ValueError, match="--threads"):
        fathom.run("scenarios/beacons.toml", threads=0)
    with pytest.raises(ValueError, match="--seed"):
        fathom.run("scenarios/beacons.toml", seed=2**63)
    with pytest.raises(OverflowError):
        fathom.run("scenarios/beacons.toml", runs=-1)
    with pytest.raises(ValueError, match="deterministic"):
        fathom.run("scenarios/plaza.toml", seed=3)
    with pytest.raises(FileNotFoundError, match="no-such-file.toml"):
        fathom.run("no-such-file.toml")
    with pytest.raises(TypeError):
        fathom.run(42)
    with pytest.raises(ValueError, match="unknown experiment"):
        fathom.preset("nope")
    assert "beacons" in fathom.experiments()


def test_the_gil_is_released_while_running(root, monkeypatch):
    monkeypatch.chdir(root)
    ticks = []
    done = threading.Event()

    def ticker():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=ticker)
    start = time.perf_counter()
    t.start()
    fathom.run("scenarios/beacons.toml", runs=4, threads=1)
    elapsed = time.perf_counter() - start
    done.set()
    t.join()
    # the other thread kept running during the run: ticks spread over its duration
    during = [x for x in ticks if x < start + elapsed]
    assert elapsed > 0.05 and len(during) > 10, (elapsed, len(during))
