"""The system a campaign runs, as every worker process loads it: an SSP archive identified by
its content hash, optionally with one component's FMU swapped (``altfusion compare``) and a
fault scenario inserted (``altfusion mc --fault``)."""

from dataclasses import dataclass, replace
from pathlib import Path

from altfusion.cosim.extraction import file_sha256
from altfusion.cosim.ssp import LoadedSystem, read_ssp
from altfusion.montecarlo.swap import Swap, SwapEffect, find_fmu, swap_component
from altfusion.systems.faults import FAULT_COMPONENT, FAULT_FMU, with_fault
from altfusion.systems.spec import SystemSpec


class CampaignError(RuntimeError):
    """A campaign that cannot be started, resumed or read; the message says why."""


@dataclass(frozen=True)
class SystemSource:
    """An SSP archive (absolute path, SHA-256 of its bytes), an optional FMU swap and an
    optional fault scenario (a name of :data:`altfusion.systems.faults.FAULTS`) with the
    SensorFaults FMU that applies it (``fault_fmu``, found like a swapped FMU), and the runner
    backend: "fmu" (FMI calls, the default) or "core" (the FMUs' core objects stepped
    in-process: the same numbers without the FMI overhead; ``altfusion evaluate``).

    Workers (local processes or Dask workers) read the archive from ``ssp``: on a cluster it
    must be on a file system every worker sees, at the same path.
    """

    ssp: Path
    sha256: str
    swap: Swap | None = None
    fault: str | None = None
    fault_fmu: Swap | None = None
    backend: str = "fmu"

    @classmethod
    def from_path(cls, ssp: Path, swap: Swap | None = None,
                  fault: str | None = None, backend: str = "fmu") -> "SystemSource":
        """The source of ``ssp``; with ``fault``, the scenario is checked against the system
        (ValueError) and the SensorFaults FMU located (SwapError if there is none)."""
        ssp = Path(ssp).resolve()
        if not ssp.is_file():
            raise CampaignError(f"no SSP archive at {ssp}")
        source = cls(ssp, file_sha256(ssp), swap, backend=backend)
        if fault is None:
            return source
        loaded = read_ssp(ssp)
        with_fault(loaded.spec, fault)
        located = find_fmu(FAULT_COMPONENT, FAULT_FMU, ssp, loaded.fmu_paths)
        return replace(source, fault=fault, fault_fmu=located)

    @property
    def key(self) -> tuple:
        """What identifies the simulated system (for caches and manifests)."""
        return (str(self.ssp), self.sha256, self.swap.sha256 if self.swap else None,
                self.swap.component if self.swap else None, self.fault,
                self.fault_fmu.sha256 if self.fault_fmu else None, self.backend)


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
    if source.fault is not None and source.fault_fmu is not None:
        located = source.fault_fmu
        if located.path is not None:
            if file_sha256(located.path) != located.sha256:
                raise CampaignError(f"{located.path} changed since the campaign started")
            fmu_paths[located.fmu] = located.path
        spec = with_fault(spec, source.fault)
    return PreparedSystem(spec, fmu_paths, effect, loaded)
