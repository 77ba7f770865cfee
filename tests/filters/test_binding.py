"""Rule-file bindings: parsed once into a frozen dataclass, every mistake one clear line."""
import copy
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.filters import measurements
from fuzzynav.filters.adaptation.binding import Binding
from fuzzynav.filters.catalog import bind_systems
from fuzzynav.filters.named import get_filter
from fuzzynav.fuzzy import load_fis
from fuzzynav.sim.sensors import SensorData

RULES = Path(__file__).resolve().parents[2] / "rules"
GPS = RULES / "paper000_gps_sins.json"
SHIPPED = sorted(RULES.glob("*.json"))


def _doc(path=GPS):
    return json.loads(path.read_text(encoding="utf-8"))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_every_shipped_binding_parses_and_writes_back_unchanged(path):
    doc = _doc(path)
    b = Binding.of(load_fis(path), str(path))
    # the JSON on disk is the contract: to_dict gives back exactly what the file holds
    assert b.to_dict() == doc["binding"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        b.window = 3


def test_the_parsed_binding_of_paper000_gps():
    b = Binding.of(load_fis(GPS), "g.json")
    assert (b.adapter, b.window, b.sensor, b.normalisation) == \
        ("exponential-weighting", 20, None, "relative-trace")
    assert [(i.name, i.statistic, i.channel) for i in b.inputs] == \
        [("dom_pos", "dom", "pos"), ("dom_vel", "dom", "vel")]
    assert b.channels == ("pos", "vel")


def _error(mutate, path=GPS) -> str:
    doc = _doc(path)
    mutate(doc["binding"])
    with pytest.raises(InputFileError) as info:
        Binding.of(load_fis(doc), "bad.json")
    assert "\n" not in str(info.value)
    return str(info.value)


def _set(path, value):
    """A mutation setting ``binding[path...] = value`` (``None``: delete the key)."""
    def mutate(b):
        node = b
        for key in path[:-1]:
            node = node[key]
        if value is None:
            del node[path[-1]]
        else:
            node[path[-1]] = value
    return mutate


@pytest.mark.parametrize("path, value, message", [
    (("windw",), 20, "bad.json: $.binding.windw: unknown key 'windw'; known: adapter, "
                     "inputs, outputs, window, sensor, normalisation"),
    (("inputs", "dom_pos", "chanel"), "pos",
     "bad.json: $.binding.inputs.dom_pos.chanel: unknown key 'chanel'; known: statistic, "
     "channel"),
    (("inputs", "dom_pos", "statistic"), "median",
     "bad.json: $.binding.inputs.dom_pos.statistic: unknown statistic 'median'; known: dom, "
     "ror"),
    (("inputs", "dom_pos", "channel"), "posiiton",
     "bad.json: $.binding.inputs.dom_pos.channel: unknown channel 'posiiton'; known: "),
    (("inputs", "dom_vel"), None,
     "bad.json: $.binding.inputs.dom_vel: missing: say which statistic feeds this input"),
    (("inputs", "dom_att"), {"statistic": "dom", "channel": "heading"},
     "bad.json: $.binding.inputs.dom_att: names no input of the fuzzy system (inputs: "
     "dom_pos, dom_vel)"),
    (("outputs", "alpha"), "r_scale",
     "bad.json: $.binding.outputs.alpha: unknown target 'r_scale'; this adapter's output "
     "drives 'alpha'"),
    (("outputs",), {}, "bad.json: $.binding.outputs: bind exactly one output to 'alpha'"),
    (("window",), 0, "bad.json: $.binding.window: must be an integer number of epochs in "
                     "1..10000, got 0"),
    (("window",), 2.5, "bad.json: $.binding.window: must be an integer"),
    (("normalisation",), "absolute",
     "bad.json: $.binding.normalisation: unknown normalisation 'absolute'; known: "
     "relative-trace"),
    (("adapter",), "sage-husa",
     "bad.json: $.binding.adapter: unknown fuzzy adapter 'sage-husa'; known: "
     "exponential-weighting, fuzzy-huber, fuzzy-sage-husa, fuzzy-vb, r-scaling"),
    (("sensor",), "", "bad.json: $.binding.sensor: must name a sensor or sensor kind"),
])
def test_a_malformed_binding_is_one_line_naming_file_and_json_path(path, value, message):
    assert _error(_set(path, value)).startswith(message)


def test_an_unknown_channel_lists_the_channels_of_every_measurement_model():
    msg = _error(_set(("inputs", "dom_pos", "channel"), "posiiton"))
    for model in measurements.MODELS.load().values():
        for chan in model.channels:
            assert chan in msg.split("known: ")[1].split(", ")


def test_a_binding_is_required_and_must_be_an_object():
    doc = _doc()
    doc["binding"] = {"adapter": "exponential-weighting", "inputs": []}
    with pytest.raises(InputFileError, match=r"\$\.binding\.inputs: must be a JSON object, "
                                             r"got list"):
        Binding.of(load_fis(doc), "bad.json")
    del doc["binding"]
    with pytest.raises(InputFileError, match=r"bad\.json: \$\.binding: missing"):
        Binding.of(load_fis(doc), "bad.json")


def _sensor(kind, m):
    return SensorData(kind, np.zeros(1), np.zeros((1, m)), np.ones((1, m)))


def test_a_channel_the_named_sensors_model_lacks_is_refused_at_bind_time():
    # "heading" is a known channel (of the polarization model), but not of gnss
    doc = _doc()
    doc["binding"]["inputs"]["dom_pos"]["channel"] = "heading"
    doc["binding"]["sensor"] = "gnss"
    with pytest.raises(InputFileError, match=r"^bad\.json: \$\.binding\.inputs\.dom_pos\."
                                             r"channel: the gnss model has no channel "
                                             r"'heading' \(channels: pos, vel, all\)$"):
        bind_systems([(load_fis(doc), "bad.json")], {"gps": _sensor("gnss", 6)})


def test_binding_systems_parses_each_binding_once_and_hands_it_to_the_policy():
    fis = load_fis(GPS)
    bound = bind_systems([(fis, "g.json")], {"gps": _sensor("gnss", 6)})
    assert bound["gps"].binding == Binding.of(fis, "g.json")
    assert bound["gps"].channels == ("pos", "vel")


def test_normalisation_is_written_only_where_a_dom_input_reads_it():
    ror = Binding.of(load_fis(RULES / "paper002_ror.json"))
    assert ror.normalisation == "relative-trace" and "normalisation" not in ror.to_dict()
    doc = copy.deepcopy(_doc())
    del doc["binding"]["normalisation"]  # the default is the only normalisation there is
    assert Binding.of(load_fis(doc)).normalisation == "relative-trace"


def test_fuzzy_is_the_filter_and_fakf_its_listed_alias():
    fuzzy, fakf = get_filter("fuzzy"), get_filter("fakf")
    assert fakf.make is fuzzy.make
    assert fakf.description == "alias of 'fuzzy'"


def test_fis_check_refuses_a_bad_binding_in_one_line(tmp_path, capsys):
    from fuzzynav.cli import main

    doc = _doc()
    doc["binding"]["inputs"]["dom_pos"] = {"statistic": "dom", "chanel": "pos"}
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    code = main(["fis", "check", str(path)])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.strip().splitlines() == [f"fuzzynav: error: {path}: $.binding.inputs.dom_pos."
                                        f"chanel: unknown key 'chanel'; known: statistic, "
                                        f"channel"]


def _remapped(doc, out_index, lo, hi):
    """``doc`` with output ``out_index`` mapped affinely onto ``[lo, hi]`` (its terms and
    default too, so that only the range is wrong)."""
    doc = copy.deepcopy(doc)
    out = doc["outputs"][out_index]
    a, b = out["range"]

    def f(v):
        return lo + (v - a) * (hi - lo) / (b - a)
    out["range"] = [lo, hi]
    for term in out["terms"]:
        term["params"] = [f(v) for v in term["params"]]
    if out.get("default") is not None:
        out["default"] = f(out["default"])
    return doc


@pytest.mark.parametrize("name, out_index, lo, hi, target", [
    ("paper000_select_gnss.json", 0, -2.0, -0.5, "r_scale"),   # a factor below zero
    ("paper000_select_gnss.json", 0, 1e5, 1e9, "r_scale"),     # beyond the running bounds
    ("paper000_rq_gnss.json", 1, 0.5, 500.0, "q_scale"),      # beyond the level's 1e2
    ("paper000_gps_sins.json", 0, 0.0, 1.1, "alpha"),         # raised to 0.1 silently
    ("paper001_beta.json", 0, -1.0, 1.2, "beta"),             # a negative weight
])
def test_an_output_range_outside_its_targets_domain_is_refused(tmp_path, capsys, name,
                                                               out_index, lo, hi, target):
    """These were clamped in the kernel while ``fis check`` said OK."""
    from fuzzynav.cli import main
    from fuzzynav.fuzzy.io import from_dict

    doc = _remapped(_doc(RULES / name), out_index, lo, hi)
    with pytest.raises(InputFileError, match=rf"\$\.outputs\[{out_index}\]\.range.*{target}"):
        Binding.of(from_dict(doc), "x.json")
    path = tmp_path / name
    path.write_text(json.dumps(doc), encoding="utf-8")
    code = main(["fis", "check", str(path)])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and f"outside what '{target}' can take" in err


def test_an_output_range_at_its_domains_edges_is_accepted():
    from fuzzynav.filters.adaptation.r_scaling import S_MAX, S_MIN
    from fuzzynav.fuzzy.io import from_dict

    doc = _remapped(_doc(RULES / "paper000_select_gnss.json"), 0, S_MIN, S_MAX)
    assert Binding.of(from_dict(doc), "x.json").adapter == "r-scaling"
