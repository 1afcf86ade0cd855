"""Flight-log replay: recorded PX4 sensor data (ULog) delivered as the sensor FMUs deliver it.

* :mod:`~altfusion.replay.streams` - sample streams as plain numpy arrays and the clean-up of
  their time stamps (order, duplicates, gaps), with a report of every problem found;
* :mod:`~altfusion.replay.attitude` - quaternion helpers (body-to-NED rotation, interpolation);
* :mod:`~altfusion.replay.extract` - the PX4 topics -> contract streams, on plain arrays;
* :mod:`~altfusion.replay.ulog` - reading a ``.ulg`` file with ``pyulog``;
* :mod:`~altfusion.replay.component` - the ``LogReplay`` core behind the FMU;
* :mod:`~altfusion.replay.compare`, :mod:`~altfusion.replay.plot` - comparing estimators with
  PX4 EKF2 after a replay run (numpy and matplotlib on recorded results);
* :mod:`~altfusion.replay.calibration` - a log's launch calibration (datums) for the replay
  tuning of the replay systems (:mod:`altfusion.systems.replay`, plain data in the catalog);
* :mod:`~altfusion.replay.run` - ``altfusion replay``: builds and runs the system through the
  co-simulation runner.

The reader and the component are core code (numpy and pyulog) and import no FMI code; only
``run`` steps FMUs, and no FMU imports it.
"""
