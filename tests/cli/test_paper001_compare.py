"""``fuzzynav compare paper001`` with the pairs: the paper's claims beside ours."""
import json

from tests.cli.test_nav_commands import _run


def test_compare_paper001_pairs_prints_the_claims(capsys, sim_cache):
    code, out, _ = _run(capsys, "compare", "paper001", "--filters",
                        "centralized,ekf-bds-pol,fuzzy-bds-mag", "--cache", str(sim_cache))
    assert code == 0
    assert "ekf-bds-pol vs centralized" in out and "paper combined (claim)" in out
    assert "3.2305" in out and "3.7419" in out and "pol pair best" in out


def test_a_filter_without_rules_refuses_them_on_a_pair(capsys, sim_cache):
    code, _, err = _run(capsys, "compare", "paper001", "--filters",
                        "centralized,ekf-bds-mag@rules/paper001_mag.json", "--cache",
                        str(sim_cache))
    assert code == 2 and "takes no rule files" in err


def test_compare_paper001_with_the_federated_filters(capsys, sim_cache):
    filters = "centralized,federated-p001,federated-fuzzy,ekf-bds-pol"
    code, out, _ = _run(capsys, "compare", "paper001", "--filters", filters, "--mc", "2",
                        "--cache", str(sim_cache), "--json")
    assert code == 0
    doc = json.loads(out)["filters"]
    assert set(doc) == set(filters.split(","))
    # the 8-deg magnetometer anomaly: the plain bank's heading is off by over a degree on
    # average over the run, the fuzzy magnetometer local keeps it near the polarization
    # compass's (~0.05 deg), as the pair without the magnetometer does
    assert doc["federated-p001"]["rms_heading_deg"]["mean"] > 0.5
    assert doc["federated-fuzzy"]["rms_heading_deg"]["mean"] < 0.2
    code, out, _ = _run(capsys, "compare", "paper001", "--filters", filters, "--mc", "1",
                        "--cache", str(sim_cache))
    assert code == 0 and "federated-fuzzy vs centralized" in out and "3.2305" in out
