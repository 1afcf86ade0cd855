"""``python -m altfusion.interop``'s answer to a bad system file: one line, no traceback."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("content, said", [(None, "no such file"),
                                           (b"not a zip", "not a valid SSP archive")])
def test_a_bad_system_file_is_one_line_and_status_2(tmp_path, content, said):
    ssp = tmp_path / "system.ssp"
    if content is not None:
        ssp.write_bytes(content)
    done = subprocess.run([sys.executable, "-m", "altfusion.interop", "run", "--engine", "ecos",
                           str(ssp), "--csv", str(tmp_path / "out.csv")],
                          capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 2
    assert done.stderr.startswith("error: ") and said in done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out.csv").exists()
