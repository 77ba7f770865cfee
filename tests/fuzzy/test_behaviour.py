"""Engine behaviour users rely on: clamping, defaults, NaN, broadcasting, closed forms."""
import numpy as np
import pytest

from fuzzynav.fuzzy import FisEvaluationError, load_fis
from tests.floats import ULP_RTOL, assert_same_up_to_rounding, sum_order_rtol
from tests.fuzzy.systems import ATT, GPS, ROR

ENGINES = ("compiled", "python")


def one_input(out_terms, rules, ops=None, default=None, fis_type="mamdani"):
    ops = ops or {"and": "min", "or": "max", "implication": "min", "aggregation": "max",
                  "defuzzifier": "centroid"}
    out = {"name": "y", "range": [0.0, 10.0], "terms": out_terms}
    if default is not None:
        out["default"] = default
    return load_fis({
        "format": "fuzzynav-fis", "version": 1, "name": "t", "type": fis_type,
        "operators": ops,
        "inputs": [{"name": "x", "range": [0.0, 1.0], "terms": [
            {"name": "lo", "mf": "tri", "params": [0.0, 0.0, 1.0]},
            {"name": "hi", "mf": "tri", "params": [0.0, 1.0, 1.0]}]}],
        "outputs": [out], "rules": rules})


RULES = [{"if": {"x": "lo"}, "then": {"y": "a"}}, {"if": {"x": "hi"}, "then": {"y": "b"}}]


@pytest.mark.parametrize("engine", ENGINES)
def test_closed_form_centroids(engine):
    # lo(x) = 1 - x, hi(x) = x.  One symmetric triangle fully fired: its centre; a
    # triangle cut by the range end: the centroid of that polygon
    fis = one_input([{"name": "a", "mf": "tri", "params": [2.0, 3.0, 4.0]},
                     {"name": "b", "mf": "tri", "params": [6.0, 10.0, 14.0]}], RULES)
    assert fis.evaluate({"x": 0.0}, engine=engine)["y"] == pytest.approx(3.0, abs=1e-14)
    _, cb = _polygon([(6, 0), (10, 1), (10, 0)])
    assert fis.evaluate({"x": 1.0}, engine=engine)["y"] == pytest.approx(cb, abs=1e-13)
    # x = 0.5: both clipped at 0.5, disjoint: area-weighted mean of the polygons' centroids
    area_a, ca = _polygon([(2, 0), (2.5, 0.5), (3.5, 0.5), (4, 0)])
    area_b, cb = _polygon([(6, 0), (8, 0.5), (10, 0.5), (10, 0)])
    y = fis.evaluate({"x": 0.5}, engine=engine)["y"]
    assert y == pytest.approx((ca * area_a + cb * area_b) / (area_a + area_b), abs=1e-13)


def _polygon(points):
    # area and x-centroid of a polygon (shoelace formula)
    xs, ys = np.array(points + points[:1], dtype=float).T
    cross = xs[:-1] * ys[1:] - xs[1:] * ys[:-1]
    area = cross.sum() / 2
    return abs(area), float(((xs[:-1] + xs[1:]) * cross).sum() / (6 * area))


@pytest.mark.parametrize("engine", ENGINES)
def test_closed_form_bisector_and_maxima(engine):
    ops = {"and": "min", "or": "max", "implication": "min", "aggregation": "max"}
    terms = [{"name": "a", "mf": "trap", "params": [1.0, 2.0, 4.0, 5.0]},
             {"name": "b", "mf": "tri", "params": [6.0, 8.0, 10.0]}]
    x = 0.0  # only rule 1 fires, fully: trapezoid 1-2-4-5
    for method, expected in (("bisector", 3.0), ("mom", 3.0), ("som", 2.0), ("lom", 4.0)):
        fis = one_input(terms, RULES, dict(ops, defuzzifier=method))
        assert fis.evaluate({"x": x}, engine=engine)["y"] == pytest.approx(expected, abs=1e-13)
    # x = 0.75: a clipped at 0.25 stays below b clipped at 0.75 -> plateau [7.5, 8.5]
    for method, expected in (("mom", 8.0), ("som", 7.5), ("lom", 8.5)):
        fis = one_input(terms, RULES, dict(ops, defuzzifier=method))
        assert fis.evaluate({"x": 0.75}, engine=engine)["y"] == pytest.approx(expected,
                                                                             abs=1e-13)


@pytest.mark.parametrize("engine", ENGINES)
def test_sugeno_weighted_average_and_sum(engine):
    # at x = 0.2: lo = 0.8, not hi = 0.8; rule 1 fires 0.8 * 0.5 and outputs 4x + 1
    terms = [{"name": "a", "mf": "linear", "params": [4.0, 1.0]},
             {"name": "b", "mf": "constant", "params": [7.0]}]
    rules = [{"if": {"x": "lo"}, "then": {"y": "a"}, "weight": 0.5},
             {"if": {"x": {"not": "hi"}}, "then": {"y": "b"}}]
    for d, expected in (("wtaver", (0.4 * 1.8 + 0.8 * 7.0) / 1.2),
                        ("wtsum", 0.4 * 1.8 + 0.8 * 7.0)):
        fis = one_input(terms, rules, {"and": "prod", "or": "max", "defuzzifier": d},
                        fis_type="sugeno")
        assert fis.evaluate({"x": 0.2}, engine=engine)["y"] == pytest.approx(expected, abs=1e-13)


@pytest.mark.parametrize("engine", ENGINES)
def test_clamping_is_counted_not_printed(engine, capsys):
    fis = load_fis(GPS)
    out, info = fis.evaluate({"dom_pos": [-5.0, 0.0, 3.0], "dom_vel": 0.0},
                             engine=engine, return_info=True)
    inside = fis.evaluate({"dom_pos": [-1.0, 0.0, 1.0], "dom_vel": 0.0}, engine=engine)
    # exact on purpose: the same engine on the same batch shape, and clamping must land on
    # the range end itself, so the clamped rows are the in-range rows bit for bit
    np.testing.assert_array_equal(out["alpha"], inside["alpha"])
    assert (info.n_samples, info.n_clamped, info.n_no_rule, info.n_nan) == (3, 2, 0, 0)
    np.testing.assert_array_equal(info.status, [1, 0, 1])
    assert capsys.readouterr() == ("", "")


@pytest.mark.parametrize("engine", ENGINES)
def test_no_rule_fired_gives_default_else_midpoint(engine):
    terms = [{"name": "a", "mf": "tri", "params": [2.0, 3.0, 4.0]},
             {"name": "b", "mf": "tri", "params": [6.0, 8.0, 10.0]}]
    rules = [{"if": {"x": "lo"}, "then": {"y": "a"}}]
    for default, expected in ((None, 5.0), (1.5, 1.5)):
        fis = one_input(terms, rules, default=default)
        out, info = fis.evaluate({"x": [1.0, 0.0]}, engine=engine, return_info=True)
        assert out["y"][0] == expected and out["y"][1] == pytest.approx(3.0)
        np.testing.assert_array_equal(info.status, [2, 0])


@pytest.mark.parametrize("mode", ("exact", "sampled"))
def test_nan_input_only_spoils_its_own_sample(mode):
    fis = load_fis(GPS)
    out, info = fis.evaluate({"dom_pos": [0.1, np.nan, 0.3], "dom_vel": [0.2, 0.2, np.nan]},
                             mode=mode, return_info=True)
    a = out["alpha"]
    assert np.isfinite(a[0]) and np.isnan(a[1]) and np.isnan(a[2])
    # a batch of 3 against a single sample: the sampled centroid is a BLAS product whose
    # summation order depends on the number of rows and on the CPU, so the two agree to
    # rounding (a sum of 101 non-negative terms), not to the bit; a spoiled sample would be
    # NaN or far off
    single = fis.evaluate({"dom_pos": 0.1, "dom_vel": 0.2}, mode=mode)["alpha"]
    rtol = ULP_RTOL if mode == "exact" else sum_order_rtol(101)
    assert_same_up_to_rounding(a[0], single, rtol)
    assert info.n_nan == 2


def test_broadcasting_and_scalars():
    fis = load_fis(GPS)
    scalar = fis.evaluate({"dom_pos": 0.3, "dom_vel": -0.2})
    assert isinstance(scalar["alpha"], float)
    grid = fis.evaluate({"dom_pos": np.linspace(-1, 1, 5)[:, None],
                         "dom_vel": np.linspace(-1, 1, 4)[None, :]})["alpha"]
    assert grid.shape == (5, 4)
    # one cell of the grid against a scalar call at the grid's own input values (1/3 and
    # linspace's 1/3 may differ by an ulp); batch against scalar: to rounding
    one = fis.evaluate({"dom_pos": -0.5, "dom_vel": np.linspace(-1, 1, 4)[2]})["alpha"]
    assert_same_up_to_rounding(grid[1, 2], one)
    empty = fis.evaluate({"dom_pos": np.zeros(0), "dom_vel": 0.0})["alpha"]
    assert empty.shape == (0,)


def test_paper_rule_files_reproduce_their_provenance_numbers():
    # centroid of one fully fired triangle: its peak; of a half triangle cut by the range:
    # a third of its half-width from the edge (numbers quoted in each file's provenance)
    gps = load_fis(GPS)
    assert gps.evaluate({"dom_pos": 0.0, "dom_vel": 0.0})["alpha"] == pytest.approx(1.10)
    assert gps.evaluate({"dom_pos": -1.0, "dom_vel": 0.0})["alpha"] == pytest.approx(1 + 0.05 / 3)
    assert gps.evaluate({"dom_pos": 0.0, "dom_vel": 1.0})["alpha"] == pytest.approx(1.15 - 0.05 / 3)
    ror = load_fis(ROR)
    t = ror.evaluate({"ror": [0.0, 1.0, 2.5, 9.0]})["t"]
    np.testing.assert_allclose(t, [0.75, 1.0, 1.25, 1.25], atol=1e-14)
    att = load_fis(ATT)
    a = att.evaluate({"dom_att": [-1.0, 0.0, 1.0]})["alpha"]
    np.testing.assert_allclose(a, [1 + 0.05 / 3, 1.05, 1.1 - 0.05 / 3], atol=1e-14)


@pytest.mark.parametrize("bad,match", [
    ({"dom_pos": 0.0}, "missing: \\['dom_vel'\\]"),
    ({"dom_pos": 0.0, "dom_vel": 0.0, "typo": 1.0}, "unknown: \\['typo'\\]"),
    ({"dom_pos": [0.0, 1.0], "dom_vel": [0.0, 1.0, 2.0]}, "do not broadcast"),
    ({"dom_pos": "a", "dom_vel": 0.0}, "numbers"),
])
def test_bad_inputs_raise_one_clear_error(bad, match):
    with pytest.raises(FisEvaluationError, match=match):
        load_fis(GPS).evaluate(bad)


def test_bad_mode_engine_and_points():
    fis = load_fis(GPS)
    x = {"dom_pos": 0.0, "dom_vel": 0.0}
    with pytest.raises(FisEvaluationError, match="mode"):
        fis.evaluate(x, mode="fast")
    with pytest.raises(FisEvaluationError, match="engine"):
        fis.evaluate(x, engine="gpu")
    with pytest.raises(FisEvaluationError, match="n_points"):
        fis.evaluate(x, mode="sampled", n_points=1)
