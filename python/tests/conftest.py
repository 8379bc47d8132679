"""Shared fixtures: the `volcast` binary the Python results are compared with, and the data folders."""

import os
import pathlib
import shutil

import pytest

# Every test renders under the Khronos validation layer with synchronization validation (the processes the tests
# start inherit it); `validated` below fails a test after which the layer has said anything.
os.environ["VOLCAST_VALIDATION"] = "1"

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


@pytest.fixture(autouse=True)
def validated():
    """Fails the test if the validation layer reported an error or a warning during it (the device is kept across
    tests, so its counts only grow: any growth is this test's); at the end of the session, leaks are counted by
    `volcast.shutdown()` in test_zz_shutdown.py."""
    from volcast import _volcast

    before = _volcast.validation_counts() or (0, 0)
    yield
    after = _volcast.validation_counts() or (0, 0)
    assert after == before, f"validation: {after[0] - before[0]} errors, {after[1] - before[1]} warnings"
