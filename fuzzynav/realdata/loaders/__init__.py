"""Loaders of real recordings into fuzzynav's containers.

Each loader takes the recording's directory (any copy of a recording of that kind loads)
and returns IMU increments in the body RFU frame (:class:`fuzzynav.sim.imu.ImuData`) and
aiding-sensor data (:class:`fuzzynav.sim.sensors.SensorData`) on one time axis.

* :mod:`.rtklib` — RTKLIB-logged IMU CSV + time tags + RTKLIB ``.pos`` (the rtklib-drive);
* :mod:`.akit_recording` — the A-KIT AUV trajectories (clock map in :mod:`.akit_timing`,
  checks in :mod:`.akit_checks`).

Both read their files a block of lines at a time (:mod:`.chunked`; the car's IMU CSV in
:mod:`.imu_csv`), with the same arrays and errors as a whole read.  A car recording loaded
``streamed`` keeps no IMU rows: its increments are read again from the file, a block at a
time, whenever they are used (:mod:`.imu_file`).
"""
