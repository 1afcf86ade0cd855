"""FMU VerticalDynamics: maps FMI variables onto altfusion.physics.vertical_dynamics."""

from altfusion import fmi
from altfusion.physics import vertical_dynamics


class VerticalDynamics(fmi.CoreSlave):
    """Point-mass vertical dynamics of a UAV: thrust, gravity, quadratic drag; RK4 sub-steps."""

    core_class = vertical_dynamics.VerticalDynamics
    variables = (
        fmi.Input("thrust", "N", "Total thrust along the vertical, held over each step", min=0.0),
        fmi.Output("h", "m", "True altitude (MSL)", reads_at_step_end=()),
        fmi.Output("vz", "m/s", "True vertical speed, positive up", reads_at_step_end=()),
        fmi.Output("az", "m/s2", "True vertical acceleration at the end of the step, positive up",
                   reads_at_step_end=(), initial_depends_on=("thrust",)),
    )
