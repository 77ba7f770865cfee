"""docs/paper002.md's tuned-fuzzy vs tuned-classical section on hand-made frames (answers
worked by hand: the objective of each run, per-seed differences, Student-t intervals from
scipy)."""
from types import SimpleNamespace

import numpy as np
import pandas as pd
from scipy import stats

from fuzzynav.pages.best_classical import paired_terms_lines
from fuzzynav.papers.paper002 import page_tuned as pt

SCN = SimpleNamespace(duration_s=400.0, threshold_arcmin=10.0)


def _runs(fz_time, kf_time, fz_az, kf_az, name="s"):
    n = len(fz_time)
    df = pd.DataFrame({"scenario": name, "filter": [pt.FUZZY] * n + [pt.CLASSICAL] * n,
                       "seed": list(range(n)) * 2, "align_time_s": [*fz_time, *kf_time],
                       "final_azimuth_arcmin": [*fz_az, *kf_az]})
    return {name: (SCN, df)}


def _t(d):
    d = np.asarray(d, float)
    h = stats.t.ppf(0.975, d.size - 1) * d.std(ddof=1) / np.sqrt(d.size)
    return d.mean(), d.mean() - h, d.mean() + h


def test_the_objective_of_each_run_is_the_studys():
    runs = _runs([200.0], [400.0], [5.0], [2.0])
    df = pt.frame(runs, weight=2.0)
    got = dict(zip(df["filter"], df["objective"]))
    assert got[pt.FUZZY] == 200.0 / 400.0 + 2.0 * 5.0 / 10.0      # 1.5
    assert got[pt.CLASSICAL] == 400.0 / 400.0 + 2.0 * 2.0 / 10.0  # 1.4


def test_pairing_cancels_the_spread_between_seeds_and_names_a_win():
    # seeds differ by 100 s; the fuzzy filter is 20 s (+-1) faster on every one and its
    # azimuth no different on average: a time win, an azimuth draw
    kf_t = [100.0, 200.0, 300.0, 350.0]
    fz_t = [79.0, 181.0, 280.0, 330.0]
    kf_a, fz_a = [5.0, 6.0, 5.5, 5.0], [5.5, 5.5, 5.0, 5.5]
    df = pt.frame(_runs(fz_t, kf_t, fz_a, kf_a), weight=1.0)
    lines = paired_terms_lines(df, ["s"], pt.FUZZY, pt.CLASSICAL, pt.TERMS,
                               notes={"s": "a note"})
    assert lines[0] == ("| scenario | seeds | objective (95 % CI) | alignment time [s] "
                        "(95 % CI) | final azimuth [arcmin] (95 % CI) |")
    dt = np.subtract(fz_t, kf_t)
    da = np.subtract(fz_a, kf_a)
    dobj = dt / 400.0 + da / 10.0
    m, lo, hi = _t(dt)
    assert hi < 0
    ma, loa, hia = _t(da)
    assert loa < 0 < hia
    mo, loo, hio = _t(dobj)
    assert lines[2] == (f"| `s` (a note) | 4 | {mo:+.3f} [{loo:+.3f}, {hio:+.3f}] "
                        f"{'**win**' if hio < 0 and mo <= -0.005 else 'draw'} | "
                        f"{m:+.1f} [{lo:+.1f}, {hi:+.1f}] **win** | "
                        f"{ma:+.2f} [{loa:+.2f}, {hia:+.2f}] draw |")


def test_a_loss_is_called_a_loss_on_held_out_sets():
    runs = _runs([300.0, 310.0, 305.0], [200.0, 205.0, 195.0], [5.0] * 3, [5.0] * 3,
                 name="paper002")
    df = pt.frame(runs, weight=1.0)
    assert pt.verdicts(df, ["paper002"]) == {"paper002": "loses to"}
    assert pt.verdicts(df, ["paper002"], "final_azimuth_arcmin") == {"paper002": "draws with"}


def test_the_finding_says_what_the_verdicts_say():
    runs = {}
    for name, shift in (("paper002", 100.0), ("paper002-gusts", -100.0),
                        ("paper002-mems", 0.0)):
        kf = [200.0, 210.0, 190.0, 205.0]
        fz = [t + shift + d for t, d in zip(kf, (1.0, -1.0, 2.0, -2.0))]
        runs.update(_runs(fz, kf, [5.0] * 4, [5.0] * 4, name=name))
    text = pt.finding(runs)
    assert text.startswith("- **Against the equally tuned classical filter — the fuzzy "
                           "layer wins 1 of 3 held-out sets.**")
    assert "on `paper002` it loses (+0.250 " in text
    assert "on `paper002-gusts` it wins (-0.250 " in text
    assert "on `paper002-mems` it draws (" in text  # mean 0 up to rounding
