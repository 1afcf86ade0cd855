"""altfusion: barometer/GPS altitude estimation components for co-simulation.

The core numerics (``physics``, ``sensors``, ``estimators``) are plain Python + numpy and
import no FMI code. FMI lives at three edges:

* ``altfusion.fmi``: the pythonfmu adapter base every FMU's slave script builds on;
* ``altfusion.cosim``: our multi-rate runner on fmpy and the SSP reader/writer of the
  plain-data system descriptions of ``altfusion.systems`` (which import no FMI library);
* ``altfusion.interop``: third-party engines (libcosim, ECOS), OSP export, FMU containers and
  compliance checks (the ``interop`` extra, imported only when used).

The import contracts in ``pyproject.toml`` (checked by ``tests/test_architecture.py``) enforce
this.
"""

from importlib import import_module

from altfusion.version import BUNDLE, CORE_VERSION, __version__

__all__ = ["CORE_VERSION", "__version__"]

if BUNDLE:  # a private copy inside an FMU: load all of it while its folder exists
    for _module in BUNDLE["modules"]:
        import_module(f"{__name__}.{_module}")
