"""Flight-log replay: recorded PX4 sensor data (ULog) delivered as the sensor FMUs deliver it.

* :mod:`~altfusion.replay.streams` - sample streams as plain numpy arrays and the clean-up of
  their time stamps (order, duplicates, gaps), with a report of every problem found;
* :mod:`~altfusion.replay.attitude` - quaternion helpers (body-to-NED rotation, interpolation);
* :mod:`~altfusion.replay.extract` - the PX4 topics -> contract streams, on plain arrays;
* :mod:`~altfusion.replay.ulog` - reading a ``.ulg`` file with ``pyulog``;
* :mod:`~altfusion.replay.component` - the ``LogReplay`` core behind the FMU;
* :mod:`~altfusion.replay.compare`, :mod:`~altfusion.replay.plot`,
  :mod:`~altfusion.replay.tuning` - comparing estimators with PX4 EKF2 after a replay run.

Only the first four and the component are core code (numpy and pyulog); nothing here imports
FMI code.
"""
