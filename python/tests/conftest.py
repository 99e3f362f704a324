"""Shared fixtures: the repository root and the real `fathom` binary (built with
cargo when it is not given by FATHOM_BIN)."""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def fathom_bin() -> pathlib.Path:
    """The `fathom` command-line binary of this checkout (FATHOM_BIN, else built)."""
    given = os.environ.get("FATHOM_BIN")
    if given:
        path = pathlib.Path(given)
        assert path.is_file(), f"FATHOM_BIN={given} is not a file"
        return path
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "-p", "fathom-cli", "--bin", "fathom"],
        cwd=ROOT,
        check=True,
    )
    meta = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--no-deps"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    )
    target = pathlib.Path(json.loads(meta.stdout)["target_directory"])
    path = target / "release" / "fathom"
    assert path.is_file(), path
    return path
