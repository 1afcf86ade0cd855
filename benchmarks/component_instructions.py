"""Instructions per step of each plant, atmosphere, controller, sensor and fault core object,
stepped alone, counted by valgrind (callgrind).

    python benchmarks/component_instructions.py [NAME,NAME...] [--base /tmp/base]

Each component is built with its default parameters but those of :data:`CASES` (a sample at
every step, so that the figure is the cost of a sample) and given constant inputs, then
stepped ``do_step`` by ``do_step`` on its own tick; two processes step it 500 and 2500 times
and the difference of their counts divided by 2000 is the cost of a step, start-up removed
(the loop and its tick times included, ~1,000 instructions). As in
``instructions_per_step.py``: ``PYTHONHASHSEED`` fixed, OpenBLAS on one thread, address-space
randomization off where ``setarch`` runs. ``--base``: the root of another checkout whose
``altfusion`` is counted instead (e.g. ``git worktree add --detach /tmp/base 0ac13b4``).
"""

import argparse
from pathlib import Path

from instructions_per_step import callgrind_count

ROOT = Path(__file__).resolve().parents[1]

CASES = {
    "plant": ("altfusion.physics.vertical_dynamics:VerticalDynamics", {}, {"thrust": 15.0},
              0.01),
    "atmosphere": ("altfusion.physics.atmosphere:Atmosphere",
                   {"gust_std": 1.0, "lapse_rate_std": 0.003}, {"h": 100.0}, 0.01),
    "controller": ("altfusion.physics.flight_controller:FlightController", {},
                   {"h_fb": 1.0, "vz_fb": 0.1}, 0.01),
    "air_data": ("altfusion.sensors.air_data:AirDataModule", {"sample_period": 0.01},
                 {"p_static": 100000.0, "T_air": 288.0, "wind_speed": 2.0}, 0.01),
    "accelerometer": ("altfusion.sensors.accelerometer:Accelerometer", {}, {"az": 0.1}, 0.01),
    "gnss": ("altfusion.sensors.gnss:GnssReceiver", {"sample_period": 0.1},
             {"h": 10.0, "vz": 0.1}, 0.1),
    "laser": ("altfusion.sensors.laser:LaserRangefinder", {}, {"h": 10.0}, 0.01),
    "radar": ("altfusion.sensors.radio_altimeter:RadioAltimeter", {}, {"h": 10.0}, 0.2),
    "faults": ("altfusion.sensors.faults:SensorFaults",
               {"scenario": "baro_step", "fault_start": 1.0}, {"h": 10.0}, 0.01),
}
"""name: (core class, parameters, inputs, step). ``faults`` gets a new baro and accelerometer
sample at every step (their raw counts rise)."""

STEP = """
import importlib, sys
from dataclasses import replace
from altfusion.timegrid import TickClock
path, params, inputs, step = {case!r}
module, name = path.split(":")
cls = getattr(importlib.import_module(module), name)
core = cls(replace(cls.Params(), **params), step_size=step, inputs=inputs)
grid = TickClock(step)
fresh = {faults!r}
for n in range(int(sys.argv[1])):
    if fresh:
        core.raw_baro_count = core.raw_acc_count = n + 1
    core.do_step(grid.time(n), step)
"""


def instructions(name: str, steps: int, root: Path) -> int:
    """Instructions of a whole process that builds component ``name`` and steps it."""
    code = STEP.format(case=CASES[name], faults=name == "faults")
    return callgrind_count(code, str(steps), env={"PYTHONPATH": str(root)},
                           cwd=root)                     # and run in root: sys.path[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="?", default=",".join(CASES),
                        help=f"comma-separated, of {', '.join(CASES)} (default: all)")
    parser.add_argument("--base", type=Path, default=ROOT,
                        help="root of the checkout whose altfusion is counted")
    args = parser.parse_args()
    for name in args.names.split(","):
        per_step = (instructions(name, 2500, args.base) - instructions(name, 500, args.base))
        print(f"{name}: {per_step / 2000:,.0f} instructions per step", flush=True)


if __name__ == "__main__":
    main()
