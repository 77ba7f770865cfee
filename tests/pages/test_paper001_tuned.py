"""paper001's paired and magnetometer-use tables on hand-made frames."""
import pandas as pd

from fuzzynav.papers.paper001 import page_tuned as pt


def _frame(a, b, key_a="centralized, fuzzy R on the magnetometer"):
    n = len(a)
    return pd.DataFrame({"filter": [key_a] * n + [pt.REF] * n, "seed": list(range(n)) * 2,
                         "rms_pos_h_m": [*a, *b], "rms_heading_deg": [*a, *b]})


def test_paired_difference_cancels_the_spread_between_seeds():
    # the seeds differ by 100 m, the fuzzy filter is 1 m better on every one: the paired
    # CI is a point at -1, an unpaired one would span the seeds' spread
    a = [1.0, 101.0, 201.0]
    b = [2.0, 102.0, 202.0]
    table = pt.paired_table({"s": _frame(a, b)}, {"centralized, fuzzy R on the magnetometer": 1,
                                                  pt.REF: 1})
    row = [line for line in table.splitlines() if line.startswith("| centralized, fuzzy")]
    assert len(row) == 1 and "-1 [-1, -1] / -1 [-1, -1]" in row[0]


def test_pairs_absent_from_the_page_are_left_out():
    table = pt.paired_table({"s": _frame([1.0], [2.0])}, {pt.REF: 1})
    assert len(table.splitlines()) == 2  # the header only


def test_constant_r_left_out_and_switched_off_named():
    df = pd.DataFrame({"filter": ["const", "off", "off"],
                       "r_use_median_calm": [1.0, 20.0, 40.0],
                       "r_use_median_zone": [1.0, 50.0, 50.0],
                       "r_use_off_calm": [0.0, 0.9, 1.0], "r_use_off_zone": [0.0, 1.0, 1.0]})
    text = pt.usage_table(df, ["const", "off"])
    assert "| const |" not in text
    assert "| off | 30.00 | 50.00 | 95% | 100% |" in text
    assert text.rstrip().endswith("switched the sensor off: off.")


def _bank_runs(factor):
    metrics = ("rms_pos_m", "rms_vel_mps", "rms_att_deg")
    rows = []
    for seed in range(6):
        rows.append({"filter": pt.FEDERATED, "seed": seed, "r_use_dev_calm": 1.0,
                     **{m: 2.0 + seed for m in metrics}})
        rows.append({"filter": pt.BANK_DESIGN, "seed": seed, "r_use_dev_calm": 1.0,
                     **{m: (2.0 + seed) * factor(seed) for m in metrics}})
    return pd.DataFrame(rows)


def test_bank_against_federated_pooled_over_tunings():
    # the bank halves every RMS of federated-p001 (a little less on later seeds) in each
    # tuning: score (3 x ~0.5 + 0.1 x 1) / 3.1 ~ 0.52 against 1, a win in every tuning
    df = _bank_runs(lambda seed: 0.5 + 0.01 * seed)
    dfs = {"s": df}
    filters = {pt.BANK_DESIGN: "federated-fuzzy-beta@" + "+".join(pt.TUNED_BANK), pt.FEDERATED: "x"}

    def run(specs):
        assert list(specs) == [pt.BANK_DESIGN] and "_t" in specs[pt.BANK_DESIGN]  # a further tuning's files
        return {"s": df[df["filter"] == pt.BANK_DESIGN]}

    text = "\n".join(pt.bank_vs_federated(dfs, filters, run))
    row = [line for line in text.splitlines() if line.startswith("| `s` |")]
    assert len(row) == 1
    assert row[0].count("**win**") == 3 and "**wins against**" in row[0]
    assert "-0.4" in row[0]
    assert "1 / 0 / 0" in text


def test_bank_against_federated_needs_both():
    df = _bank_runs(lambda seed: 1.0)
    assert pt.bank_vs_federated({"s": df}, {pt.BANK_DESIGN: "x"}, None) == []
