"""The system a campaign runs, as every worker process loads it: an SSP archive identified by
its content hash, optionally with one component's FMU swapped (``altfusion compare``)."""

from dataclasses import dataclass
from pathlib import Path

from altfusion.cosim.ssp import LoadedSystem, read_ssp
from altfusion.cosim.system import SystemSpec
from altfusion.montecarlo.swap import Swap, SwapEffect, file_sha256, swap_component


class CampaignError(RuntimeError):
    """A campaign that cannot be started, resumed or read; the message says why."""


@dataclass(frozen=True)
class SystemSource:
    """An SSP archive (absolute path, SHA-256 of its bytes) and an optional FMU swap.

    Workers (local processes or Dask workers) read the archive from ``ssp``: on a cluster it
    must be on a file system every worker sees, at the same path.
    """

    ssp: Path
    sha256: str
    swap: Swap | None = None

    @classmethod
    def from_path(cls, ssp: Path, swap: Swap | None = None) -> "SystemSource":
        ssp = Path(ssp).resolve()
        if not ssp.is_file():
            raise CampaignError(f"no SSP archive at {ssp}")
        return cls(ssp, file_sha256(ssp), swap)

    @property
    def key(self) -> tuple:
        """What identifies the simulated system (for caches and manifests)."""
        return (str(self.ssp), self.sha256, self.swap.sha256 if self.swap else None,
                self.swap.component if self.swap else None)


@dataclass
class PreparedSystem:
    """A loaded source: the system to simulate and its FMU files."""

    spec: SystemSpec
    fmu_paths: dict[str, Path]
    swap_effect: SwapEffect
    loaded: LoadedSystem
    """Keeps the folder the SSP's FMUs were extracted to alive."""


def load_system(source: SystemSource) -> PreparedSystem:
    """Read the SSP, check it is the archive the campaign was started with, apply the swap."""
    if not source.ssp.is_file():
        raise CampaignError(f"no SSP archive at {source.ssp} (on a cluster, every worker must "
                            f"see the archive at the same path)")
    if file_sha256(source.ssp) != source.sha256:
        raise CampaignError(f"{source.ssp} changed since the campaign started "
                            f"(SHA-256 {source.sha256[:12]}...)")
    loaded = read_ssp(source.ssp)
    spec, fmu_paths, effect = loaded.spec, dict(loaded.fmu_paths), SwapEffect()
    if source.swap is not None:
        if source.swap.path is not None and file_sha256(source.swap.path) != source.swap.sha256:
            raise CampaignError(f"{source.swap.path} changed since the campaign started")
        spec, fmu_paths, effect = swap_component(spec, fmu_paths, source.swap)
    return PreparedSystem(spec, fmu_paths, effect, loaded)
