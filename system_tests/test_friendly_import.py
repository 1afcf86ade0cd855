"""A user who imports one FMU into a tool: ``step_size`` defaults to the tool's step (the
first doStep's; fmpy's co-simulation step is its ``output_interval``), a later different step
or a step that does not fit the sample periods is refused with the reason logged at
fmi2Error (the call returns fmi2Error: the native shim returns the worst status logged), and
LogReplay without pyulog says so. Errors reach the host's logger with debug logging off."""

import subprocess
import sys

import numpy as np
from fmpy import simulate_fmu

from altfusion.cosim.instances import FmuInstance, fmu_info

FMI2_ERROR = 3


class Messages(list):
    """An fmpy logger keeping (status, message)."""

    def __call__(self, _component, _instance, status, _category, message):
        self.append((status, message.decode()))

    def errors(self) -> list[str]:
        return [m for s, m in self if s >= FMI2_ERROR]


def test_the_default_step_size_is_the_tools_step(fmus):
    """1 s at the tool's 0.05 s step: 21 rows (0 to 1 s), no error."""
    messages = Messages()
    result = simulate_fmu(str(fmus["GnssReceiver"]), output_interval=0.05, stop_time=1.0,
                          start_values={"h": 100.0, "sample_period": 0.1},
                          output=["gps_h", "gps_count"], debug_logging=True, logger=messages)
    assert messages.errors() == []
    np.testing.assert_allclose(result["time"], np.arange(21) * 0.05, rtol=0, atol=1e-12)
    assert result["gps_count"][-1] == 10            # a fix every 0.1 s over 1 s


def test_a_host_step_other_than_step_size_runs_on_the_ticks_of_step_size(fmus):
    """A 0.01 s tick under the tool's 0.05 s steps: a fix every 0.1 s, ten over 1 s."""
    messages = Messages()
    result = simulate_fmu(str(fmus["GnssReceiver"]), output_interval=0.05, stop_time=1.0,
                          start_values={"step_size": 0.01, "sample_period": 0.1, "h": 100.0},
                          output=["gps_count", "gps_time"], logger=messages)
    assert messages.errors() == []
    assert result["gps_count"][-1] == 10
    assert result["gps_time"][-1] == 1.0


def test_a_first_step_that_does_not_fit_a_sample_period_falls_back_to_the_default_tick(fmus):
    """The GNSS fix period 1 s is not a whole number of 0.3 s steps: the instance ticks
    on 0.01 s and still fixes at 1 s, seen at the end of the step that contains it."""
    messages = Messages()
    result = simulate_fmu(str(fmus["GnssReceiver"]), output_interval=0.3, stop_time=1.2,
                          output=["gps_count", "gps_time"], logger=messages)
    assert messages.errors() == []
    assert list(result["gps_count"]) == [0, 0, 0, 0, 1]
    assert result["gps_time"][-1] == 1.0


def test_log_replay_without_pyulog_logs_an_error_naming_pyulog(fmus):
    """In a Python where ``import pyulog`` fails, as in a host without the package."""
    script = (
        "import sys\n"
        "sys.modules['pyulog'] = None\n"
        "from fmpy import simulate_fmu\n"
        "seen = []\n"
        "def logger(c, i, status, cat, msg):\n"
        "    seen.append((status, msg.decode()))\n"
        "try:\n"
        "    simulate_fmu(sys.argv[1], output_interval=0.01, stop_time=0.1, logger=logger,\n"
        "                 start_values={'log_file': 'flightlogs/pyulog_sample_px4_events.ulg'})\n"
        "except Exception as error:\n"
        "    print(error)\n"
        "print('\\n'.join(m for s, m in seen if s >= 3))\n"
    )
    completed = subprocess.run([sys.executable, "-c", script, str(fmus["LogReplay"])],
                               capture_output=True, text=True, timeout=120)
    assert "needs the Python package pyulog" in completed.stdout, (completed.stdout,
                                                                   completed.stderr[-2000:])


def test_later_steps_of_any_length_follow_the_adopted_tick(fmus):
    instance = FmuInstance("gnss", fmu_info(fmus["GnssReceiver"]))
    try:
        instance.initialize({"sample_period": 0.1}, 0.0, 0.0, 1.0)    # 0: adopt
        instance.exit_initialization()
        count = instance.info.variables["gps_count"].value_reference
        for time, step in ((0.0, 0.05), (0.05, 0.05), (0.1, 0.25), (0.35, 1e-13)):
            instance.do_step(time, step)
        assert instance.get("Integer", [count]) == [3]        # fixes at 0.1, 0.2 and 0.3 s
    finally:
        instance.free()


def test_our_instances_keep_their_logger_when_the_user_runs_simulate_fmu_in_between(fmus):
    """fmpy's native logger proxy holds one Python callback per process and every
    ``simulate_fmu(logger=...)`` replaces it, then frees its own: the runner logs through a
    private copy of the proxy, so an error of an instance created before the user's
    ``simulate_fmu`` still reaches the runner (before: a segfault). In a subprocess, so that a
    crash fails this test only."""
    script = (
        "import gc, sys\n"
        "from fmpy import simulate_fmu\n"
        "from altfusion.cosim.instances import CosimError, FmuInstance, fmu_info\n"
        "gnss, baseline = sys.argv[1:3]\n"
        "instance = FmuInstance('gnss', fmu_info(gnss))\n"
        "instance.initialize({'sample_period': 0.1}, 0.0, 0.0, 1.0)\n"
        "instance.exit_initialization()\n"
        "instance.do_step(0.0, 0.05)\n"
        "simulate_fmu(baseline, stop_time=0.1, output_interval=0.01, debug_logging=True,\n"
        "             logger=lambda *args: None)\n"
        "gc.collect()\n"
        "try:\n"
        "    instance.do_step(0.5, 0.1)\n"
        "except CosimError as error:\n"
        "    print(error)\n"
        "instance.free()\n"
    )
    completed = subprocess.run([sys.executable, "-c", script, str(fmus["GnssReceiver"]),
                                str(fmus["BaselineKF"])], capture_output=True, text=True,
                               timeout=120)
    assert completed.returncode == 0, completed.stderr[-2000:]
    assert "doStep at t = 0.5 s, but this component is at t = 0.05 s" in completed.stdout, \
        completed.stdout
