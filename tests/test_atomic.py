"""Atomic result files: a failing write leaves the previous file (or none) under the final
name and no temporary file."""

import numpy as np
import pytest

from altfusion.atomic import output_folder, save_figure, write_text
from altfusion.cosim.results import Results
from altfusion.errors import UsageError


class FailingFigure:
    """A figure whose rendering fails half way (as on a full disk)."""

    def savefig(self, handle, **_options):
        handle.write(b"\x89PNG half")
        raise OSError(28, "No space left on device")


def test_a_failing_figure_leaves_no_file(tmp_path):
    with pytest.raises(OSError, match="No space left"):
        save_figure(FailingFigure(), tmp_path / "plot.png")
    assert list(tmp_path.iterdir()) == []


def test_a_failing_csv_keeps_the_previous_file_whole(tmp_path, monkeypatch):
    path = tmp_path / "run.csv"
    write_text(path, "previous\n")
    results = Results(np.arange(3.0), {"a.x": np.zeros(3)})

    def full_disk(_descriptor):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("altfusion.atomic.os.fsync", full_disk)
    with pytest.raises(OSError, match="No space left"):
        results.to_csv(path)
    assert path.read_text() == "previous\n"
    assert [p.name for p in tmp_path.iterdir()] == ["run.csv"]


def test_a_csv_round_trips(tmp_path):
    results = Results(np.arange(3.0) * 0.1, {"a.x": np.array([1.0, 2.5, -3.0])}, {"a.x": "m"})
    back = Results.from_csv(results.to_csv(tmp_path / "sub" / "r.csv"))
    assert np.array_equal(back.time, results.time) and np.array_equal(back["a.x"],
                                                                       results["a.x"])
    assert back.units == {"a.x": "m"}


def test_an_output_folder_is_checked_without_being_made(tmp_path):
    """A folder that can be made is accepted and not made (a refused command leaves nothing
    behind; the first result written makes it), and nothing of the check stays; a file, or a
    folder under a file, is refused naming the option."""
    assert output_folder(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "f").write_text("")
    with pytest.raises(UsageError, match=r"^--out .*/f: a file, not a folder$"):
        output_folder(tmp_path / "f")
    with pytest.raises(UsageError, match=r"^--docs .*/f/x: cannot create the folder \(.*/f is a "
                                         r"file\)$"):
        output_folder(tmp_path / "f" / "x", "--docs")
    assert output_folder(tmp_path) == tmp_path and [p.name for p in tmp_path.iterdir()] == ["f"]
