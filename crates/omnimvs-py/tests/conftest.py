"""Shared fixtures: the real samples beside the repository, the `omnimvs` command line (to
compare with the files it writes) and a private lookup-table cache."""

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
SAMPLES = Path(os.environ.get("OMNIMVS_SAMPLES", REPO.parent / "shared" / "data" / "omnimvs-samples"))

# Lookup tables built by the tests (and by the command line they run) go to a private cache,
# never to the user's; set before the first call into the library.
_CACHE = tempfile.mkdtemp(prefix="omnimvs-pytest-cache-")
os.environ["OMNIMVS_CACHE_DIR"] = _CACHE


def pytest_sessionfinish(session, exitstatus):
    shutil.rmtree(_CACHE, ignore_errors=True)


def _sample(name):
    path = SAMPLES / name
    if not (path / "config.yaml").is_file():
        pytest.skip(f"sample {path} not found (../shared/data/omnimvs-samples beside the repository)")
    return path


@pytest.fixture(scope="session")
def itbt_path():
    """The real 4-camera indoor sample (3 frames, 1532x1600 gray)."""
    return _sample("itbt_sample")


@pytest.fixture(scope="session")
def sunny_path():
    """One synthetic frame of the published rig (768x800 RGB)."""
    return _sample("sunny_single")


def _find_cli():
    env = os.environ.get("OMNIMVS_CLI")
    if env:
        return Path(env)
    for profile in ("release", "debug"):
        candidate = REPO / "target" / profile / "omnimvs"
        if candidate.is_file():
            return candidate
    found = shutil.which("omnimvs")
    return Path(found) if found else None


@pytest.fixture(scope="session")
def cli():
    """Runs the `omnimvs` binary ($OMNIMVS_CLI, else target/{release,debug}/omnimvs, else on
    PATH) and returns its stdout; CI sets $OMNIMVS_CLI."""
    path = _find_cli()
    if path is None or not path.is_file():
        pytest.skip("the omnimvs binary was not found: build it or set OMNIMVS_CLI")

    def run(*args):
        done = subprocess.run(
            [str(path), *map(str, args)], capture_output=True, text=True, check=False
        )
        assert done.returncode == 0, f"omnimvs {' '.join(map(str, args))}:\n{done.stderr}"
        return done.stdout

    return run
