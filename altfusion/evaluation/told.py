"""What ``altfusion evaluate`` tells the estimators it evaluates (``--told``).

A user dropping an estimator into a new system knows its sensors' datasheets, perhaps what
the system states about their errors beyond white noise, perhaps nothing; and a datasheet may
be wrong. Each mode is one evaluation of every scenario, in its own campaigns:

* ``models`` (the default): every estimator told its sensors' true noise and, in a paper
  scenario, the sensor error models the paper system states
  (:data:`altfusion.systems.error_models.SENSOR_ERRORS`);
* ``noise``: the true noise only (the GNSS's at the receiver's nominal VDOP, told with it:
  :data:`NOISE_REFERENCES`);
* ``nothing``: neither (each estimator's defaults);
* ``misstated``: what ``noise`` tells with every noise misstated, once x0.2 and once x5
  (:data:`MISSTATED_FACTORS`: two variants; a noise told as a variance x0.04 and x25).

Every mode also tells the *site* (:data:`SITE_NAMES`, :func:`split_site`): the terrain under
the flight, which is the world the rangefinders measure, not an error of a sensor. The paper
estimators that read a rangefinder have it in their equations (YangFusionKF's and XuSHAEKF's
``terrain_h``: flat ground at 0 m, whatever they are told); told it, an estimator with a
terrain state (AltitudeEKF) compares with them on the same knowledge, and a user flying over
known ground knows it. Told nothing about the terrain, no estimator can place a
rangefinder's height above sea level better than its GNSS averages (docs/montecarlo.md
gives the numbers).

In the fault flight the fault suite's settings (:data:`altfusion.systems.faults.TRUE_NOISE`)
are split the same way (:func:`split_noise`): ``noise`` tells their noises and the site (its
flat terrain), ``models`` also the rest (AltitudeEKF's range height reference, the flight's
baro and GNSS walks), which is what the fault suite tells.

The paper's own estimator (the system's component ``estimator``) keeps its paper's
parameters, and in ``models`` and ``noise`` its cell is that component: the reference an
estimator told the noise has to beat. In ``nothing`` and ``misstated`` (:attr:`Told.observes_own`)
every evaluated estimator must be told per the mode: the paper's estimator is evaluated as an
observer component of its FMU told per the mode, while the system's ``estimator`` still
flies the aircraft on the paper's parameters and is then not evaluated.
"""

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

NOISE = "noise"
MODELS = "models"
NOTHING = "nothing"
MISSTATED = "misstated"
TOLD_MODES = (NOISE, MODELS, NOTHING, MISSTATED)
"""The ``--told`` modes, in the order the report shows them."""

TOLD = {
    NOISE: "each estimator told its sensors' true noise and the terrain only",
    MODELS: "each estimator told its sensors' true noise, the terrain and, in a paper "
            "scenario, the sensor error models the paper system states",
    NOTHING: "each estimator told nothing but the terrain (its defaults otherwise)",
    MISSTATED: "each estimator told its sensors' noise and the terrain only, every noise "
               "misstated",
}
"""What each mode tells, as the report says it."""

MISSTATED_FACTORS = (0.2, 5.0)
"""The factors every noise (1σ) is misstated by in ``misstated``."""

NOISE_NAMES = ("baro_noise", "gps_noise", "gps_vz_noise", "acc_noise", "radar_noise",
               "laser_noise")
"""The contract names of the sensor noises (1σ, SI units)."""

NOISE_REFERENCES = ("gps_vdop_ref",)
"""Not noises but the conditions a noise is stated at, told with it and never misstated: the
VDOP at which the GPS noise holds (an estimator that scales its GPS noise by
VDOP/``gps_vdop_ref`` would otherwise take a noise stated at VDOP 1.5 as 1.5 times larger)."""

SIGMA_PARAMETERS = ("user_range_error",)
"""Estimator parameters that state a noise as its 1σ under another name than the contract's
or ``<source>_noise_std``: BaoDriftEstimator's GNSS user range error, from which it computes
its GPS noise (told in the fault flight)."""


SITE_NAMES = ("terrain_h", "P0_terrain", "terrain_psd")
"""The parameters that describe the site, not a sensor: the terrain under the flight (its
height, the variance it is known with, how it varies along the flight). Told in every mode
(module documentation)."""


def noise_power(name: str) -> int:
    """How the parameter ``name`` states a sensor noise: 1 as its σ, 2 as its variance
    (``R_<...>``: ``R_baro``, BaoDriftEstimator's ``R_worst``), 0 not a noise (an error
    model, a terrain, a reference)."""
    if name.startswith("R_"):
        return 2
    if name in NOISE_NAMES or name.endswith("_noise_std") or name in SIGMA_PARAMETERS:
        return 1
    return 0


def split_noise(parameters: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """``parameters`` split into those stating a sensor noise (:func:`noise_power`, with the
    conditions a noise holds at, :data:`NOISE_REFERENCES`) and the others: the error models
    (a terrain, a reference, a bias's walk)."""
    return _partition(parameters, lambda name: noise_power(name) or name in NOISE_REFERENCES)


def split_site(models: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """``models`` split into those describing the site (:data:`SITE_NAMES`: the terrain) and
    the sensor error models."""
    return _partition(models, lambda name: name in SITE_NAMES)


def _partition(parameters: dict[str, Any], chosen: Callable[[str], Any],
               ) -> tuple[dict[str, Any], dict[str, Any]]:
    """``parameters`` split into those whose name is ``chosen`` and the others."""
    first = {name: value for name, value in parameters.items() if chosen(name)}
    return first, {name: value for name, value in parameters.items() if name not in first}


def misstate(parameters: dict[str, Any], factor: float) -> dict[str, Any]:
    """``parameters`` with every noise told ``factor`` times its σ (a variance
    ``factor``²), the others as they are."""
    return {name: value * factor**power if (power := noise_power(name)) else value
            for name, value in parameters.items()}


@dataclass(frozen=True)
class Told:
    """One evaluation of every scenario: the mode, and for ``misstated`` the factor."""

    mode: str = MODELS
    factor: float = 1.0

    @property
    def name(self) -> str:
        """The variant's name: its folder under ``--out`` and its key in the summary."""
        return f"{self.mode}_x{self.factor:g}" if self.mode == MISSTATED else self.mode

    @property
    def label(self) -> str:
        """How the report heads the variant: told ``noise``, ``models``, ``nothing``, or
        the factor of the misstated noise."""
        return f"x{self.factor:g}" if self.mode == MISSTATED else self.mode

    @property
    def description(self) -> str:
        """What this variant tells, as the report says it."""
        if self.mode == MISSTATED:
            return f"{TOLD[MISSTATED]} x{self.factor:g} (a variance x{self.factor**2:g})"
        return TOLD[self.mode]

    @property
    def observes_own(self) -> bool:
        """The paper's estimator is evaluated as an observer told per this mode (the system's
        own keeps the paper's parameters and is not evaluated)."""
        return self.mode in (NOTHING, MISSTATED)

    def tell(self, noise: dict[str, Any], models: dict[str, Any]) -> dict[str, Any]:
        """The parameters an evaluated estimator gets: of those telling its sensors' noise
        (``noise``) and those telling the site and the stated error models (``models``),
        what this mode tells: the site always (:func:`split_site`)."""
        if self.mode == MODELS:
            return {**noise, **models}
        site, _ = split_site(models)
        if self.mode == NOISE:
            return {**noise, **site}
        if self.mode == MISSTATED:
            return {**misstate(noise, self.factor), **site}
        return site


DEFAULT_TOLD = Told()
"""The default evaluation: told the noise and the models."""


def told_variants(modes: list[str]) -> list[Told]:
    """The evaluations of the ``modes`` (known, each once), in :data:`TOLD_MODES` order,
    ``misstated`` as one per :data:`MISSTATED_FACTORS`."""
    return [told for mode in TOLD_MODES if mode in modes
            for told in ([Told(mode, f) for f in MISSTATED_FACTORS] if mode == MISSTATED
                         else [Told(mode)])]
