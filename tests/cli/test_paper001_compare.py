"""``fuzzynav compare paper001`` with the pairs: the paper's claims beside ours."""
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
