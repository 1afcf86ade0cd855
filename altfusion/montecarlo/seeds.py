"""Per-run, per-component seeds derived from one master seed.

Run ``i`` of a campaign with master seed ``M`` gives component ``c`` the seed drawn from
``numpy.random.SeedSequence([M, i, crc32(c)])``. The seed depends on nothing else (not the
number of runs, the worker or the order of execution), so any run can be re-run alone, a
campaign of 10 runs is the first 10 runs of a campaign of 1000, and a component keeps its
noise realization when another component of the system is swapped (``altfusion compare``).
The component name is hashed with CRC-32, which is stable across processes and machines
(Python's ``hash()`` of a string is salted per process).
"""

import zlib
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from altfusion.cosim.instances import fmu_info
from altfusion.systems.spec import SystemSpec

SEED_PARAMETER = "seed"
"""The Integer parameter through which a component receives its seed."""

SEED_MAX = 2**31 - 1
"""FMI 2.0 Integers are 32-bit signed: derived seeds lie in [0, SEED_MAX]."""


def name_key(component: str) -> int:
    """A stable 32-bit integer for a component name (CRC-32 of its UTF-8 bytes)."""
    return zlib.crc32(component.encode("utf-8"))


def derived_seed(master_seed: int, run: int, component: str) -> int:
    """The seed of ``component`` in run ``run`` of a campaign with ``master_seed``."""
    if master_seed < 0 or run < 0:
        raise ValueError(f"master seed and run index must be >= 0, got {master_seed}, {run}")
    sequence = np.random.SeedSequence([master_seed, run, name_key(component)])
    return int(sequence.generate_state(1, dtype=np.uint32)[0] >> 1)


def seeded_components(system: SystemSpec, fmu_paths: dict[str, Path]) -> tuple[str, ...]:
    """Names of the components whose FMU declares an Integer parameter ``seed``."""
    names = []
    for component in system.components:
        var = fmu_info(fmu_paths[component.fmu]).variables.get(SEED_PARAMETER)
        if var is not None and var.causality == "parameter" and var.type == "Integer":
            names.append(component.name)
    return tuple(names)


def run_seeds(master_seed: int, run: int, components: Iterable[str]) -> dict[str, int]:
    """Parameter overrides {'component.seed': seed} for run ``run``."""
    return {f"{name}.{SEED_PARAMETER}": derived_seed(master_seed, run, name)
            for name in components}
