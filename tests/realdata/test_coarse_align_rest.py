"""The opening rest must not end early when block edges fall between IMU samples."""
from types import SimpleNamespace

import numpy as np

from fuzzynav.realdata.coarse_align import opening_rest


def test_rest_blocks_with_uneven_sample_counts():
    # 100-Hz samples with sub-microsecond jitter around the 0.5-s block edges: the blocks
    # hold 49, 50 or 51 samples
    jitter = np.random.default_rng(0).uniform(-1e-7, 1e-7, 3001)
    t = 20.3 + np.arange(3001) * 0.01 + jitter
    dv = np.tile([0.0, 0.0, 9.8 * 0.01], (3000, 1))
    imu = SimpleNamespace(time_s=t, dtheta_b=np.zeros((3000, 3)), dv_b=dv)
    tg = 20.3 + np.arange(0.0, 30.0, 0.25)
    speed = np.where(tg >= 45.3, 5.0, 0.0)
    z = np.zeros((tg.size, 6))
    z[:, 4] = speed
    gnss = SimpleNamespace(time_s=tg, z=z, sigma=np.ones((tg.size, 6)))
    t0, t1 = opening_rest(imu, gnss)
    assert t0 == t[0] and t1 > t0 + 24.0
