"""`recreate`: which tests are drawn, the effort ordering, and the sheets a technician prints.
Runs come from the real search loop with test doubles (no Blender)."""
import itertools
import json

import numpy as np
import pytest

from isu_validate.analysis.runs import load_run
from isu_validate.cli import main
from isu_validate.recreate.effort import EffortError, best_order, load_effort, path_cost
from isu_validate.recreate.guide import checklist
from isu_validate.recreate.select import select
from isu_validate.search import run_search
from isu_validate.space import load_space, space_from_dict
from tests.test_run import config


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    path = tmp_path_factory.mktemp("runs") / "run"
    run_search(config(path, budget_tests=36))
    return path


def test_selection_draws_failing_passing_or_the_runs_share(run_dir):
    run = load_run(run_dir)
    failing, passing = len({r.scene_key for r in run.failures}), len({r.scene_key for r in run.valid if not r.failed})
    assert failing and passing
    picked = select([run], "failing", 5, seed=1).chosen
    assert len(picked) == 5 and all(c.failed for c in picked)
    assert [c.position for c in picked] == sorted(c.position for c in picked)   # in run order
    assert all(not c.failed for c in select([run], "passing", 3, seed=1).chosen)
    mixed = select([run], "mixed", 10, seed=2)
    share = mixed.available_failing / (mixed.available_failing + mixed.available_passing)
    assert sum(c.failed for c in mixed.chosen) == round(10 * share)
    assert sum(c.failed for c in select([run], "mixed", 10, seed=2, failing_share=0.3).chosen) == 3
    assert [c.record.test_id for c in select([run], "failing", 5, seed=1).chosen] == [c.record.test_id for c in picked]
    many = select([run], "passing", 1000, seed=0)
    assert len(many.chosen) == many.available_passing and "taking all" in many.notes[0]


def test_the_order_never_costs_more_than_the_run_order_and_is_exact_when_small(run_dir):
    space = load_space()
    model = load_effort("default", space)
    scenes = [r.canonical for r in load_run(run_dir).valid]
    rng = np.random.default_rng(0)
    for n in (2, 5, 7, 9, 14, 20):
        chosen = [scenes[i] for i in rng.choice(len(scenes), n, replace=False)]
        setup, cost = model.matrix(chosen)
        order = best_order(setup, cost)
        assert sorted(order) == list(range(n))
        assert path_cost(setup, cost, order) <= path_cost(setup, cost, list(range(n))) + 1e-9
        if n <= 7:   # against every permutation
            brute = min(path_cost(setup, cost, p) for p in itertools.permutations(range(n)))
            assert path_cost(setup, cost, order) == pytest.approx(brute)


def test_change_costs_count_a_group_once_and_respect_tolerance():
    space = load_space()
    model = load_effort("default", space)
    a = space.canonical({**space.sample(np.random.default_rng(0), 1)[0], "luggage": "YES",
                         "luggage_position": "BACK", "luggage_colour": "YELLOW", "luggage_orientation": 60.0})
    b = dict(a, driver_gender="FEMALE" if a["driver_gender"] == "MALE" else "MALE",
             driver_height="H4" if a["driver_height"] != "H4" else "H1")
    assert [g.name for g in model.changed(a, b)] == ["person"]
    assert model.step(a, b) == model.per_scene + 15.0
    c = dict(a, luggage_orientation=63.0)   # within the 5 degree tolerance: nothing to do
    assert model.changed(a, c) == [] and model.step(a, c) == model.per_scene
    assert [g.name for g in model.changed(a, dict(a, luggage_orientation=70.0))] == ["luggage_angle"]
    d = {k: v for k, v in a.items() if not k.startswith("luggage_")} | {"luggage": "NO"}
    assert [g.name for g in model.changed(a, d)] == ["luggage", "luggage_angle"]   # gone counts as changed


def test_effort_files_are_checked(tmp_path):
    space = load_space()
    bad = tmp_path / "bad.toml"
    bad.write_text('[groups.a]\nfeatures = ["seat_belt"]\nminutes = 1\n'
                   '[groups.b]\nfeatures = ["seat_belt"]\nminutes = 2\n')
    with pytest.raises(EffortError, match="another group"):
        load_effort(bad, space)
    bad.write_text('[groups.a]\nfeatures = ["seat_belt"]\nminutes = -1\n')
    with pytest.raises(EffortError, match="minutes >= 0"):
        load_effort(bad, space)
    ok = tmp_path / "ok.toml"
    ok.write_text('default = 2\n[groups.a]\nfeatures = ["seat_belt", "no_such_feature"]\nminutes = 1\n')
    model = load_effort(ok, space)
    assert model.unused == ["no_such_feature"]
    minutes = {g.name: g.minutes for g in model.groups}
    assert minutes["a"] == 1.0 and minutes["tshirt_colour"] == 2.0


SPACE = {"name": "words", "features": {
    "driver_height": {"type": "ordinal", "values": ["H1", "H2"], "label": "driver's height",
                      "describe": {"H1": "1.50-1.60 m"}},
    "luggage": {"type": "categorical", "values": ["YES", "NO"], "predicted": True, "question": "Luggage?",
                "options": ["YES", "NO"], "label": "suitcase"},
    "luggage_position": {"type": "categorical", "values": ["PASSENGER", "BACK"], "active_when": {"luggage": "YES"}},
    "luggage_colour": {"type": "categorical", "values": ["YELLOW", "ANTHRACITE"], "active_when": {"luggage": "YES"}},
    "luggage_orientation": {"type": "continuous", "low": 20, "high": 140, "unit": "deg",
                            "active_when": {"luggage": "YES"}}}}


def test_the_checklist_has_only_active_features_in_words_with_cabin_measurements():
    from isu_validate.render.cabin import load_cabin
    space = space_from_dict(SPACE)
    cabin = load_cabin("default")
    items = {i.feature: i for i in checklist(space, {"driver_height": "H1", "luggage": "NO"}, cabin)}
    assert set(items) == {"driver_height", "luggage"}     # no suitcase place, colour or angle without a suitcase
    assert items["driver_height"].title == "driver's height" and items["driver_height"].text == "1.50-1.60 m"
    scene = {"driver_height": "H2", "luggage": "YES", "luggage_position": "BACK", "luggage_colour": "ANTHRACITE",
             "luggage_orientation": 75.0}
    items = {i.feature: i for i in checklist(space, scene, cabin)}
    assert items["driver_height"].text == "H2" and items["luggage_colour"].text == "anthracite"
    where = items["luggage_position"].placement
    assert where.point == tuple(cabin["anchors"]["luggage_BACK"]) and where.angle_deg == 75.0
    assert "x = -0.86 m" in where.text and items["luggage_orientation"].text.startswith("75°")
    with pytest.raises(ValueError, match="not values of the feature"):
        space_from_dict({"features": {"a": {"type": "categorical", "values": ["X"], "describe": {"Y": "why"}}}})


def test_the_things_on_the_co_driver_seat_are_placed_where_the_rig_renders_them():
    from isu_validate.render.cabin import load_cabin
    space, cabin = load_space(), load_cabin("default")
    scene = {**space.sample(np.random.default_rng(0), 1)[0], "child_seat": "NO", "luggage": "NO",
             "phone_codriver_seat": "YES", "colacan_codriver_seat": "YES", "colabottle_codriver_seat": "NO"}
    items = {i.feature: i for i in checklist(space, scene, cabin)}
    phone = items["phone_codriver_seat"]
    spot = cabin["codriver_seat"]["phone_codriver_seat"]
    assert phone.title == "K1 phone on the co-driver seat" and "screen up" in phone.text
    assert phone.placement.point == tuple(spot["position"]) and phone.placement.angle_deg == spot["rotation_deg"][2]
    assert phone.crop_parts == ("phone_codriver_seat",)
    assert (items["colacan_codriver_seat"].placement.point
            == tuple(cabin["codriver_seat"]["colacan_codriver_seat"]["position"]))
    assert items["colabottle_codriver_seat"].placement is None   # NO: nothing to place


def test_recreate_writes_pairs_sheets_and_the_effort_against_the_run_order(run_dir, tmp_path, capsys):
    out = tmp_path / "pairs"
    assert main(["recreate", str(run_dir), "--select", "mixed", "--n", "6", "--seed", "3", "--out", str(out),
                 "--sheet-preset", "run", "--json"]) == 0   # the run's frames: no Blender here
    plan = json.loads(capsys.readouterr().out)
    assert plan["minutes"] <= plan["run_order_minutes"]
    names = [s["sample"] for s in plan["samples"]]
    assert names == ["S01", "S02", "S03", "S04", "S05", "S06"]
    for s in plan["samples"]:
        sample = out / s["sample"]
        label = run_dir / "labels" / f"{s['test_id']}.json"
        assert (sample / "scene.json").read_bytes() == label.read_bytes()   # the run's label, unchanged
        assert (sample / "sim.png").is_file() and (sample / "camera.toml").is_file()
        sheet = (sample / "sheet.html").read_text()
        scene = json.loads(label.read_text())["scene"]
        colour = load_space().features["luggage_colour"].display_name   # the space's own words for it
        assert (colour in sheet) == ("luggage_colour" in scene)
        assert 'src="sim.png"' in sheet
    index = (out / "index.html").read_text()
    assert index.count('class="sheet"') == 6 and "@page{size:A4" in index and "in the run&#x27;s order" in index
    manifest = json.loads((out / "pairs.json").read_text())
    assert manifest["effort"]["minutes"] == plan["minutes"] and manifest["space"] == "isu-paper"
    assert main(["recreate", str(run_dir), "--out", str(out)]) == 2   # never over a pairs directory in use
    assert "not empty" in capsys.readouterr().err
    assert main(["recreate", str(run_dir), "--out", str(tmp_path / "other"), "--sheet-preset", "best"]) == 2
    assert "unknown --sheet-preset 'best'" in capsys.readouterr().err


def test_the_sketch_keeps_every_label_off_the_markers():
    """Seat names, angles, 'origin' and 'camera' are laid out apart from the numbered markers (they used
    to sit on the passenger seat's name when the co-driver seat held things)."""
    import re

    from isu_validate.recreate.sketch import CHAR_W, FONT, MARKER_R, top_view
    from isu_validate.render.cabin import load_cabin
    space, cabin = load_space(), load_cabin("default")
    scene = {"driver_gender": "FEMALE", "driver_emotion": "HAPPY", "driver_height": "H2", "driver_weight": "W2",
             "phone_position": "P5", "seat_belt": "YES", "tshirt_colour": "WHITE", "child_seat": "NO", "child": "NO",
             "car_lights": "OFF", "external_light": "MEDIUM", "luggage": "YES", "luggage_orientation": 60.0,
             "luggage_position": "BACK", "luggage_colour": "ANTHRACITE", "phone_codriver_seat": "YES",
             "colacan_codriver_seat": "YES", "colabottle_codriver_seat": "YES"}
    svg = top_view(cabin, checklist(space, scene, cabin), camera=(0.6, 0.0))
    markers = [(float(x), float(y))
               for x, y in re.findall(rf'<circle cx="([\d.]+)" cy="([\d.]+)" r="{MARKER_R:g}"', svg)]
    labels = re.findall(r'<text x="([\d.]+)" y="([\d.]+)" font-size="[\d.]+" text-anchor="(\w+)"[^>]*>'
                        r'([^<]+)</text>', svg)
    assert len(markers) == 4 and {"passenger", "driver", "rear", "origin", "camera", "75°"} <= {t for *_, t in labels}
    for x, y, anchor, text in labels:
        width = CHAR_W * len(text)
        left = float(x) - {"start": 0.0, "middle": width / 2, "end": width}[anchor]
        top, bottom = float(y) - 0.8 * FONT, float(y) + 0.25 * FONT
        for cx, cy in markers:
            apart = (left >= cx + MARKER_R or left + width <= cx - MARKER_R
                     or top >= cy + MARKER_R or bottom <= cy - MARKER_R)
            assert apart, f"{text!r} overlaps the marker at ({cx}, {cy})"
