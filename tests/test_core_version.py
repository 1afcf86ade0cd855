"""The runner refuses FMUs built from another core version."""

from pathlib import Path

import pytest

from altfusion import CORE_VERSION
from altfusion.cosim.instances import CosimError, FmuInfo, check_core_version
from altfusion.version import source_digest


def info(version: str) -> FmuInfo:
    return FmuInfo(Path("X.fmu"), "X", "guid", version, None, {}, frozenset())


def test_same_core_version_is_accepted():
    check_core_version(info(CORE_VERSION))


def test_other_core_version_is_refused_with_the_remedy():
    with pytest.raises(CosimError, match="built from altfusion core 0.0.1\\+abc.*python build_fmu"):
        check_core_version(info("0.0.1+abc"))


def test_core_version_tracks_the_source(tmp_path):
    (tmp_path / "a.py").write_text("x = 1\n")
    before = source_digest(tmp_path)
    (tmp_path / "a.py").write_text("x = 2\n")
    assert source_digest(tmp_path) != before
