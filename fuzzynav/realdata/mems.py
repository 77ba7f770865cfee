"""The filter's model of a consumer MEMS IMU on real data (datasheet units at this edge).

The white-noise figures are the ones the rtklib-drive's source configures for its IMU
(TDK ICM-45686; ``../shared/datasets/README.md``): gyro 0.0038 °/s/√Hz, accelerometer
70 µg/√Hz.  The rest is chosen for a consumer part and checked on the drive
(``docs/validation.md`` §2):

* **Gyro bias.**  The large turn-on bias (≈ 0.17 °/s here) is removed before the filter
  starts by the mean rate at rest (:mod:`fuzzynav.realdata.coarse_align`); what is left is the
  in-run change.  On the drive the mean rate at the four stops moves by up to 100 °/h
  within minutes (the IMU had been powered for four minutes: warm-up), so the residual
  prior is 50 °/h and the random walk 100 °/h/√h (13 °/h per minute).
* **Accelerometer bias.**  Turn-on offsets of consumer parts are tens of mg; levelling
  at rest hides the horizontal part in the tilt, and the vertical reads 14 mg high here
  (1.4 % of g).  Prior 20 mg, random walk 100 µg/√s.
* **Angle random walk inflated.**  In motion a consumer gyro has errors the 15-state model
  lacks (scale factor, cross-axis and acceleration sensitivity, vibration rectification —
  the engine shakes the IMU by 2.6 °/s RMS at 31 Hz even at idle).  With the datasheet ARW
  the filter is overconfident (normalised innovation squared 2.8 per row instead of 1, 4.6
  on the velocity rows) and turns these errors into gyro-bias estimates of several hundred
  °/h.  Ten times the
  datasheet ARW (2.3 °/√h) is the smallest factor that makes the innovations consistent
  (1.1 per row) with GNSS throughout; it was chosen on that criterion, not on the drift.
"""
from __future__ import annotations

from dataclasses import dataclass

from fuzzynav import units
from fuzzynav.sim.imu import ImuNoise, TriadNoise

__all__ = ["MemsModel", "CONSUMER_MEMS"]


@dataclass(frozen=True)
class MemsModel:
    """Noise figures and initial uncertainty a filter assumes for a consumer MEMS IMU.

    Parameters
    ----------
    gyro_noise_dps_psqrthz, accel_noise_ug_psqrthz : float
        Datasheet white-noise densities [°/s/√Hz], [µg/√Hz].
    arw_inflation : float
        Factor on the gyro white noise the filter assumes (unmodelled in-motion errors).
    gyro_bias_sigma_dph, gyro_bias_rw_dph_psh : float
        Prior of the residual gyro bias after the rest calibration [°/h] and its random
        walk [°/h/√h].
    accel_bias_sigma_ug, accel_bias_rw_ug_psqrts : float
        Accelerometer bias prior [µg] and random walk [µg/√s].
    init_att_sigma_deg : tuple of 3 float
        Initial attitude uncertainty (east, north, up) [deg]: levelling at rest, heading
        from the GNSS course.
    init_vel_sigma_mps : float
        Initial velocity uncertainty [m/s] (the vehicle is at rest).
    """

    gyro_noise_dps_psqrthz: float = 0.0038
    accel_noise_ug_psqrthz: float = 70.0
    arw_inflation: float = 10.0
    gyro_bias_sigma_dph: float = 50.0
    gyro_bias_rw_dph_psh: float = 100.0
    accel_bias_sigma_ug: float = 20000.0
    accel_bias_rw_ug_psqrts: float = 100.0
    init_att_sigma_deg: tuple = (0.5, 0.5, 3.0)
    init_vel_sigma_mps: float = 0.1

    def imu_noise(self) -> ImuNoise:
        """The figures as the SI :class:`ImuNoise` named filters configure themselves from."""
        gyro = TriadNoise(bias_sigma=self.gyro_bias_sigma_dph * units.DPH,
                          white=self.arw_inflation * self.gyro_noise_dps_psqrthz * units.DPS,
                          rrw=self.gyro_bias_rw_dph_psh * units.DPH_PSH)
        accel = TriadNoise(bias_sigma=self.accel_bias_sigma_ug * units.UG,
                           white=self.accel_noise_ug_psqrthz * units.UG,
                           rrw=self.accel_bias_rw_ug_psqrts * units.UG)
        return ImuNoise(gyro=gyro, accel=accel)

    def filter_options(self, init_pos_sigma_m: float) -> dict:
        """Initial-uncertainty options for a named filter (:class:`FilterContext`)."""
        return {"init_att_sigma_deg": tuple(self.init_att_sigma_deg),
                "init_vel_sigma_mps": float(self.init_vel_sigma_mps),
                "init_pos_sigma_m": float(init_pos_sigma_m)}


#: the model used for the rtklib-drive (and by default for any ``--data`` recording)
CONSUMER_MEMS = MemsModel()
