"""Declarations of an FMU's inputs and outputs (its parameters come from the core's Params)."""

from dataclasses import dataclass

from altfusion.estimators.health import SourceBit, Status
from altfusion.estimators.streams import stream_inputs, stream_sources
from altfusion.signals import SIGNALS


@dataclass(frozen=True)
class Input:
    """An FMI input mapped onto the core attribute of the same name; its start value is the
    core's default for that attribute."""

    name: str
    unit: str | None
    description: str
    type: type = float
    min: float | None = None
    max: float | None = None


@dataclass(frozen=True)
class Output:
    """An FMI output read from the core attribute of the same name.

    ``depends_on`` lists the inputs whose value at the end of a step enters the output at that
    instant (direct feedthrough); ``None`` means every input, ``()`` none (a state output).
    """

    name: str
    unit: str | None
    description: str
    type: type = float
    depends_on: tuple[str, ...] | None = None
    min: float | None = None
    max: float | None = None


def contract_input(name: str) -> Input:
    """An input carrying a signal of the contract, with its type, unit and description."""
    kind, unit, description = SIGNALS[name]
    return Input(name, unit, description, type=kind)


def contract_output(name: str, depends_on: tuple[str, ...] | None = None,
                    description: str | None = None) -> Output:
    """An output carrying a signal of the contract; ``description`` replaces the contract's
    where an FMU's source of the signal needs saying (a replayed log, not a sensor model)."""
    kind, unit, meaning = SIGNALS[name]
    return Output(name, unit, description or meaning, type=kind, depends_on=depends_on)


def status_description() -> str:
    """The ``status`` output's description: every bit and its meaning."""
    common = ", ".join(f"{flag.bit_length() - 1} {flag.name}" for flag in Status)
    per_source = ", ".join(f"+{bit.value} {bit.name}" for bit in SourceBit)
    per_source += " (height sources)"
    return (f"Status bit field: {common}; per source i (baro 0, gps 1, radar 2, laser 3, "
            f"gps_vz 4, acc 5) bit 8 + 4 i {per_source} (docs/estimator_health.md)")


def health_outputs(streams) -> tuple[Output, ...]:
    """The health outputs every estimator shares: h_valid, status, counters, and per source
    its test ratio and rejection count."""
    outputs = [contract_output("h_valid"),
               contract_output("status", description=status_description()),
               *(contract_output(n) for n in ("n_rejected", "n_ignored", "n_height_resets"))]
    for source in stream_sources(streams):
        outputs.append(Output(f"{source}_test_ratio", "1",
                              f"{source}: innovation² / (gate² · its variance) of the last "
                              f"sample (PX4's test ratio; > 1: rejected)"))
        outputs.append(Output(f"{source}_rejected", None,
                              f"{source}: samples rejected so far", type=int))
    return tuple(outputs)


def estimator_variables(streams, diagnostics: tuple[Output, ...] = (),
                        extra_inputs: tuple[str, ...] = ()) -> tuple:
    """Inputs of an estimator's sensor streams and its extra (stream-less) contract inputs,
    then h_est, vz_est, h_std, the health outputs and diagnostics.

    The estimate at the end of a step fuses the samples of that instant, so every output
    depends on every input (direct feedthrough)."""
    names = list(stream_inputs(streams))
    names += [name for name in extra_inputs if name not in names]
    outputs = [contract_output(n) for n in ("h_est", "vz_est", "h_std")]
    return (*(contract_input(n) for n in names), *outputs, *health_outputs(streams),
            *diagnostics)
