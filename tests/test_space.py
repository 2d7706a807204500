"""Scene space: loading, validation errors, activity, encoding, sampling, repair."""
import textwrap

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from isu_validate.space import SpaceError, load_space, space_from_dict

SPACE = load_space()


def write(tmp_path, body: str):
    path = tmp_path / "space.toml"
    path.write_text(textwrap.dedent(body))
    return path


def test_default_space_has_the_papers_features():
    expected = {"driver_gender", "driver_emotion", "phone_position", "driver_weight", "driver_height", "seat_belt",
                "tshirt_colour", "child_seat", "child", "child_seat_orientation", "car_lights", "external_light",
                "luggage", "luggage_orientation", "luggage_position", "luggage_colour", "phone_codriver_seat",
                "colacan_codriver_seat", "colabottle_codriver_seat"}
    assert set(SPACE.names) == expected
    assert SPACE.features["phone_position"].values == ("NONE",) + tuple(f"P{i}" for i in range(1, 11))
    assert SPACE.features["luggage_orientation"].low == 20 and SPACE.features["luggage_orientation"].high == 140


def test_default_space_weighs_as_the_papers_table_3_and_labels_k1_to_k12():
    weights = {f.name: f.weight for f in SPACE.predicted}
    assert {n for n, w in weights.items() if w == 0.05} == {
        "driver_gender", "driver_emotion", "colabottle_codriver_seat", "colacan_codriver_seat"}
    assert {n for n, w in weights.items() if w == 0.10} == {
        "phone_position", "seat_belt", "luggage", "luggage_position", "phone_codriver_seat", "child_seat",
        "child_seat_orientation", "child"}
    # Table 3 leaves the colours out: asked, weight 0
    assert {n for n, w in weights.items() if w == 0} == {"tshirt_colour", "luggage_colour"}
    assert sum(weights.values()) == pytest.approx(1.0)
    k = {f.label.split()[0]: f.name for f in SPACE.predicted if f.label.startswith("K")}
    assert sorted(k, key=lambda s: int(s[1:])) == [f"K{i}" for i in range(1, 13)]
    assert (k["K1"], k["K4"], k["K5"], k["K8"]) == (
        "phone_codriver_seat", "colacan_codriver_seat", "colabottle_codriver_seat", "phone_position")
    assert all(f.display_name == f.label for f in SPACE.features.values())
    plain = space_from_dict({"features": {"a": {"type": "categorical", "values": ["X"]}}})
    assert plain.features["a"].display_name == "a"


def test_inactive_features_are_dropped_from_canonical_form_questions_and_key():
    scene = SPACE.sample(np.random.default_rng(0), 1)[0]
    scene.update(luggage="NO", luggage_colour="YELLOW", child_seat="NO", child="YES")
    other = dict(scene, luggage_colour="ANTHRACITE", luggage_orientation=33.0, child="NO")
    canonical = SPACE.canonical(scene)
    assert "luggage_colour" not in canonical and "child" not in canonical
    assert "luggage_colour" not in {q.key for q in SPACE.questions(scene)}
    assert SPACE.key(scene) == SPACE.key(other)
    assert SPACE.key(scene) != SPACE.key(dict(scene, luggage="YES", luggage_position="BACK"))


def test_truth_mapping_and_questions():
    scene = SPACE.sample(np.random.default_rng(1), 1)[0]
    scene.update(phone_position="P3")
    truth = {q.key: q.truth for q in SPACE.questions(scene)}
    assert truth["phone_position"] == "YES"
    scene.update(phone_position="NONE")
    assert {q.key: q.truth for q in SPACE.questions(scene)}["phone_position"] == "NO"


def test_constraints_are_checked():
    scene = SPACE.sample(np.random.default_rng(2), 1)[0]
    scene.update(child_seat="YES", child="YES", child_seat_orientation="FRONT_FACING", luggage="YES",
                 luggage_position="PASSENGER", luggage_colour="YELLOW", luggage_orientation=50.0)
    assert any("same seat" in p for p in SPACE.violations(scene))
    scene.update(luggage="NO", phone_codriver_seat="NO", colacan_codriver_seat="NO",
                 colabottle_codriver_seat="NO")  # an absent suitcase is on no seat
    assert SPACE.is_valid(scene)
    for thing in ("phone_codriver_seat", "colacan_codriver_seat", "colabottle_codriver_seat"):
        with pytest.raises(SpaceError, match="co-driver seat needs the seat free"):
            SPACE.check(dict(scene, **{thing: "YES"}))          # the child seat is there
        free = dict(scene, child_seat="NO", **{thing: "YES"})
        assert SPACE.is_valid(free)
        free.update(luggage="YES", luggage_position="PASSENGER", luggage_colour="YELLOW", luggage_orientation=50.0)
        assert any("needs the seat free" in p for p in SPACE.violations(free))
    # a phone in the hand and one on the seat are two phones: either without the other is fine
    assert SPACE.is_valid(dict(scene, child_seat="NO", phone_position="P1", phone_codriver_seat="NO"))
    assert SPACE.is_valid(dict(scene, child_seat="NO", phone_position="NONE", phone_codriver_seat="YES"))


def test_out_of_domain_and_unknown_features_are_named():
    scene = SPACE.sample(np.random.default_rng(3), 1)[0]
    problems = SPACE.violations(dict(scene, seat_belt="MAYBE", wings="YES"))
    assert any("wings" in p for p in problems)
    assert any("seat_belt" in p and "MAYBE" in p for p in problems)


@pytest.mark.parametrize("body, message", [
    ("[features.a]\ntype = 'tensor'\nvalues = [1]\n", "unknown type 'tensor'"),
    ("[features.a]\ntype = 'categorical'\nvalues = []\n", "empty domain"),
    ("[features.a]\ntype = 'continuous'\nlow = 2.0\nhigh = 1.0\n", "empty domain"),
    ("[features.a]\ntype = 'categorical'\nvalues = ['X']\npredicted = true\nweight = -1\nquestion = 'q'\n",
     "weight must be a number >= 0"),
    ("[features.a]\ntype = 'categorical'\nvalues = ['X']\nactive_when = { ghost = 'Y' }\n", "unknown feature 'ghost'"),
    ("[features.a]\ntype = 'categorical'\nvalues = ['X','Y']\n[[constraints]]\nname = 'c'\nif = { ghost = 'X' }\n"
     "then = { a = 'X' }\n", "unknown feature 'ghost'"),
    ("[features.a]\ntype = 'categorical'\nvalues = ['X','Y']\n[[constraints]]\nname = 'never X'\nif = { a = 'X' }\n"
     "then = { a = 'Y' }\n[[constraints]]\nname = 'never Y'\nif = { a = 'Y' }\nthen = { a = 'X' }\n",
     "contradict each other"),
    ("[features.a]\ntype = 'categorical'\nvalues = ['X','Y']\n[[constraints]]\nname = 'typo'\nif = { a = 'Z' }\n"
     "then = { a = 'X' }\n", "never takes"),
    ("features = 3\n", r"no \[features\.\*\] tables"),
    ("[features.a\n", "not valid TOML"),
])
def test_bad_space_files_fail_with_a_message_naming_file_feature_and_problem(tmp_path, body, message):
    path = write(tmp_path, body)
    with pytest.raises(SpaceError, match=message) as err:
        load_space(path)
    assert str(path) in str(err.value)


def test_missing_space_file_is_named():
    with pytest.raises(SpaceError, match="no spaces rig named 'nope'"):
        load_space("nope")


def test_zero_width_ranges_encode_without_dividing_by_zero():
    space = space_from_dict({"features": {
        "fixed": {"type": "continuous", "low": 5.0, "high": 5.0},
        "one": {"type": "categorical", "values": ["ONLY"]},
        "x": {"type": "continuous", "low": 0.0, "high": 10.0}}})
    scene = {"fixed": 5.0, "one": "ONLY", "x": 2.5}
    u = space.encode(scene)
    assert np.all(np.isfinite(u)) and u.tolist() == [0.0, 0.0, 0.25]
    assert space.decode(u) == scene
    vectors = np.array([space.canonical_vector(s) for s in (scene, dict(scene, x=10.0))])
    assert space.distances(vectors[0], vectors).tolist() == pytest.approx([0.0, 0.75 / 3])


def test_distance_counts_features_active_in_only_one_scene():
    base = SPACE.sample(np.random.default_rng(4), 1)[0]
    base.update(luggage="NO", child_seat="NO")
    with_luggage = dict(base, luggage="YES", luggage_position="BACK", luggage_colour="YELLOW", luggage_orientation=80.0)
    a, b = SPACE.canonical_vector(base), SPACE.canonical_vector(with_luggage)
    # luggage itself differs (1) and three luggage features are active in only one scene (3)
    assert SPACE.distances(a, b[None])[0] == pytest.approx(4 / len(SPACE.names))
    assert SPACE.distances(a, a[None])[0] == 0.0


scenes = st.integers(0, 2**32 - 1).map(lambda seed: SPACE.sample(np.random.default_rng(seed), 1)[0])


@settings(max_examples=60, deadline=None)
@given(scenes)
def test_encoding_round_trips(scene):
    decoded = SPACE.decode(SPACE.encode(scene))
    assert SPACE.key(decoded) == SPACE.key(scene)
    assert np.all((SPACE.encode(scene) >= 0) & (SPACE.encode(scene) <= 1))


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.lists(st.floats(-0.5, 1.5), min_size=19, max_size=19))
def test_repair_turns_any_vector_into_a_valid_scene(seed, u):
    raw = {n: f.decode(x) for (n, f), x in zip(SPACE.features.items(), u)}
    raw["child_seat"], raw["phone_codriver_seat"] = "YES", "YES"  # break a constraint on purpose
    repaired = SPACE.repair(raw, np.random.default_rng(seed))
    assert SPACE.violations(repaired) == []


def test_a_scene_file_holding_a_list_is_a_clear_error_not_a_traceback(tmp_path, capsys):
    import json

    from isu_validate.cli import main

    scenes = SPACE.sample(np.random.default_rng(0), 2)
    with pytest.raises(SpaceError, match="a scene is a JSON object .* not a list; write one scene per file"):
        SPACE.check(scenes)
    path = tmp_path / "scenes.json"
    path.write_text(json.dumps(scenes))
    assert main(["render", str(path), "--out", str(tmp_path / "x.png"), "--preset", "draft"]) == 2
    assert "not a list; write one scene per file" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()



def test_a_space_extends_another_adding_features_and_keeping_its_constraints(tmp_path):
    diverse = load_space("isu-diverse")
    assert diverse.names[:len(SPACE.names)] == SPACE.names
    looks = ("driver_skin_tone", "driver_hair_colour", "driver_hair_style", "driver_top", "driver_top_print",
             "driver_print_colour", "driver_jacket_colour", "driver_trousers_colour", "driver_eyewear", "driver_cap",
             "driver_watch", "driver_hands", "drink", "phone_screen", "driver_gaze", "phone_case", "phone_tip",
             "phone_roll", "phone_turn")
    assert set(diverse.names) - set(SPACE.names) == set(looks) | {"surroundings", "sun_direction", "cabin_trim",
                                                                  "seat_material", "seat_belt_colour"}
    # every value of what the hands do is a position the default rig has (or both hands on the wheel)
    from isu_validate.render.cabin import load_cabin
    assert set(diverse.features["driver_hands"].values) == {"WHEEL"} | set(load_cabin("default")["hand_positions"])
    assert set(diverse.features["driver_gaze"].values) == {"ROAD"} | set(load_cabin("default")["gaze_targets"])
    assert not any(diverse.features[n].predicted for n in looks)
    assert len(diverse.constraints) == len(SPACE.constraints)
    assert {f.name: f.weight for f in diverse.predicted} == {f.name: f.weight for f in SPACE.predicted}
    again = write(tmp_path, """
        extends = "isu-paper"
        [features.driver_gender]
        type = "categorical"
        values = ["A", "B"]
        """)
    with pytest.raises(SpaceError, match="redefines driver_gender"):
        load_space(again)
    feature = '[features.{}]\ntype = "categorical"\nvalues = ["A"]\n'
    (tmp_path / "a.toml").write_text(f'extends = "{tmp_path / "b.toml"}"\n' + feature.format("x"))
    (tmp_path / "b.toml").write_text(f'extends = "{tmp_path / "a.toml"}"\n' + feature.format("y"))
    with pytest.raises(SpaceError, match="extends it back"):
        load_space(tmp_path / "a.toml")
    with pytest.raises(SpaceError, match="extends 'no-such-space'"):
        load_space(write(tmp_path, 'extends = "no-such-space"\n'))
