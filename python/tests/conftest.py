"""Shared fixtures: the `volcast` binary the Python results are compared with, and the data folders."""

import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data"
IN_CI = os.environ.get("CI") == "true"


def need(condition: bool, why: str) -> None:
    """Skips where `condition` fails, except in CI (CI=true), where nothing may silently not run."""
    if not condition:
        if IN_CI:
            pytest.fail(f"CI needs this: {why}")
        pytest.skip(why)


@pytest.fixture(scope="session")
def cli() -> str:
    """The `volcast` binary of this checkout (VOLCAST_BIN, else target/release/volcast)."""
    path = os.environ.get("VOLCAST_BIN") or str(ROOT / "target" / "release" / "volcast")
    need(os.path.exists(path) or shutil.which(path) is not None, f"the volcast binary ({path}); cargo build --release")
    return path


@pytest.fixture(scope="session")
def shared() -> pathlib.Path:
    need(SHARED.is_dir(), f"{SHARED} (the real volumes beside the checkout)")
    return SHARED


@pytest.fixture(scope="session")
def data() -> pathlib.Path:
    return ROOT / "tests" / "data"
