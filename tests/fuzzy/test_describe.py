"""Text views of a fuzzy system."""
from fuzzynav.fuzzy import load_fis
from fuzzynav.fuzzy.describe import rule_grid, rule_lines, rule_markdown


def test_grid_of_the_paper_table():
    head, rows = rule_grid(load_fis("rules/paper000_gps_sins.json"))
    assert head == ["dom_pos \\ dom_vel", "NS", "ZE", "PS"]
    # Table 1 of paper 000 (DIGEST.md): rows DoM_pos, columns DoM_V
    assert rows == [["NS", "medium", "zero", "small"], ["ZE", "small", "medium", "large"],
                    ["PS", "medium", "large", "zero"]]


def test_one_input_systems_are_listed():
    fis = load_fis("rules/paper002_ror.json")
    assert rule_grid(fis) is None
    assert rule_lines(fis)[0] == "if ror is less1 then t is less1"
    assert rule_markdown(fis).startswith("- if ror is less1")
