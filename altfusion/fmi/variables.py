"""Declarations of an FMU's inputs and outputs (its parameters come from the core's Params)."""

from dataclasses import dataclass, replace

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

    No output of ours depends directly on an input in FMI's sense: outputs change only in
    doStep, so ModelStructure/Outputs declares none. What the FMU declares instead:

    * ``initial_depends_on``: the inputs its value in Initialization Mode follows (the core is
      rebuilt from the inputs set there), written to ModelStructure/InitialUnknowns;
    * ``reads_at_step_end``: the inputs whose value at the end of a step enters the output at
      that instant (a sensor samples its input then); ``None`` means every input, ``()`` none.
      Written to our VendorAnnotation: our runner gives these inputs the source's value at the
      end of the step (stepping sources first); FMI hosts hold inputs from the step's start.
    """

    name: str
    unit: str | None
    description: str
    type: type = float
    reads_at_step_end: tuple[str, ...] | None = None
    min: float | None = None
    max: float | None = None
    initial_depends_on: tuple[str, ...] = ()


def contract_input(name: str) -> Input:
    """An input carrying a signal of the contract, with its type, unit and description."""
    kind, unit, description = SIGNALS[name]
    return Input(name, unit, description, type=kind)


def contract_output(name: str, reads_at_step_end: tuple[str, ...] | None = None,
                    description: str | None = None,
                    initial_depends_on: tuple[str, ...] = ()) -> Output:
    """An output carrying a signal of the contract; ``description`` replaces the contract's
    where an FMU's source of the signal needs saying (a replayed log, not a sensor model)."""
    kind, unit, meaning = SIGNALS[name]
    return Output(name, unit, description or meaning, type=kind,
                  reads_at_step_end=reads_at_step_end, initial_depends_on=initial_depends_on)


def status_description() -> str:
    """The ``status`` output's description: every bit and its meaning."""
    common = ", ".join(f"{flag.bit_length() - 1} {flag.name}" for flag in Status)
    which = {SourceBit.ISOLATED: " (height sources)", SourceBit.NOISE_INFLATED: " (not acc)"}
    per_source = ", ".join(f"+{bit.value} {bit.name}{which.get(bit, '')}" for bit in SourceBit)
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
                        extra_inputs: tuple[str, ...] = (),
                        initial_depends_on: dict[str, tuple[str, ...]] | None = None) -> tuple:
    """Inputs of an estimator's sensor streams and its extra (stream-less) contract inputs,
    then h_est, vz_est, h_std, the health outputs and diagnostics.

    The estimate at the end of a step fuses the samples of that instant, so every output reads
    every input at the step's end; ``initial_depends_on`` names, per common output, the inputs
    its value in Initialization Mode follows (an estimate started from the held sample)."""
    initial = initial_depends_on or {}
    names = list(stream_inputs(streams))
    names += [name for name in extra_inputs if name not in names]
    outputs = [contract_output(n) for n in ("h_est", "vz_est", "h_std")]
    common = [replace(o, initial_depends_on=initial.get(o.name, ()))
              for o in (*outputs, *health_outputs(streams))]
    unknown = set(initial) - {o.name for o in common}
    if unknown:
        raise ValueError(f"initial_depends_on names outputs that are not common: {unknown}")
    return (*(contract_input(n) for n in names), *common, *diagnostics)
