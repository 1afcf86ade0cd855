"""A campaign: N seeded runs of one system, described once for the workers (``CampaignTask``)
and once on disk (the manifest, which ``--resume`` checks before adding runs)."""

import dataclasses
import json
import platform
from dataclasses import dataclass
from datetime import datetime, timezone
from importlib import metadata
from typing import Any

from altfusion.cosim.instances import check_core_version, fmu_info
from altfusion.cosim.runner import recorded_columns, recording_size
from altfusion.errors import ParameterError
from altfusion.montecarlo.seeds import SEED_PARAMETER, run_seeds, seeded_components
from altfusion.montecarlo.source import CampaignError, PreparedSystem, SystemSource, load_system
from altfusion.version import CORE_VERSION

MANIFEST_FORMAT = 1
PACKAGES = ("numpy", "scipy", "matplotlib", "fmpy", "pythonfmu", "control", "distributed")
IDENTITY = ("ssp_sha256", "swap", "master_seed", "stop_time", "parameters")
"""Manifest entries that must match for a campaign to be resumed."""


@dataclass(frozen=True)
class CampaignTask:
    """Everything a worker needs to execute any run of the campaign."""

    source: SystemSource
    master_seed: int
    stop_time: float
    parameters: tuple[tuple[str, Any], ...]
    """Parameter overrides ('component.parameter', value) common to every run."""
    seeded: tuple[str, ...]
    """Components that receive a derived seed."""

    def seeds(self, index: int) -> dict[str, int]:
        """The derived seeds of run ``index``: {'component.seed': seed}."""
        return run_seeds(self.master_seed, index, self.seeded)


def plan(source: SystemSource, master_seed: int = 0, stop_time: float | None = None,
         parameters: dict[str, Any] | None = None) -> tuple[CampaignTask, PreparedSystem]:
    """Load the system once in this process (no FMU is instantiated) and describe the task."""
    if master_seed < 0:
        raise CampaignError(f"--seed {master_seed}: the master seed must be >= 0")
    prepared = load_system(source)
    for path in prepared.fmu_paths.values():
        check_core_version(fmu_info(path))
    seeded = seeded_components(prepared.spec, prepared.fmu_paths)
    parameters = dict(parameters or {})
    clashes = sorted(p for p in parameters if p in {f"{c}.{SEED_PARAMETER}" for c in seeded})
    if clashes:
        raise CampaignError(f"{', '.join(clashes)}: seeds are derived per run from the master "
                            f"seed (--seed); they cannot be set")
    stop = prepared.spec.stop_time if stop_time is None else float(stop_time)
    given = f"--stop {stop:g}" if stop_time is not None else f"stop time {stop:g} s"
    try:
        recording_size(prepared.spec, stop, recorded_columns(prepared.spec, prepared.fmu_paths))
    except ParameterError as error:
        raise CampaignError(f"{given}: {error.reason}") from None
    if stop <= prepared.spec.start_time:
        raise CampaignError(f"{given}: must be after the start time "
                            f"({prepared.spec.start_time:g} s): a run of no duration has only "
                            f"its initial values, no statistics")
    task = CampaignTask(source, master_seed, stop, tuple(sorted(parameters.items())), seeded)
    return task, prepared


def package_versions() -> dict[str, str]:
    versions = {"python": platform.python_version(), "altfusion core": CORE_VERSION}
    for name in PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


def build_manifest(task: CampaignTask, prepared: PreparedSystem, runs: int) -> dict[str, Any]:
    """The manifest of a campaign of ``runs`` runs (JSON-ready)."""
    spec, swap = prepared.spec, task.source.swap
    versions = package_versions()
    created = datetime.now(timezone.utc).isoformat(timespec="seconds")
    manifest = {
        "format": MANIFEST_FORMAT,
        "system": dataclasses.asdict(spec),
        "ssp": str(task.source.ssp),
        "ssp_sha256": task.source.sha256,
        "swap": None if swap is None else {"component": swap.component, "fmu": swap.fmu,
                                           "path": str(swap.path) if swap.path else None,
                                           "sha256": swap.sha256},
        "swap_effect": dataclasses.asdict(prepared.swap_effect),
        "runs": runs,
        "master_seed": task.master_seed,
        "stop_time": task.stop_time,
        "parameters": dict(task.parameters),
        "seeded_components": list(task.seeded),
        "recorded": list(spec.record),
        "metrics": [dataclasses.asdict(m) for m in spec.metrics],
        "versions": versions,
        "created": created,
        "sessions": [{"started": created, "versions": versions}],
    }
    return json.loads(json.dumps(manifest))


def check_same_campaign(stored: dict[str, Any], new: dict[str, Any]) -> None:
    """Refuse a manifest of another system or other settings than ``new``."""
    if stored.get("format") != MANIFEST_FORMAT:
        raise CampaignError(f"manifest format {stored.get('format')!r} is not "
                            f"{MANIFEST_FORMAT}")
    differences = [f"{key}: campaign has {stored.get(key)!r}, now {new[key]!r}"
                   for key in IDENTITY if stored.get(key) != new[key]]
    if differences:
        raise CampaignError("not the same campaign:\n  " + "\n  ".join(differences))


def check_resumable(stored: dict[str, Any], new: dict[str, Any]) -> None:
    """Refuse to add runs to a campaign that was started with another system or settings."""
    try:
        check_same_campaign(stored, new)
    except CampaignError as error:
        raise CampaignError(f"cannot resume: {error}") from None
    if new["runs"] < stored["runs"]:
        raise CampaignError(f"cannot resume with -n {new['runs']}: the campaign has "
                            f"{stored['runs']} runs (resume without -n, or with more runs)")
