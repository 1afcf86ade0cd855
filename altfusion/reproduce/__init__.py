"""Paper reproductions: ``altfusion reproduce NAME`` runs a paper's simulation section as Monte
Carlo campaigns of catalog systems (models/*.ssp) and writes the paper's figures' equivalents
and a table of the paper's numbers beside ours.

Each reproduction is a module ``altfusion.reproduce.<name>`` with ``DEFAULT_RUNS`` (the
paper's Monte Carlo size) and ``reproduce(options: ReproduceOptions) -> int``.
"""

import importlib
from dataclasses import dataclass
from pathlib import Path

REPRODUCTIONS = ("whang2008", "hajiyev", "bao2017", "yang2020", "xu2016")


@dataclass(frozen=True)
class ReproduceOptions:
    """What the command line gives a reproduction."""

    out: Path
    """Output folder (campaigns, figures, table)."""
    runs: int | None = None
    """Monte Carlo runs; None: the paper's number (``DEFAULT_RUNS``)."""
    workers: int | None = None
    scheduler: str | None = None
    master_seed: int = 0
    resume: bool = False
    models: Path = Path("models")
    """Folder holding the built FMUs and SSP files."""
    paper_algorithm: bool = False
    """Every estimator with ``fault_detection`` false: the papers' algorithms, without the
    shared health machinery's resets, isolation and bias states."""
    backend: str = "core"
    """The runner's backend: "core" (the FMUs' core objects stepped in-process, as
    ``altfusion evaluate`` does: the same numbers, faster) or "fmu" (every call through
    FMI)."""


def reproduction(name: str):
    """The module of reproduction ``name``."""
    if name not in REPRODUCTIONS:
        raise KeyError(f"unknown reproduction {name!r}; known: {', '.join(REPRODUCTIONS)}")
    return importlib.import_module(f"altfusion.reproduce.{name}")
