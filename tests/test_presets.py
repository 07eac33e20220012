"""Built-in presets (core.moving.presets): format, descriptions, and the answer each one promises."""

import json

import pytest

from core import Relation, analyse, motion_from_dict, preset, preset_names
from core.moving.presets import PRESETS, preset_arguments

S, T_, O = Relation.SEPARATE, Relation.TANGENT, Relation.OVERLAP

# what each preset's description promises, verified independently in tests/test_parametric.py
# (paper examples) or by hand (2D): (event relations/kinds, interval relations)
EXPECTED = {
    "example-29": (["change", "change"], [S, O, S]),
    "example-30": (["change"] * 4, [S, O, S, O, S]),
    "example-31": (["touch"], [S, S]),
    "example-32": (["change", "change"], [O, S, O]),
    "example-33": ([], [T_]),
    "circles-crossing": (["change", "change"], [S, O, S]),
    "circles-graze": (["touch"], [S, S]),
    "ellipse-spin": (["touch"], [S, S]),
    "circles-sqrt2": (["change", "change"], [S, O, S]),
    "circles-endpoint": (["endpoint"], [S]),
}


def test_names_and_paper_examples_first():
    names = preset_names()
    assert names[:5] == [f"example-{k}" for k in range(29, 34)]
    assert set(names) == set(EXPECTED)


@pytest.mark.parametrize("name", list(PRESETS))
def test_format(name):
    p = preset(name)
    assert p["name"] == name and isinstance(p["description"], str) and 10 < len(p["description"]) < 200
    assert "\n" not in p["description"]
    json.dumps(p)  # plain JSON
    for key in "AB":
        motion_from_dict(p[key])
    lo, hi = p["interval"]
    assert (lo is None or isinstance(lo, str)) and (hi is None or isinstance(hi, str))


@pytest.mark.parametrize("name", list(PRESETS))
def test_preset_answers(name):
    r = analyse(**preset_arguments(name))
    kinds, rels = EXPECTED[name]
    assert [e.kind for e in r.events] == kinds
    assert all(e.relation == T_ for e in r.events)
    assert [iv.relation for iv in r.intervals] == rels


def test_preset_is_a_copy():
    p = preset("example-31")
    p["A"]["translation"][1] = "8"
    assert preset("example-31")["A"]["translation"][1] == "7"
    with pytest.raises(ValueError, match="unknown preset 'nope'; available: example-29"):
        preset("nope")
