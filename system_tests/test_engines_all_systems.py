"""Every ``models/*.ssp`` loaded and run one after another in a single libcosim process and in
a single ECOS process (issue 14): each FMU's private core copy, and the native shim releasing
pythonfmu's state before an engine unloads an FMU, make a process survive any sequence of our
systems. Short runs (``STOP`` s each), one subprocess per engine.

Each run must complete with finite outputs. The one exception is libcosim's documented
observer gap: it has no t = 0 value for a Boolean output of a component at the base step
(``engines.run_libcosim``), so such a cell of the first row may be NaN, and no other."""

import importlib.util
import json
import subprocess
import sys

import pytest
from conftest import ROOT

if not all(importlib.util.find_spec(name) for name in ("libcosimpy", "ecospy")):
    pytest.skip("the interop extra is not installed", allow_module_level=True)

STOP = 2.0
"""Simulated seconds per system: every system's sensors deliver samples within 1 s."""

ALL_SYSTEMS = """
import json, sys
from pathlib import Path
import numpy as np
from altfusion.cosim.instances import fmu_info
from altfusion.cosim.ssp import read_ssp
from altfusion.interop.__main__ import run_engine

engine, stop = sys.argv[1], float(sys.argv[2])
for ssp in sys.argv[3:]:
    try:
        results = run_engine(engine, Path(ssp), stop)
    except Exception as error:
        print(json.dumps({"ssp": Path(ssp).name, "error": repr(error)}), flush=True)
        continue
    loaded = read_ssp(Path(ssp))
    fmus = {c.name: fmu_info(loaded.fmu_paths[c.fmu]) for c in loaded.spec.components}
    bad = []
    for name, values in results.columns.items():
        component, _, variable = name.partition(".")
        kind = fmus[component].variables[variable].type
        rows = np.flatnonzero(~np.isfinite(np.asarray(values, dtype=float)))
        bad += [[name, kind, int(row)] for row in rows[:3]]
    print(json.dumps({"ssp": Path(ssp).name, "rows": len(results.time),
                      "end": float(results.time[-1]), "non_finite": bad}), flush=True)
"""


@pytest.mark.parametrize("engine", ["libcosim", "ecos"])
def test_every_system_runs_one_after_another_in_one_engine_process(ssp_files, engine):
    systems = sorted(ssp_files.values())
    done = subprocess.run(
        [sys.executable, "-c", ALL_SYSTEMS, engine, str(STOP), *map(str, systems)],
        capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert done.returncode == 0, (done.returncode, done.stderr[-3000:])
    reports = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    assert [r["ssp"] for r in reports] == [p.name for p in systems], done.stderr[-3000:]
    for report in reports:
        assert "error" not in report, report
        assert report["rows"] >= 2 and report["end"] == pytest.approx(STOP), report
        allowed = [cell for cell in report["non_finite"]
                   if engine == "libcosim" and cell[1] == "Boolean" and cell[2] == 0]
        assert report["non_finite"] == allowed, report
