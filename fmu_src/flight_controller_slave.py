"""FMU FlightController: maps FMI variables onto altfusion.physics.flight_controller."""

from altfusion import fmi
from altfusion.physics import flight_controller


class FlightController(fmi.CoreSlave):
    """Altitude-tracking PID with feedforward (python-control design) flying a scenario
    profile; its altitude feedback is an input (truth or an estimator's output)."""

    core_class = flight_controller.FlightController
    variables = (
        fmi.Input("h_fb", "m", "Altitude feedback (MSL): truth or an estimate"),
        fmi.Input("vz_fb", "m/s", "Vertical-speed feedback: truth or an estimate"),
        fmi.Output("thrust", "N", "Thrust command", min=0.0, initial_depends_on=("vz_fb",)),
        fmi.Output("h_ref", "m", "Reference altitude (MSL)", reads_at_step_end=()),
        fmi.Output("vz_ref", "m/s", "Reference vertical speed", reads_at_step_end=()),
        fmi.Output("az_ref", "m/s2", "Reference vertical acceleration", reads_at_step_end=()),
    )
