"""Sensor models: each samples the plant on its own schedule through :mod:`.sampling`."""

from altfusion.sensors.accelerometer import Accelerometer, AccelerometerParams
from altfusion.sensors.air_data import AirDataModule, AirDataParams
from altfusion.sensors.gnss import GnssParams, GnssReceiver
from altfusion.sensors.laser import LaserRangefinder, LaserRangefinderParams
from altfusion.sensors.radio_altimeter import RadioAltimeter, RadioAltimeterParams
from altfusion.sensors.sampling import Sample, SampledSensor, SamplingParams

__all__ = [
    "Accelerometer", "AccelerometerParams", "AirDataModule", "AirDataParams", "GnssParams",
    "GnssReceiver", "LaserRangefinder", "LaserRangefinderParams", "RadioAltimeter",
    "RadioAltimeterParams", "Sample", "SampledSensor", "SamplingParams",
]
