"""Replacing one component's FMU by another that shares its signal contract.

Interchangeable estimators read the sensor outputs they need and all write ``h_est``,
``vz_est`` and ``h_std`` (``shared/spec/signals.md``). Swapping the FMU of a component keeps
its name and step size and adapts the system to what the replacement declares:

* connections into inputs the replacement does not declare are dropped (an estimator declares
  only the sensor signals it uses);
* bound parameters it does not declare are dropped, same-named ones are kept (same name, same
  quantity, by the contract);
* recorded signals of the component that it does not output (diagnostics) are dropped;
* a connection or error metric that needs an output it lacks is an error: the system would
  not mean the same thing.
"""

from dataclasses import dataclass, replace
from pathlib import Path

from altfusion.cosim.extraction import file_sha256
from altfusion.cosim.instances import fmu_info
from altfusion.systems.spec import SystemSpec


class SwapError(ValueError):
    """The replacement FMU cannot take the component's place."""


@dataclass(frozen=True)
class Swap:
    """Component ``component`` runs FMU ``fmu`` (a model name) instead of its own.

    ``path`` is None when the FMU is one of the SSP's own resources, else an FMU file that
    every worker can read; ``sha256`` identifies the file's content.
    """

    component: str
    fmu: str
    path: Path | None
    sha256: str


@dataclass(frozen=True)
class SwapEffect:
    """What the swap removed from the system, for the record."""

    dropped_connections: tuple[str, ...] = ()
    dropped_parameters: tuple[str, ...] = ()
    dropped_recordings: tuple[str, ...] = ()


def find_fmu(component: str, name: str, ssp: Path, ssp_fmus: dict[str, Path]) -> Swap:
    """The swap to FMU ``name``: an FMU inside the SSP, else ``<name>.fmu`` next to the SSP,
    else ``name`` as a path to an ``.fmu`` file."""
    if name in ssp_fmus:
        return Swap(component, name, None, file_sha256(ssp_fmus[name]))
    candidates = [Path(ssp).resolve().parent / f"{name}.fmu"]
    if name.endswith(".fmu"):
        candidates.append(Path(name).resolve())
    for path in candidates:
        if path.is_file():
            return Swap(component, fmu_info(path).model_name, path, file_sha256(path))
    raise SwapError(f"no FMU '{name}' inside {Path(ssp).name} or at "
                    f"{', '.join(str(p) for p in candidates)}")


def swap_component(system: SystemSpec, fmu_paths: dict[str, Path], swap: Swap,
                   ) -> tuple[SystemSpec, dict[str, Path], SwapEffect]:
    """``system`` with ``swap.component`` running ``swap.fmu``; new FMU paths; what was dropped."""
    path = fmu_paths.get(swap.fmu) if swap.path is None else swap.path
    if path is None:
        raise SwapError(f"the SSP holds no FMU '{swap.fmu}'")
    if swap.path is not None and swap.fmu in fmu_paths and \
            file_sha256(fmu_paths[swap.fmu]) != swap.sha256:
        raise SwapError(f"{swap.path} is another build of the SSP's own {swap.fmu}.fmu; one "
                        f"process cannot load two builds of one FMU: use the SSP's")
    variables = fmu_info(path).variables
    component = system.component(swap.component)
    prefix = f"{swap.component}."

    def declares(path_: str, causality: str) -> bool:
        var = variables.get(path_[len(prefix):])
        return var is not None and var.causality == causality

    kept_connections, dropped_connections = [], []
    for connection in system.connections:
        if connection.start.startswith(prefix) and not declares(connection.start, "output"):
            raise SwapError(f"{swap.fmu} has no output '{connection.start[len(prefix):]}', "
                            f"which drives '{connection.end}'")
        if connection.end.startswith(prefix) and not declares(connection.end, "input"):
            dropped_connections.append(f"{connection.start} -> {connection.end}")
        else:
            kept_connections.append(connection)
    for metric in system.metrics:
        for signal in (metric.estimate, metric.truth):
            if signal.startswith(prefix) and not declares(signal, "output"):
                raise SwapError(f"{swap.fmu} has no output '{signal[len(prefix):]}', which "
                                f"error metric '{metric.name}' needs")
    parameters = {k: v for k, v in component.parameters.items()
                  if k in variables and variables[k].causality == "parameter"}
    record = tuple(s for s in system.record if not s.startswith(prefix) or declares(s, "output"))
    swapped = replace(component, fmu=swap.fmu, parameters=parameters)
    effect = SwapEffect(
        tuple(dropped_connections),
        tuple(sorted(set(component.parameters) - set(parameters))),
        tuple(s for s in system.record if s not in record),
    )
    system = replace(system, components=tuple(swapped if c.name == component.name else c
                                              for c in system.components),
                     connections=tuple(kept_connections), record=record)
    return system, {**fmu_paths, swap.fmu: Path(path)}, effect
