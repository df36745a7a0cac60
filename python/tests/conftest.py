"""Shared fixtures: the repository, the CLI binary to compare with, the problems."""

import json
import os
import pathlib
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def cli() -> str:
    """The `grasp-torque` binary: $GRASP_TORQUE_CLI, or the repository's release or
    debug build, built here (release) when neither exists."""
    given = os.environ.get("GRASP_TORQUE_CLI")
    if given:
        return given
    for profile in ("release", "debug"):
        exe = ROOT / "target" / profile / "grasp-torque"
        if exe.exists():
            return str(exe)
    cargo = shutil.which("cargo")
    assert cargo, "cargo is needed to build the CLI the tests compare with"
    subprocess.run(
        [cargo, "build", "--release", "--bin", "grasp-torque"], cwd=ROOT, check=True
    )
    return str(ROOT / "target" / "release" / "grasp-torque")


def fixture_files():
    files = []
    for d in ("fixtures", "fixtures/geometry", "fixtures/hands"):
        files += sorted((ROOT / d).glob("*.json"))
    return files


def reference_cases():
    with open(ROOT / "tests" / "data" / "reference-cases.json") as f:
        return json.load(f)["cases"]
