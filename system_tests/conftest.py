"""System tests run whole systems of built FMUs through fmpy: build them first
(``python build_fmu.py``); these fixtures refuse stale or missing FMUs."""

import importlib.util
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from algorithms import ALGORITHMS, PAPER_ALGORITHM
from omsimulator import OMSimulator, unpack

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
sys.path.insert(0, str(ROOT))

import build_fmu  # noqa: E402


@pytest.fixture(scope="session")
def fmus() -> dict[str, Path]:
    """Built FMUs by model name; fails if any is missing or older than its sources."""
    if build_fmu.main(["--check"]) != 0:
        pytest.fail("FMUs are missing or out of date: run python build_fmu.py")
    return {path.stem: path for path in MODELS.glob("*.fmu")}


@pytest.fixture(scope="session")
def ssp_files(fmus) -> dict[str, Path]:
    """Built SSP archives by system name."""
    return {path.stem: path for path in MODELS.glob("*.ssp")}


REPRODUCE_WORKERS = 1
"""Worker processes of each ``altfusion reproduce`` run: one, since pytest-xdist already keeps
every core busy (two workers each on CI's two cores only added their start-ups); several
workers giving the same numbers is test_montecarlo.py's."""


@pytest.fixture(scope="session")
def reproduce_cli(fmus) -> Callable[[str, int, Path, str], str]:
    """``altfusion reproduce NAME -n RUNS --out OUT`` in a subprocess on the built models,
    :data:`REPRODUCE_WORKERS` workers, with ``--paper-algorithm`` for
    :data:`PAPER_ALGORITHM`; returns its standard output (fails the test with its error
    output otherwise)."""
    def run(name: str, runs: int, out: Path, algorithm: str = ALGORITHMS[0]) -> str:
        completed = subprocess.run(
            [sys.executable, "-m", "altfusion.cli", "reproduce", name, "-n", str(runs),
             "--workers", str(REPRODUCE_WORKERS), "--models", str(MODELS), "--out", str(out),
             *(["--paper-algorithm"] if algorithm == PAPER_ALGORITHM else [])],
            capture_output=True, text=True, timeout=600, cwd=ROOT)
        assert completed.returncode == 0, completed.stderr[-3000:]
        return completed.stdout
    return run


def repository_folders() -> list[Path]:
    """This checkout and, for a git worktree, the main checkout its repository lives in."""
    common = subprocess.run(["git", "rev-parse", "--path-format=absolute", "--git-common-dir"],
                            cwd=ROOT, capture_output=True, text=True, check=False)
    main = [Path(common.stdout.strip()).parent] if common.returncode == 0 else []
    return [ROOT, *(folder for folder in main if folder != ROOT)]


OMSIMULATOR_FOLDERS = [folder.parent / "shared" / "tools" / "omsimulator"
                       for folder in repository_folders()]
"""Where the prebuilt OMSimulator archive is looked for: ``../shared/tools/omsimulator``
beside the repository (CI clones it there)."""


@pytest.fixture(scope="session")
def omsimulator(fmus, tmp_path_factory) -> OMSimulator:
    """OMSimulator, unpacked once per session (per xdist worker) into a temporary folder;
    skipped, naming where it was looked for, if no archive is there."""
    archives = next((found for folder in OMSIMULATOR_FOLDERS
                     if (found := sorted(folder.glob("*.tgz")))), [])
    if not archives:
        pytest.skip("OMSimulator is not available: no *.tgz in "
                    f"{' or '.join(map(str, OMSIMULATOR_FOLDERS))}")
    if importlib.util.find_spec("lxml") is None:
        pytest.fail("OMSimulator's Python API needs lxml: pip install -e '.[test]'")
    return unpack(archives, tmp_path_factory.mktemp("omsimulator"))
