"""The plant system (VerticalDynamics + Atmosphere + FlightController) through fmpy."""

import math
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.ssp.ssd import read_ssd
from fmpy.validation import validate_fmu
from state_restore import assert_restores_identically

from altfusion.cosim import CosimError, Simulation, read_ssp, simulate
from altfusion.cosim.instances import FmuInstance, fmu_info
from altfusion.systems import SYSTEMS, build_system
from altfusion.systems.spec import ComponentSpec, Connection, SystemSpec


def test_every_fmu_passes_fmpy_validate(fmus):
    assert fmus, "no FMUs built"
    for path in fmus.values():
        assert validate_fmu(str(path)) == [], path.name


def as_written(system, fmus):
    """``system`` as its SSP binds it: without the String parameters equal to the FMU's
    default, which the writer leaves out (OMSimulator's command line cannot set a String)."""
    def written(component):
        variables = read_model_description(str(fmus[component.fmu])).modelVariables
        defaults = {v.name: v.start for v in variables if v.type == "String"}
        return replace(component, parameters={
            name: value for name, value in component.parameters.items()
            if not (isinstance(value, str) and defaults.get(name) == value)})
    return replace(system, components=tuple(written(c) for c in system.components))


def test_every_ssp_validates_against_the_ssp_schema_and_reads_back(ssp_files, fmus):
    assert set(ssp_files) == set(SYSTEMS)
    for name, path in ssp_files.items():
        read_ssd(str(path), validate=True)
        assert read_ssp(path).spec == as_written(build_system(name), fmus)


@pytest.fixture(scope="module")
def yang_run(fmus):
    return simulate(build_system("plant_yang2020"), fmus)


def test_seed_003_profile_is_flown(yang_run):
    """yang2020 Section 4.1: climb rate peaks at 12 m/s, ±0.2 m/s² phases at their times."""
    r, t = yang_run, yang_run.time
    assert r["plant.vz"].max() == pytest.approx(12.0, abs=1e-3)
    assert r["plant.vz"].min() == pytest.approx(-12.0, abs=1e-3)
    phases = [(1, 59, 0.2), (61, 119, 0.0), (121, 179, -0.2), (181, 239, 0.0),
              (241, 299, -0.2), (301, 359, 0.0), (361, 419, 0.2)]
    for start, end, accel in phases:
        window = (t >= start) & (t <= end)
        assert np.allclose(r["plant.az"][window], accel, atol=1e-3), (start, end)
    cruise = (t >= 181) & (t <= 239)
    assert np.allclose(r["plant.h"][cruise], 1440.0, atol=1e-3)
    assert r["plant.h"][-1] == pytest.approx(0.0, abs=1e-3)


def test_fmu_run_equals_the_core_objects_stepped_directly(fmus, yang_run):
    direct = simulate(build_system("plant_yang2020"), fmus, backend="core")
    for name, values in yang_run.columns.items():
        assert np.max(np.abs(values - direct[name])) <= 1e-9, name


def test_component_step_not_a_multiple_of_the_base_step_is_rejected(fmus):
    system = build_system("plant_yang2020")
    components = tuple(replace(c, step_size=0.015) if c.name == "controller" else c
                       for c in system.components)
    with pytest.raises(CosimError, match="component 'controller': step size 0.015 s is not"):
        Simulation(replace(system, components=components), fmus)


def test_last_time_stamp_after_one_hour_at_a_centisecond_base_step_is_exact(fmus):
    system = SystemSpec(
        name="hover_hour", description="VerticalDynamics alone for one hour",
        components=(ComponentSpec("plant", "VerticalDynamics", 0.01, {"h0": 10.0}),),
        connections=(), stop_time=3600.0, output_interval=1.0, record=("plant.h",),
    )
    results = simulate(system, fmus)
    assert results.time[-1] == 3600.0
    assert np.array_equal(results.time, np.arange(3601, dtype=float))


def test_an_invalid_parameter_fails_initialization_naming_it(fmus):
    with Simulation(build_system("plant_yang2020"), fmus) as simulation:
        with pytest.raises(CosimError, match=r"'plant'.*'mass' = -1\.0: must be > 0"):
            simulation.run(stop_time=1.0, parameters={"plant.mass": -1.0})
        # the process and the instances survive: a good run follows
        good = simulation.run(stop_time=1.0)
    assert good.time[-1] == 1.0


def test_a_failing_do_step_is_a_clear_error_not_a_crash(fmus):
    info = fmu_info(fmus["VerticalDynamics"])
    instance = FmuInstance("plant", info)
    try:
        instance.initialize({}, 0.01, 0.0, 1.0)
        instance.exit_initialization()
        instance.set("Real", [info.variables["thrust"].value_reference], [math.nan])
        expected = r"component 'plant': doStep.*ValueError: input thrust = nan"
        with pytest.raises(CosimError, match=expected):
            instance.do_step(0.0, 0.01)
    finally:
        instance.free()


def test_a_do_step_that_does_not_start_where_the_last_ended_is_refused_by_the_fmu(fmus):
    info = fmu_info(fmus["VerticalDynamics"])
    instance = FmuInstance("plant", info)
    try:
        instance.initialize({}, 0.01, 0.0, 1.0)
        instance.exit_initialization()
        instance.do_step(0.0, 0.02)                               # any step is taken
        with pytest.raises(CosimError, match="this component is at t = 0.02 s"):
            instance.do_step(0.5, 0.01)
    finally:
        instance.free()


def test_algebraic_loops_are_detected_and_reported(fmus):
    system = SystemSpec(
        name="loop", description="a feedthrough cycle",
        components=(ComponentSpec("atmosphere", "Atmosphere", 0.01),
                    ComponentSpec("controller", "FlightController", 0.01)),
        connections=(Connection("controller.thrust", "atmosphere.h"),
                     Connection("atmosphere.p_static", "controller.h_fb")),
        stop_time=1.0,
    )
    with pytest.raises(CosimError, match="algebraic loop in loop: .*atmosphere.*controller"):
        Simulation(system, fmus)


def test_fmu_state_save_and_restore_continue_bit_identically(fmus):
    info = fmu_info(fmus["Atmosphere"])
    instance = FmuInstance("atmosphere", info)
    outputs = [info.variables[n].value_reference
               for n in ("p_static", "wind_speed", "lapse_rate_actual")]
    h = info.variables["h"].value_reference

    def advance(start, count):
        values = []
        for n in range(start, start + count):
            instance.set("Real", [h], [100.0 + n])
            instance.do_step(n * 0.1, 0.1)
            values.append(instance.get("Real", outputs))
        return values

    try:
        instance.initialize({"lapse_rate_std": 0.003, "lapse_rate_period": 1.0,
                             "gust_std": 1.0, "wind_mean": 5.0, "seed": 11}, 0.1, 0.0, 100.0)
        instance.exit_initialization()
        advance(0, 50)
        assert_restores_identically(instance, lambda: advance(50, 100))
    finally:
        instance.free()


def test_instances_are_reused_across_runs_with_identical_results(fmus):
    with Simulation(build_system("plant_yang2020"), fmus) as simulation:
        first = simulation.run(stop_time=20.0)
        second = simulation.run(stop_time=20.0)
    for name in first.columns:
        assert np.array_equal(first[name], second[name])


def test_cli_run_writes_a_csv_and_a_plot(ssp_files, tmp_path):
    completed = subprocess.run(
        [sys.executable, "-m", "altfusion.cli", "run", str(ssp_files["plant_yang2020"]),
         "--stop", "30", "--set", "controller.profile=xu_hover15", "--out", str(tmp_path)],
        capture_output=True, text=True, check=True,
    )
    assert "tracking error" in completed.stdout
    csv = (tmp_path / "plant_yang2020.csv").read_text().splitlines()
    assert csv[0].startswith("time [s],plant.h [m],")
    assert len(csv) == 1 + 301
    assert (tmp_path / "plant_yang2020.png").stat().st_size > 10_000


def test_many_instantiations_leave_the_host_interpreter_intact(fmus):
    """pythonfmu 0.7.0 over-releases the slave module's dict on every instantiation; the
    adapter base compensates. Run in a child process so a crash fails the test."""
    script = (
        "import gc, sys\n"
        "from pathlib import Path\n"
        "from altfusion.cosim.instances import FmuInstance, fmu_info\n"
        "keep = []\n"
        "for i in range(40):\n"
        "    for path in sys.argv[1:]:\n"
        "        keep.append(FmuInstance(f'i{i}', fmu_info(Path(path))))\n"
        "    gc.collect()\n"
        "for instance in keep:\n"
        "    instance.free()\n"
        "gc.collect()\n"
        "print('intact', len(keep))\n"
    )
    completed = subprocess.run([sys.executable, "-c", script, *map(str, fmus.values())],
                               capture_output=True, text=True, timeout=300)
    assert completed.returncode == 0, completed.stderr[-2000:]
    assert f"intact {40 * len(fmus)}" in completed.stdout
