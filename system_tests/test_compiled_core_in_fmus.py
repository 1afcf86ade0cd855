"""Every FMU's private core carries the compiled core modules (Kalman steps, machinery) for
the build's interpreter and steps on them in a host of that interpreter; with
``ALTFUSION_PURE_PYTHON`` set, on the sources (:mod:`altfusion.compiled`). That the FMUs'
outputs are the same bits as the sources' is system_tests/test_output_checksums.py's (its
checksums were recorded before anything was compiled).

Each host is a fresh interpreter, as a user's is: fmpy simulates the FMU of YangFusionKF (its
extraction folder deleted afterwards, as fmpy does) and reports which file its core's
``kalman`` module was loaded from.
"""

import json
import os
import subprocess
import sys
import textwrap
import zipfile

import pytest

from altfusion.compiled import COMPILED, FOLDER, MANIFEST, PURE_PYTHON

HOST = """
    import json, sys
    import numpy as np
    from fmpy import simulate_fmu
    result = simulate_fmu({path!r}, stop_time=2.0, output_interval=0.01,
                          start_values={{"baro_h": 12.5, "baro_time": 0.0, "baro_count": 1}})
    values = np.array([list(row) for row in result], dtype=float)
    [kalman] = [m.__file__ for name, m in sys.modules.items()
                if name.startswith("altfusion_") and name.endswith(".estimators.kalman")]
    print(json.dumps({{"kalman": kalman, "finite": bool(np.isfinite(values).all())}}))
"""


def host(path: str, pure: bool) -> dict:
    environment = {**os.environ, PURE_PYTHON: "1" if pure else ""}
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(HOST.format(path=path))],
                          env=environment, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_every_fmu_bundles_the_compiled_modules_for_the_build_interpreter(fmus):
    """Each FMU's private core holds, for every compiled module, its extension module for
    this interpreter and a manifest naming this interpreter."""
    tag = sys.implementation.cache_tag
    for path in fmus.values():
        with zipfile.ZipFile(path) as archive:
            names = archive.namelist()
            for package, modules in COMPILED.items():
                folder = [n.rpartition("/")[0] for n in names
                          if n.endswith(f"/{package}/{FOLDER}/{MANIFEST}")]
                assert len(folder) == 1, (path.name, folder)
                manifest = json.loads(archive.read(f"{folder[0]}/{MANIFEST}"))
                assert manifest["cache_tag"] == tag
                assert sorted(manifest["sources"]) == sorted(f"{m}.py" for m in modules)
                for module in modules:
                    assert any(n.startswith(f"{folder[0]}/{module}.{tag}") for n in names), \
                        (path.name, module)


@pytest.mark.parametrize("pure", [False, True])
def test_an_fmu_steps_on_the_compiled_modules_unless_told_not_to(fmus, pure):
    found = host(str(fmus["YangFusionKF"]), pure)
    assert found["finite"]
    assert found["kalman"].endswith(".py" if pure else ".so"), found["kalman"]

