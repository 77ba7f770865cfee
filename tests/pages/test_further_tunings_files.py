"""The further tunings shipped for the paper pages (issue 25: tuning variance): each `_t<k>`
study file is its first tuning's file with nothing changed but its name, sampler seed and
the names of its outputs and parents, its outputs exist, and the page code reads them."""
import json
import tomllib
from pathlib import Path

import pytest

from fuzzynav.pages import science_split_tunings as st
from fuzzynav.pages.science_splits import AKIT_FOLDS

ROOT = Path(__file__).resolve().parents[2]

#: first tuning's study -> the sampler seeds of tunings 0, 1, 2
FAMILIES = {
    "studies/paper000_baselines.toml": (0, 1, 2),
    "studies/paper000_fuzzy_sage_husa.toml": (0, 1, 2),
    "studies/paper000_fuzzy_vb.toml": (0, 1, 2),
    "studies/paper000_fuzzy_huber.toml": (0, 1, 2),
    "studies/paper000_tune.toml": (0, 1, 2),
    "studies/paper000_rscale_tune.toml": (0, 1, 2),
    "studies/paper001_beta_tune.toml": (0, 100, 200),
    "studies/paper004_apso.toml": (4, 104, 204),
    "studies/paper004_apso_rev.toml": (4, 104, 204),
}


def _load(path: str) -> dict:
    return tomllib.loads((ROOT / path).read_text(encoding="utf-8"))


def _strip(doc: dict, k: int) -> dict:
    """The study with what a further tuning may change put back to the first's form."""
    doc = json.loads(json.dumps(doc))
    doc.pop("name", None)
    doc["study"].pop("seed", None)
    out = doc.get("baselines", {}).get("out")
    if out:
        doc["baselines"]["out"] = out.replace(f"_t{k}.json", ".json")
    for c in doc.get("controllers", []):
        if "parent" in c:
            c["parent"] = c["parent"].replace(f"_t{k}.json", ".json")
    return doc


@pytest.mark.parametrize("first", sorted(FAMILIES))
def test_further_tunings_change_only_seed_and_names(first):
    base = _load(first)
    seeds = FAMILIES[first]
    assert base["study"]["seed"] == seeds[0]
    for k in (1, 2):
        other = _load(st.tuning_file(first, k))
        assert other["name"] == f"{base['name']}_t{k}"
        assert other["study"]["seed"] == seeds[k]
        assert _strip(other, k) == _strip(base, 0)
    assert st.sampler_seeds(first, [0, 1, 2], ROOT) == list(seeds)


def test_apso_has_the_fuzzy_studys_budget():
    for fold in ("", "_rev"):
        apso = _load(f"studies/paper004_apso{fold}.toml")["study"]
        fuzzy = _load(f"studies/paper004_fuzzy{fold}.toml")["study"]
        assert apso["trials"] == apso["pso"]["particles"] * apso["pso"]["iterations"]
        assert apso["trials"] == fuzzy["trials"]


@pytest.mark.parametrize("k", [1, 2])
def test_each_fold_carries_its_apso_tuning(k):
    for fold in AKIT_FOLDS:
        sp = st.split_of(fold, k)
        assert sp.apso == st.tuning_file(fold.apso, k)
        doc = json.loads((ROOT / sp.apso).read_text())
        assert doc["study"] == Path(fold.apso).stem + f"_t{k}"
        assert doc["trials"]["apso"] == 150
    # the APSO training scores enter the tunings' training table, one per tuning
    train = st._split_training(AKIT_FOLDS[0], [0, 1, 2], ROOT)
    assert len(train["apso"]) == 3 and all(0 < v < 2 for v in train["apso"])


def test_paper001_bank_tunings_are_shipped_and_named_by_the_page():
    from fuzzynav.papers.paper001 import page_tuned as pt

    for k in (0, 1, 2):
        for f in pt.TUNED_BANK:
            doc = json.loads((ROOT / st.tuning_file(f, k)).read_text())
            assert doc["provenance"]["study"] == "paper001_beta_tune" + (f"_t{k}" if k else "")
            # tuned on the runs and with the objective of the classical filters
            assert doc["provenance"]["objective"]["weights"]["r_use"] == 0.1
    assert pt.BANK_DESIGN in pt.DESIGNS and pt.DESIGN_FILES[pt.BANK_DESIGN] == pt.TUNED_BANK[0]


def test_paper000_tunings_are_shipped_for_every_tuned_filter():
    from fuzzynav.papers.paper000 import page

    tuned = [*page.DESIGNS, *page.POOL]
    files = [f for label in tuned for f in page.FILTERS[label].partition("@")[2].split("+")]
    assert len(files) == len(tuned) + 1  # the alpha design has two rule files
    assert st.tunings_present(files, 3, ROOT) == [0, 1, 2]
    for k in (1, 2):
        params = json.loads((ROOT / st.tuning_file(page.BASELINES, k)).read_text())
        assert params["study"] == f"paper000_baselines_t{k}"
        for label, f in page.DESIGN_FILES.items():
            prov = json.loads((ROOT / st.tuning_file(f, k)).read_text())["provenance"]
            assert prov["study"].endswith(f"_t{k}"), (label, prov["study"])


def test_apso_multipliers_at_their_bounds_are_named(tmp_path, monkeypatch):
    from dataclasses import replace

    from fuzzynav.papers.paper004 import page_heldout as ph

    (tmp_path / "studies").mkdir()
    values = {0: {"q_att": 0.01, "q_vel": 3.0, "r_all": 100.0},  # two ends
              1: {"q_att": 1.0, "q_vel": 3.0, "r_all": 1.0}}      # inside the box
    for k, params in values.items():
        (tmp_path / st.tuning_file("studies/a.json", k)).write_text(
            json.dumps({"filters": {"apso": params}}))
    monkeypatch.setattr(ph, "ROOT", tmp_path)
    fold = replace(AKIT_FOLDS[0], apso="studies/a.json")
    lines = ph.apso_bounds_lines([fold])
    hits = [line for line in lines if line.startswith("- ")]
    assert len(hits) == 1 and "tuning 0" in hits[0]
    assert "q_att = 0.01 at the lower end" in hits[0] and "r_all = 100 at the upper end" in hits[0]
    assert "q_vel" not in hits[0]
    assert ph.apso_bounds_lines([replace(fold, apso="studies/none.json")]) == []
