"""FMU FlightController: maps FMI variables onto altfusion.physics.flight_controller."""

from altfusion.fmi import CoreSlave, Input, Output
from altfusion.physics import flight_controller


class FlightController(CoreSlave):
    """Altitude-tracking PID with feedforward (python-control design) flying a scenario
    profile; its altitude feedback is an input (truth or an estimator's output)."""

    core_class = flight_controller.FlightController
    variables = (
        Input("h_fb", "m", "Altitude feedback (MSL): truth or an estimate"),
        Input("vz_fb", "m/s", "Vertical-speed feedback: truth or an estimate"),
        Output("thrust", "N", "Thrust command", min=0.0),
        Output("h_ref", "m", "Reference altitude (MSL)", depends_on=()),
        Output("vz_ref", "m/s", "Reference vertical speed", depends_on=()),
        Output("az_ref", "m/s2", "Reference vertical acceleration", depends_on=()),
    )
