"""Campaign storage: runs round-trip exactly, writes are atomic, leftovers are ignored."""

import numpy as np
import pytest

from altfusion.atomic import atomic_write
from altfusion.cosim.results import Results
from altfusion.montecarlo.storage import (
    MANIFEST,
    MANIFEST_FIELDS,
    DamagedManifestError,
    RunRecord,
    damaged_runs,
    failed_runs,
    finished_runs,
    read_manifest,
    read_run,
    run_path,
    write_failure,
    write_manifest,
    write_run,
)


def record(index: int, scale: float = 1.0) -> RunRecord:
    time = np.arange(5) * 0.1
    columns = {"plant.h": scale * np.sin(time), "gnss.gps_count": np.arange(5.0)}
    return RunRecord(index, {"gnss.seed": 12345 + index},
                     Results(time, columns, {"plant.h": "m", "gnss.gps_count": ""}),
                     elapsed=0.25, worker="1@host", worker_rss=1 << 20)


def test_a_run_round_trips_bit_for_bit(tmp_path):
    original = record(3, scale=np.pi)
    write_run(tmp_path, original)
    loaded = read_run(tmp_path, 3)
    assert loaded.seeds == original.seeds
    assert list(loaded.results.columns) == ["plant.h", "gnss.gps_count"]
    assert loaded.results.units == original.results.units
    assert np.array_equal(loaded.results.time, original.results.time)
    for name in original.results.columns:
        assert np.array_equal(loaded.results[name], original.results[name])
    assert (loaded.elapsed, loaded.worker, loaded.worker_rss) == (0.25, "1@host", 1 << 20)


def test_leftover_temporary_files_are_not_finished_runs(tmp_path):
    write_run(tmp_path, record(0))
    write_run(tmp_path, record(2))
    (run_path(tmp_path, 1).parent / ".run_00001.npz.abc.tmp").write_bytes(b"partial")
    write_failure(tmp_path, 4, "component 'gnss': boom")
    assert finished_runs(tmp_path) == [0, 2]
    assert failed_runs(tmp_path) == {4: "component 'gnss': boom"}


def test_a_successful_retry_clears_the_failure(tmp_path):
    write_failure(tmp_path, 1, "boom")
    write_run(tmp_path, record(1))
    assert failed_runs(tmp_path) == {}
    assert finished_runs(tmp_path) == [1]


def test_an_interrupted_write_leaves_neither_the_file_nor_a_temporary(tmp_path):
    target = tmp_path / "runs" / "run_00000.npz"

    def interrupted(handle):
        handle.write(b"half a file")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(target, interrupted)
    assert list((tmp_path / "runs").iterdir()) == []


def rewrite(path, **changes) -> None:
    """Rewrite the run file ``path`` as a valid .npz with some arrays replaced."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    arrays.update(changes)
    with open(path, "wb") as handle:
        np.savez(handle, **arrays)


@pytest.mark.parametrize("changes, reason", [
    (lambda values, time: {"values": values.astype(str)}, "values of dtype <U"),
    (lambda values, time: {"values": values.astype(np.int64)}, "values of dtype int64"),
    (lambda values, time: {"time": time.astype(str)}, "values of dtype <U"),
    (lambda values, time: {"values": values[:, 0]}, "IndexError"),
    (lambda values, time: {"values": values[:3]}, "inconsistent content"),
    (lambda values, time: {"time": time.reshape(5, 1)}, "time of shape (5, 1)"),
])
def test_resume_finds_a_valid_npz_of_the_wrong_dtype_or_shape_damaged(tmp_path, changes,
                                                                       reason):
    """``mc --resume`` re-runs what :func:`damaged_runs` reports: a run file that is a valid
    .npz but holds strings, integers or arrays of the wrong shape is damaged (the report
    would fail on it), named with what is wrong."""
    write_run(tmp_path, record(0))
    write_run(tmp_path, record(1))
    path = run_path(tmp_path, 1)
    with np.load(path, allow_pickle=False) as data:
        values, time = data["values"], data["time"]
    rewrite(path, **changes(values, time))
    damaged = damaged_runs(tmp_path)
    assert list(damaged) == [1]
    assert damaged[1].startswith("run_00001.npz: ") and reason in damaged[1]


def valid_manifest() -> dict:
    """A manifest with every field :func:`read_manifest` checks, of its type."""
    examples = {int: 1, dict: {}, str: "x", list: []}
    return {key: examples[kind] for key, kind in MANIFEST_FIELDS.items()}


def test_a_manifest_with_its_fields_reads_back(tmp_path):
    manifest = {**valid_manifest(), "stop_time": None, "extra": [1, 2]}
    write_manifest(tmp_path, manifest)
    assert read_manifest(tmp_path) == manifest


@pytest.mark.parametrize(("text", "reason"), [
    (b"{bad", "not a campaign manifest (Expecting property name"),
    (b"\xff\xfe\x00", "not a campaign manifest ("),
    (b"[1]", "(a JSON list, not an object)"),
    (b"{}", "runs (missing)"),
    (b'{"runs": "3"}', "runs (not int)"),
    (b'{"runs": true}', "runs (not int)"),
    (b'{"system": []}', "system (not dict)"),
])
def test_a_damaged_manifest_is_refused_naming_the_file(tmp_path, text, reason):
    """A manifest that is not JSON, not an object, or lacks a field the commands read (or
    has it of another type: a Boolean is not a run count) is refused naming the file and
    what is wrong, instead of a KeyError or TypeError halfway through ``report``."""
    (tmp_path / MANIFEST).write_bytes(text)
    with pytest.raises(DamagedManifestError) as error:
        read_manifest(tmp_path)
    message = str(error.value)
    assert message.startswith(f"{tmp_path / MANIFEST}: not a campaign manifest")
    assert reason in message


def test_a_folder_without_a_manifest_is_not_a_campaign(tmp_path):
    """``altfusion report`` of a folder that holds no campaign said "[Errno 2] No such file
    or directory: '.../manifest.json'"."""
    with pytest.raises(DamagedManifestError, match=r"not a campaign folder \(no manifest.json: "
                                                   r"altfusion mc or compare writes one\)"):
        read_manifest(tmp_path)
