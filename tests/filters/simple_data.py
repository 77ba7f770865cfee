"""Hand-made GNSS/INS data with exactly known noise (independent of fuzzynav.sim's error models).

Used to test that the filter is statistically consistent when its model matches the truth.
"""
from types import SimpleNamespace

import numpy as np

from fuzzynav import units
from fuzzynav.filters.config import FilterConfig
from fuzzynav.filters.runner import InitialState
from fuzzynav.nav import attitude, earth
from fuzzynav.sim.sensors import SensorData
from fuzzynav.sim.trajectory import Segment, generate

START = np.array([np.deg2rad(38.0178), np.deg2rad(112.4447), 825.0])
CONFIG = FilterConfig(init_att_sigma_deg=(0.1, 0.1, 1.0), gyro_sigma_dph=(20.0,),
                      accel_sigma_ug=(500.0,), arw_dpsh=0.05, vrw_ug_psqrthz=50.0)
POS_SIGMA = np.array([1.0, 1.0, 2.0])
VEL_SIGMA = np.array([0.05, 0.05, 0.1])


def trajectory(duration_blocks=1):
    segs = [Segment("static", 30), Segment("accelerate", 20, speed_change_mps=15)]
    segs += [Segment("turn", 30, turn_deg=90, bank=True), Segment("climb", 60, pitch_deg=5),
             Segment("s-turns", 80, turn_deg=45, n_turns=4), Segment("cruise", 30)] * duration_blocks
    return generate(START, segs, 100.0, 0.0, 0.3)


def gnss_fixes(tr, rng, pos_sigma=POS_SIGMA, vel_sigma=VEL_SIGMA, rate_hz=1.0):
    idx = np.arange(0, tr.n_samples + 1, int(round(tr.imu_rate_hz / rate_hz)))
    lat, h = tr.lla[idx, 0], tr.lla[idx, 2]
    rm, rn = earth.radii(lat)
    e = rng.normal(0.0, 1.0, (idx.size, 3)) * pos_sigma
    z = np.column_stack([lat + e[:, 1] / (rm + h), tr.lla[idx, 1] + e[:, 0] / ((rn + h) * np.cos(lat)),
                         h + e[:, 2], tr.vel_n[idx] + rng.normal(0, 1, (idx.size, 3)) * vel_sigma])
    sig = np.tile(np.r_[POS_SIGMA, VEL_SIGMA], (idx.size, 1))
    return SensorData("gnss", tr.time_s[idx], z, sig)


def run_inputs(tr, seed, config=CONFIG):
    """IMU log, GNSS and an initial state whose errors are drawn from the filter's P0."""
    rng = np.random.default_rng(seed)
    P0 = np.diag(config.P0())
    dt = 1.0 / tr.imu_rate_hz
    bg = rng.normal(0, 1, 3) * np.sqrt(P0[9:12])
    ba = rng.normal(0, 1, 3) * np.sqrt(P0[12:15])
    arw, vrw = config.arw_dpsh * units.DPSH, config.vrw_ug_psqrthz * units.UG
    imu = SimpleNamespace(
        time_s=tr.time_s,
        dtheta_b=tr.dtheta_b + bg * dt + rng.normal(0, arw * np.sqrt(dt), tr.dtheta_b.shape),
        dv_b=tr.dv_b + ba * dt + rng.normal(0, vrw * np.sqrt(dt), tr.dv_b.shape))
    x0 = rng.normal(0, 1, 9) * np.sqrt(P0[:9])
    C0 = (np.eye(3) - attitude.skew(x0[:3])) @ attitude.euler_to_dcm(tr.att[0])
    d = earth.enu_to_delta_lla(x0[6:9], tr.lla[0, 0], tr.lla[0, 2])
    init = InitialState(0.0, tr.lla[0] + np.array(d), tr.vel_n[0] + x0[3:6],
                        attitude.dcm_to_quat(C0))
    return imu, gnss_fixes(tr, rng), init, bg, ba


def state_errors(res, tr, bg, ba):
    """Errors of the 15 states at the output epochs (phi, dv, dpos metres, biases)."""
    k = np.searchsorted(tr.time_s, res.time_s - 1e-9)
    phi = attitude.attitude_error(attitude.quat_to_dcm(res.q_bn), attitude.quat_to_dcm(tr.q_bn[k]))
    dpos = np.array([earth.lla_to_enu(*a, *b) for a, b in zip(res.lla, tr.lla[k])])
    return np.hstack([phi, res.vel_n - tr.vel_n[k], dpos, res.gyro_bias - bg, res.accel_bias - ba])
