"""System tests run whole systems of built FMUs through fmpy: build them first
(``python build_fmu.py``); these fixtures refuse stale or missing FMUs."""

import sys
from pathlib import Path

import pytest

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
