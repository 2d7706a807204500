"""The people of the renders, with the real anny model (built by setup): bodies land on their
anthropometric classes, sit on the seat without cutting into it or the wheel, hold the wheel or the
phone, wear the belt on the body, show their expression only on the face; the child is a toddler in
its seat; the posed-vertex cache is keyed, reused and never needs anny on a hit."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from isu_validate.render.cabin import load_cabin
from isu_validate.render.cabin_geometry import CAN_HEIGHT, DRINK_PROFILES, drink_solid
from isu_validate.render.people import People, PeopleStore
from isu_validate.render.people import people as people_module
from isu_validate.render.people.checks import child_measures, driver_measures, drink_measures
from isu_validate.render.people.phenotype import (BMI_BANDS, HEIGHT_BANDS, child_phenotype, describe_texts,
                                                  measure, measured_table)
from isu_validate.render.people.store import entry_key
from isu_validate.space import load_space

pytestmark = pytest.mark.slow

# bodies at the corners of the classes, each with phone positions spread over all ten
POSES = [("FEMALE", "H1", "W1", "HAPPY", "NONE"), ("MALE", "H4", "W4", "SERIOUS", "NONE"),
         ("FEMALE", "H1", "W4", "SERIOUS", "P1"), ("MALE", "H4", "W1", "HAPPY", "P2"),
         ("MALE", "H1", "W2", "SERIOUS", "P3"), ("FEMALE", "H4", "W3", "HAPPY", "P4"),
         ("MALE", "H2", "W4", "HAPPY", "P5"), ("FEMALE", "H3", "W1", "SERIOUS", "P6"),
         ("MALE", "H4", "W3", "SERIOUS", "P7"), ("FEMALE", "H2", "W2", "HAPPY", "P8"),
         ("MALE", "H3", "W1", "HAPPY", "P9"), ("FEMALE", "H4", "W4", "SERIOUS", "P10")]
HAND_TOUCH = 0.002   # gripping fingers may press 2 mm into the rim's padding (the model's skin tolerance)
PHONE_PRESS = 0.005  # ... and the finger pads 5 mm against a phone's (sharp-box) edges, as pads squash


@pytest.fixture(scope="module")
def model():
    from isu_validate.render.people.model import load_model
    return load_model()


@pytest.fixture(scope="module")
def people(tmp_path_factory):
    """A fresh cache: every pose here is computed by the code under test, none comes from an old cache."""
    return People(load_cabin("default"), PeopleStore(tmp_path_factory.mktemp("people")))


def _load(path) -> dict:
    with np.load(path) as data:
        return {k: data[k] for k in data.files}


def test_height_and_weight_classes_land_on_their_anthropometric_bands(model):
    table = measured_table(model)
    for (gender, h, w), m in table.items():
        lo, hi = HEIGHT_BANDS[h]
        assert lo < m["height_m"] < hi and abs(m["height_m"] - (lo + hi) / 2) < 0.005, (gender, h, w, m)
        blo, bhi = BMI_BANDS[w]
        assert blo < m["bmi"] < bhi, (gender, h, w, m)
    for gender in ("MALE", "FEMALE"):
        for h in HEIGHT_BANDS:
            masses = [table[(gender, h, w)]["mass_kg"] for w in BMI_BANDS]
            assert masses == sorted(masses) and masses[-1] > masses[0] * 1.5, (gender, h, masses)
    # what the space file tells a technician is what the renderer draws
    space = load_space()
    texts = describe_texts(table)
    for feature in ("driver_height", "driver_weight"):
        assert dict(space.features[feature].describe) == texts[feature]


def test_the_child_is_a_toddler(model):
    for orientation, (lo, hi) in (("REAR_FACING", (0.72, 0.84)), ("FRONT_FACING", (0.85, 1.0))):
        height = measure(model, child_phenotype(orientation))["height_m"]
        assert lo < height < hi, (orientation, height)   # WHO: 1 year ~0.75 m, 2.5 years ~0.91 m


@pytest.mark.parametrize("key", POSES, ids=["-".join(k) for k in POSES])
def test_seated_driver_clears_seat_and_wheel_holds_wheel_or_phone_and_wears_the_belt_on_the_body(people, key):
    state = _load(people.driver_state(*key))
    topology = _load(people.topology("female" if key[0] == "FEMALE" else "male"))
    m = driver_measures(state, topology, people.cabin)
    for part in ("cushion", "back", "base", "headrest0"):
        assert m[f"clear_{part}"] >= 0.0, f"{key}: the body cuts {-m[f'clear_{part}'] * 1000:.1f} mm into the {part}"
    assert m["clear_cushion"] < 0.012, f"{key}: floats {m['clear_cushion'] * 1000:.0f} mm above the cushion"
    assert m["clear_wheel_body"] >= 0.0, f"{key}: arm or knee {-m['clear_wheel_body'] * 1000:.1f} mm into the wheel"
    assert m["clear_wheel_hands"] >= -HAND_TOUCH, \
        f"{key}: a hand {-m['clear_wheel_hands'] * 1000:.1f} mm into the wheel"
    if key[4] in ("NONE", "P3", "P5", "P6", "P9"):   # at least one hand on the rim (both when no phone)
        assert m["clear_wheel_hands"] < 0.006, f"{key}: no hand touches the wheel"
    if key[4] != "NONE":
        assert m["phone_to_palm"] < 0.016, f"{key}: the phone is {m['phone_to_palm'] * 1000:.0f} mm from the hand"
        assert m["phone_clear_hand"] > -PHONE_PRESS, f"{key}: {-m['phone_clear_hand'] * 1000:.1f} mm into the phone"
        assert m["phone_front_touch"] >= 20, f"{key}: no finger closes round the phone's edge ({m})"
    # the belt: never through the body, resting on it across the chest and the lap
    assert m["belt_diagonal_min"] > 0.001 and m["belt_lap_min"] > 0.001, key
    assert m["belt_diagonal_resting"] > 0.5 and m["belt_lap_resting"] > 0.3, (key, m)


def test_the_wheel_leans_as_a_real_one_its_face_up_to_the_driver_and_the_grips_stay_at_ten_and_two():
    """The rim's top lies further from the driver than its bottom and its face turns up to the chest, so a
    camera beside the car and above the rim sees its face (isu-blender-12 had it mirrored); the grips are
    where the mirrored wheel had them in x (the arms reach as far), 5 cm higher so that the rim clears the knees."""
    from capture.camera import load_camera
    from isu_validate.render.cabin_geometry import rim_point, wheel_frame
    wheel = load_cabin("default")["steering_wheel"]
    centre, _, up, normal = wheel_frame(wheel)
    top, bottom = centre + up * wheel["radius"], centre - up * wheel["radius"]
    assert top[0] > bottom[0] + 0.1 and normal[0] < 0 < normal[2]      # cabin +x is forward, towards the dash
    side_camera = load_camera("passenger-side").t
    assert (side_camera - centre) @ normal > 0.1 * np.linalg.norm(side_camera - centre)
    for clock in (30.0, 150.0):
        point, _, _ = rim_point(wheel, clock)
        assert point[0] == pytest.approx(0.50 - 0.185 * 0.5 * np.sin(np.radians(28)), abs=0.001)


def test_expression_moves_only_the_face(people):
    happy = _load(people.driver_state("MALE", "H2", "W2", "HAPPY", "P6"))
    serious = _load(people.driver_state("MALE", "H2", "W2", "SERIOUS", "P6"))
    topology = _load(people.topology("male"))
    moved = np.linalg.norm(happy["vertices"] - serious["vertices"], axis=1)
    head_vertices = np.unique(topology["faces"][topology["head"]])
    body = np.setdiff1d(np.arange(len(moved)), head_vertices)
    assert moved[body].max() < 0.001 and moved[head_vertices].max() > 0.004   # the chin pulls the neck < 1 mm
    # each expression folds the face's skin where it gathers it, and nowhere else
    for state in (happy, serious):
        assert np.all(state["crease"][body] == 0.0) and state["crease"][head_vertices].max() > 0.3
    np.testing.assert_allclose(happy["belt_diagonal"], serious["belt_diagonal"])


def test_regions_dress_the_body_and_split_off_the_head(people, model):
    from isu_validate.render.people.regions import bone_weights
    topology = _load(people.topology("male"))
    faces, head = topology["faces"], topology["head"]
    head_bones = bone_weights(model, ("head",)) > 0.9
    hand = topology["hands"].astype(bool)
    assert head[np.isin(faces, np.flatnonzero(head_bones)).all(axis=1)].all()      # all of the head ...
    assert not head[np.isin(faces, np.flatnonzero(hand)).any(axis=1)].any()        # ... and none of the hands
    chest = bone_weights(model, ("spine02", "spine01")) > 0.9
    forearm = bone_weights(model, ("lowerarm",)) > 0.9
    thigh = bone_weights(model, ("upperleg02",)) > 0.9
    assert (topology["field_shirt"][chest] > 0).mean() > 0.95
    assert (topology["field_shirt"][forearm] < 0).all() and (topology["field_shirt"][head_bones] < 0).all()
    assert (topology["field_trousers"][thigh] > 0).mean() > 0.95 and (topology["field_trousers"][chest] < 0).all()
    assert (topology["field_brows"] > 0).sum() > 20 and (topology["field_brows"][~head_bones] <= 0).all()
    # hair: a shell on the scalp; the women's reaches lower than the men's
    female = _load(people.topology("female"))
    rest = people_module.Body(model, people_module.driver_phenotype("MALE", "H3", "W2")).evaluate({})
    assert rest.vertices[female["hair_i"], 2].min() < rest.vertices[topology["hair_i"], 2].min() - 0.05


def test_hair_has_no_slivers_and_short_hair_has_sideburns(people, model):
    for kind, gender in (("female", "FEMALE"), ("male", "MALE")):
        topology = _load(people.topology(kind))
        state = _load(people.driver_state(gender, "H3", "W2", "HAPPY", "NONE"))
        tri = state["hair"][topology["hair_faces"]].astype(np.float64)
        area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1) / 2
        assert area.min() > 1e-8, f"{kind}: a hair triangle of {area.min():.1e} m²"    # a cut's sliver
    # sideburns: just in front of the ears short hair reaches 2 cm lower than a buzz cut does
    from isu_validate.render.people.hair import head_frame
    rest = people_module.Body(model, people_module.driver_phenotype("MALE", "H3", "W2")).evaluate({})
    v, cos_front = rest.vertices.astype(np.float64), head_frame(rest).cos_front
    lowest = {}
    for style in ("short", "buzz"):
        hair = np.unique(_load(people.topology("male", style))["hair_i"])
        lowest[style] = v[hair[(cos_front[hair] > 0.1) & (cos_front[hair] < 0.2)], 2].min()
    assert lowest["short"] < lowest["buzz"] - 0.02


def test_children_sit_in_their_seats_the_rear_facing_one_reclined(people):
    anchor = people.cabin["anchors"]["child_seat"]
    for front in (True, False):
        state = _load(people.child_state(front))
        for name, value in child_measures(state, front, anchor).items():
            assert value >= 0.0, f"{'front' if front else 'rear'}-facing child: {name} {value * 1000:.1f} mm"
    for front, (lo, hi) in ((True, (0, 20)), (False, (40, 75))):
        joints = dict(zip(people_module.JOINTS, _load(people.child_state(front))["joints"]))
        axis = joints["neck01"] - joints["root"]
        lean = np.degrees(np.arctan2(np.hypot(axis[0], axis[1]), axis[2]))
        assert lo <= lean <= hi, f"{'front' if front else 'rear'}-facing child leans {lean:.0f} deg from upright"


def test_the_cache_is_keyed_reused_and_needs_no_anny_on_a_hit(people, monkeypatch, tmp_path):
    key = ("FEMALE", "H1", "W1", "HAPPY", "NONE")
    first = people.driver_state(*key)
    scene = dict(zip(("driver_gender", "driver_height", "driver_weight", "driver_emotion", "phone_position"), key))
    dressed = people.for_scene({**scene, "child_seat": "NO"})      # the outfit cut, the driver dressed
    misses = people.misses
    monkeypatch.setattr(people_module, "load_model", lambda: pytest.fail("anny loaded on a cache hit"))
    assert people.driver_state(*key) == first and people.misses == misses
    spec = people.for_scene({**scene, "child_seat": "NO"})
    assert spec == dressed and spec["driver"]["state"] == str(first) and spec["child"] is None
    # another cabin (the seat moved) is another entry; nothing half-written is left behind
    cabin = load_cabin("default")
    cabin["seats"]["driver"]["cushion"][0] += 0.05
    moved = People(cabin, people.store)
    inputs = {"gender": "FEMALE", "height": "H1", "weight": "W1", "emotion": "HAPPY", "phone_position": "NONE"}
    assert (entry_key("driver", {**inputs, "rig": moved.driver_rig})
            != entry_key("driver", {**inputs, "rig": people.driver_rig}))
    assert not list(people.store.root.rglob(".tmp-*"))


def test_people_commands_warm_and_check_the_cache(people, capsys):
    from isu_validate.cli import main
    assert main(["people", "warm", "--limit", "1", "--cache", str(people.store.root)]) == 0
    # 1 of the grid + each rig hand position + each gaze target, the hands on the wheel and with the phone at the ear
    drivers = 1 + len(people.cabin["hand_positions"]) + 2 * len(people.cabin["gaze_targets"])
    assert f"{drivers} drivers and 2 children" in capsys.readouterr().out
    assert main(["people", "check", "--limit", "1", "--cache", str(people.store.root)]) == 0
    out = capsys.readouterr().out
    assert "clear_wheel_hands" in out and "belt_lap_resting" in out and "child_rear_clear_cs_platepad" in out


def test_a_phone_on_an_open_palm_is_not_gripped():
    """The grip measure tells a hand closed round the phone's edge from a phone lying on a flat hand."""
    from isu_validate.render.people.checks import phone_grip_measures
    R, centre = np.eye(3), np.zeros(3)
    grid = np.stack(np.meshgrid(np.linspace(-0.05, 0.05, 11), np.linspace(-0.05, 0.05, 11)), -1).reshape(-1, 2)
    palm = np.column_stack([grid, np.full(len(grid), -0.006)])               # under the phone's back
    flat = phone_grip_measures(palm, centre, R)
    assert flat["phone_front_touch"] == 0 and flat["phone_clear_hand"] > 0
    tips = np.column_stack([np.full(21, 0.039), np.linspace(-0.04, 0.04, 21), np.full(21, 0.003)])  # round the edge
    closed = phone_grip_measures(np.vstack([palm, tips]), centre, R)
    assert closed["phone_front_touch"] == 21
    inside = phone_grip_measures(np.array([[0.0, 0.0, -0.002]]), centre, R)
    assert inside["phone_clear_hand"] == pytest.approx(-0.00225, abs=1e-6)


def test_people_check_ranks_a_belt_into_the_body_worse_than_one_off_it():
    """`people check` reports the worst body per figure: smaller is worse for clearances and a belt's
    distance to the body (negative: through it), a larger gap for the phone in the palm."""
    from isu_validate.render.people.warm import is_worse
    assert is_worse("belt_lap_min", -0.001, 0.020) and not is_worse("belt_lap_min", 0.020, -0.001)
    assert is_worse("clear_wheel_hands", -0.01, 0.0) and is_worse("belt_diagonal_resting", 0.4, 0.6)
    assert is_worse("phone_to_palm", 0.03, 0.01) and is_worse("phone_to_palm", -0.03, 0.01)
    assert is_worse("phone_clear_hand", -0.004, 0.0) and is_worse("phone_front_touch", 3, 40)


def test_eyes_teeth_and_hair_styles_are_where_a_face_has_them(people, model):
    """The iris disc is centred on each eyeball's front pole; teeth lie only in the front of the mouth's
    cavity; a buzz cut is a thinner shell than short hair, and a scene's hair style picks the topology."""
    from isu_validate.render.people.regions import uv_parts
    topology = _load(people.topology("male"))
    faces, eye_uv = topology["faces"], topology["eye_uv"].reshape(-1, 3, 2)
    rest = people_module.Body(model, people_module.driver_phenotype("MALE", "H3", "W2")).evaluate({})
    v = rest.vertices.astype(np.float64)
    for side in ("L", "R"):
        front = uv_parts(model, [f"eye_front.{side}"])
        radius = np.linalg.norm(eye_uv[front], axis=2)
        assert 0.9 < radius.max() <= 1.45          # the disc reaches the equator (bounding-box corners aside)
        ball = np.unique(faces[front | uv_parts(model, [f"eye_back.{side}"])])
        centre = v[ball].mean(axis=0)
        # the corner nearest the disc's centre looks straight ahead (the body faces -Y at rest)
        nearest = faces[front].ravel()[np.argmin(radius.ravel())]
        direction = (v[nearest] - centre) / np.linalg.norm(v[nearest] - centre)
        assert direction[1] < -0.95
        assert not eye_uv[~(uv_parts(model, ["eye_front.L"]) | uv_parts(model, ["eye_front.R"]))].any()
    teeth = topology["field_teeth"] > 0
    mouth = np.unique(faces[uv_parts(model, ["mouth_cavity", "tongue"])])
    assert 50 < teeth.sum() and set(np.flatnonzero(teeth)) <= set(mouth)
    assert v[teeth, 1].max() < v[mouth, 1].min() + 0.035          # the front of the mouth, not the throat
    buzz, short = _load(people.topology("male", "buzz")), topology
    assert buzz["hair_thickness"].max() < 0.5 * short["hair_thickness"].max()
    assert people_module.hair_style_of({"driver_hair_style": "BUZZ"}, "female") == "buzz"
    assert people_module.hair_style_of({}, "female") == "bob"
    assert people_module.hair_style_of({"driver_hair_style": "BY_GENDER"}, "male") == "short"


@pytest.mark.parametrize("hands, phone", [("LAP", "NONE"), ("HAIR", "NONE"), ("LAP", "P3"), ("DRINK", "NONE"),
                                         ("DRINK_LOW", "NONE"), ("TEMPLE", "NONE")])
def test_a_free_hand_leaves_the_wheel_for_its_rig_position_and_a_phone_in_that_hand_wins(people, hands, phone):
    """isu-diverse's driver_hands: one hand off the wheel at the rig's point, the other still on the rim, the
    body clear of seat and wheel; a phone held in the same hand takes the hand (LAP + P3: reading)."""
    state = _load(people.driver_state("MALE", "H2", "W2", "SERIOUS", phone, None, hands))
    topology = _load(people.topology("male"))
    m = driver_measures(state, topology, people.cabin)
    for part in ("cushion", "back", "base", "headrest0"):
        assert m[f"clear_{part}"] >= 0.0, (hands, phone, part, m)
    assert m["clear_wheel_body"] >= 0.0 and m["clear_wheel_hands"] >= -HAND_TOUCH, (hands, phone, m)
    clear = _wheel_clearance_by_hand(state, topology, people.cabin)
    spec = people.cabin["hand_positions"][hands]
    other = "left" if spec["hand"] == "right" else "right"
    assert clear[spec["hand"]] > 0.05, f"{hands}: the {spec['hand']} hand stays {clear} m from the wheel"
    assert clear[other] < 0.006, f"{hands}: the {other} hand left the wheel ({clear})"
    if phone == "NONE":
        assert "phone_centre" not in state
        assert ("can_centre" in state) == (spec.get("holds") == "can"), hands
        if spec["relative_to"] == "head":   # the palm at the rig's point (a few cm: the hand's own thickness)
            target = state["head_centre"] + np.asarray(spec["offset"])
            v = state["vertices"][topology["hands"].astype(bool)]
            assert np.linalg.norm(v - target, axis=1).min() < 0.03, hands
    else:
        assert m["phone_to_palm"] < 0.016 and m["phone_front_touch"] >= 20, (hands, phone, m)


@pytest.mark.parametrize("gender, height, weight", [("MALE", "H2", "W2"), ("FEMALE", "H1", "W1"), ("MALE", "H3", "W3")])
def test_a_can_held_to_drink_lies_in_the_closed_hand_its_top_at_the_lips(people, gender, height, weight):
    """isu-diverse's driver_hands DRINK: the can's body in the palm with the fingers round it (the skin may press
    a few mm into it, as skin does), its top tipped back to the mouth, touching the face without cutting into it."""
    state = _load(people.driver_state(gender, height, weight, "SERIOUS", "NONE", None, "DRINK"))
    topology = _load(people.topology("male" if gender == "MALE" else "female"))
    m = driver_measures(state, topology, people.cabin)
    assert -0.008 < m["can_clear_hand"] < 0.0 and m["can_touch"] >= 100, m
    assert -0.002 < m["can_clear_body"] < 0.015, f"the can cuts into or stands off the face: {m}"
    axis = state["can_rotation"][:, 2]
    assert axis[2] > 0.5 and axis[0] < -0.3, f"the can's top is not tipped back towards the face: {axis}"
    np.testing.assert_allclose(state["can_rotation"].T @ state["can_rotation"], np.eye(3), atol=1e-5)


@pytest.mark.parametrize("gender, height, weight", [("MALE", "H2", "W2"), ("FEMALE", "H1", "W1"), ("MALE", "H4", "W4")])
def test_every_drink_sits_in_the_hand_that_holds_the_can_and_clears_the_face(people, gender, height, weight):
    """isu-diverse's `drink`: cups, a bottle and a mug held where the can is (one grip), at the mouth (DRINK) and
    below the chin (DRINK_LOW, upright): none cuts into the face or body, the fingers press into none more than
    into the can, and each touches the hand."""
    topology = _load(people.topology("male" if gender == "MALE" else "female"))
    for hands in ("DRINK", "DRINK_LOW"):
        state = _load(people.driver_state(gender, height, weight, "SERIOUS", "NONE", None, hands))
        measures = drink_measures(state, topology)
        assert set(measures) == set(DRINK_PROFILES)
        for kind, m in measures.items():
            body, fingers = m["clear_body"], m["clear_hand"]
            assert body > -0.002, f"{hands} {kind}: cuts {-body * 1000:.1f} mm into the body"
            assert -0.009 < fingers < 0.0, f"{hands} {kind}: the hand reaches {fingers * 1000:.1f} mm into it"
        if hands == "DRINK_LOW":
            axis = state["can_rotation"][:, 2]
            assert axis[2] > 0.8, f"the drink below the chin is not upright: {axis}"
            assert state["can_centre"][2] < state["head_centre"][2] - 0.15, "the drink is not below the chin"


def test_a_drinks_distance_is_exact_for_a_solid_of_revolution_with_a_hollow():
    """The outline's signed distance: a plain cylinder's agrees with Cylinder's; the hollow over a cup's coffee
    is outside, the cup's wall inside; the axis is no surface."""
    from isu_validate.render.cabin_geometry import Cylinder, Lathe
    axis = np.array([0.0, 0.6, 0.8])
    side = np.cross(axis, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    solid = Lathe("tin", np.zeros(3), axis, ((0.0, 0.0), (0.03, 0.0), (0.03, 0.1), (0.0, 0.1)))
    tin = Cylinder("tin", np.zeros(3), axis, 0.03, 0.1)
    points = np.random.default_rng(3).uniform(-0.15, 0.15, (2000, 3))
    np.testing.assert_allclose(solid.sdf(points), tin.sdf(points), atol=1e-12)
    cup = drink_solid("CUP", np.zeros(3), np.eye(3))     # its base at z = -CAN_HEIGHT / 2
    base = -CAN_HEIGHT / 2
    d = cup.sdf(np.array([[0, 0, base + 0.095], [0, 0, base + 0.05], [0.0375, 0, base + 0.1015], [0.06, 0, 0]]))
    assert d[0] > 0 and d[1] < -0.02 and d[2] < 0 and d[3] > 0.02, d


def test_the_cans_distance_is_exact_on_its_side_its_caps_and_round_its_rims():
    """The solid the fingers close on: signed distance to a capped cylinder, negative inside, along any axis."""
    from isu_validate.render.cabin_geometry import Cylinder
    axis = np.array([0.0, 0.6, 0.8])
    side = np.cross(axis, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    can = Cylinder("can", np.zeros(3), axis, 0.03, 0.1)
    points = [axis * 0.05, axis * 0.05 + side * 0.04, axis * 0.13, -axis * 0.01 + side * 0.01,
              axis * 0.12 + side * 0.07, axis * 0.05 + side * 0.025, axis * 0.099]
    expected = [-0.03, 0.01, 0.03, 0.01, np.hypot(0.02, 0.04), -0.005, -0.001]
    np.testing.assert_allclose(can.sdf(np.array(points)), expected, atol=1e-12)


def test_a_hand_position_the_rig_lacks_or_a_malformed_one_is_refused_with_the_fix(model, tmp_path):
    from isu_validate.render.cabin import CabinRigError
    from isu_validate.render.people.phenotype import driver_phenotype
    from isu_validate.render.people.seated import seat_and_pose
    from isu_validate.render.people.skeleton import Body
    with pytest.raises(ValueError, match=r"no \[hand_positions.JUGGLING\]; known: WHEEL, LAP"):
        seat_and_pose(Body(model, driver_phenotype("MALE", "H2", "W2")), load_cabin("default"), "NONE", "JUGGLING")
    text = (Path(__file__).parents[1] / "rigs" / "cabins" / "default.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("palm = [0.0, 0.0, -1.0]", "palm = \"down\"", 1))
    with pytest.raises(CabinRigError, match=r"hand_positions.LAP\] needs .* palm and fingers = \[x, y, z\]"):
        load_cabin(bad)
    bad.write_text(text.replace('\nholds = "can"', '\nholds = "coffee"', 1))
    with pytest.raises(CabinRigError, match=r"hand_positions.DRINK\] holds must be one of nothing, can"):
        load_cabin(bad)
    bad.write_text(text.replace("\nat_ear = true", "\nat_ear = \"yes\"", 1))
    with pytest.raises(CabinRigError, match=r"phone_positions.P1\] at_ear must be true or false"):
        load_cabin(bad)


@pytest.mark.parametrize("gaze, phone, hands", [("DOWN", "P5", "WHEEL"), ("DOWN", "NONE", "CONSOLE"),
                                                 ("PASSENGER", "NONE", "WHEEL"), ("MIRROR", "NONE", "LAP"),
                                                 ("PASSENGER", "P1", "WHEEL"), ("DOWN", "NONE", "DRINK_LOW")])
def test_the_head_turns_to_where_the_driver_looks_and_what_is_held_at_it_turns_with_it(people, model, gaze, phone,
                                                                                        hands):
    """isu-diverse's driver_gaze: the face turns HEAD_SHARE of the way to the rig's gaze target (down to the phone
    or the free hand when one is held below the head), within the limits (smaller with a hand at the head); only
    the neck and head move; the body still clears seat and wheel; a phone at the ear stays at the turned ear."""
    from isu_validate.render.people import seated
    from isu_validate.render.people.phenotype import driver_phenotype
    from isu_validate.render.people.skeleton import Body
    cabin = people.cabin
    body = Body(model, driver_phenotype("MALE", "H2", "W2"))
    road, dp = (seated.seat_and_pose(body, cabin, phone, hands, g) for g in ("ROAD", gaze))
    before, after = (p.posed.rot("head") @ seated.FACING for p in (road, dp))
    spec = cabin["phone_positions"].get(phone) or cabin["hand_positions"].get(hands)
    look = cabin["gaze_targets"][gaze]
    at = spec if look.get("at_hands") and spec and spec["relative_to"] != "head" else look
    want = (seated._reference(road.posed, at, cabin, road.head_centre) + np.asarray(at["offset"])
            - (road.posed.head("eye.L") + road.posed.head("eye.R")) / 2)
    heading = {k: np.degrees(seated._heading(v)) for k, v in (("want", want), ("before", before), ("after", after))}
    rise = {k: np.degrees(seated._elevation(v)) for k, v in (("want", want), ("before", before), ("after", after))}
    limit = seated.HOLDING_MAX_DEG if spec and spec["relative_to"] == "head" else seated.HEAD_MAX_DEG
    yaw = np.clip(seated.HEAD_SHARE * (heading["want"] - heading["before"]), -limit["yaw"], limit["yaw"])
    pitch = np.clip(seated.HEAD_SHARE * (rise["want"] - rise["before"]), -limit["down"], limit["up"])
    assert abs(heading["after"] - heading["before"] - yaw) < 1.0, (heading, yaw)
    assert abs(rise["after"] - rise["before"] - pitch) < 1.0, (rise, pitch)
    assert max(abs(yaw), abs(pitch)) > 10.0, "the head hardly turned"
    np.testing.assert_allclose(dp.posed.head("neck01"), road.posed.head("neck01"), atol=1e-6)
    state = _load(people.driver_state("MALE", "H2", "W2", "SERIOUS", phone, None, hands, gaze))
    m = driver_measures(state, _load(people.topology("male")), cabin)
    for part in ("cushion", "back", "base", "headrest0"):
        assert m[f"clear_{part}"] >= 0.0, (part, m)
    assert m["clear_wheel_body"] >= 0.0 and m["clear_wheel_hands"] >= -HAND_TOUCH, m
    if phone == "P1":
        assert np.linalg.norm(dp.phone[0] - road.phone[0]) > 0.03, "the phone stayed at the unturned ear"
        np.testing.assert_allclose(np.linalg.norm(dp.phone[0] - dp.head_centre),
                                   np.linalg.norm(road.phone[0] - road.head_centre), atol=0.01)
        assert m["phone_to_palm"] < 0.016 and m["phone_front_touch"] >= 20, m


def test_a_gaze_the_rig_lacks_or_a_malformed_gaze_target_is_refused_with_the_fix(model, tmp_path):
    from isu_validate.render.cabin import CabinRigError
    from isu_validate.render.people.phenotype import driver_phenotype
    from isu_validate.render.people.seated import seat_and_pose
    from isu_validate.render.people.skeleton import Body
    with pytest.raises(ValueError, match=r"no \[gaze_targets.SKY\]; known: ROAD, DOWN, PASSENGER, MIRROR"):
        seat_and_pose(Body(model, driver_phenotype("MALE", "H2", "W2")), load_cabin("default"), "NONE", "WHEEL", "SKY")
    text = (Path(__file__).parents[1] / "rigs" / "cabins" / "default.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("offset = [0.25, -0.75, -0.02]", "offset = \"right\"", 1))
    with pytest.raises(CabinRigError, match=r"gaze_targets.PASSENGER\] needs relative_to .* offset = \[x, y, z\]"):
        load_cabin(bad)
    bad.write_text(text.replace("[gaze_targets.MIRROR]\nrelative_to = \"head\"\noffset = [0.55, -0.42, 0.12]",
                                "[gaze_targets]\nMIRROR = 3", 1))
    with pytest.raises(CabinRigError, match=r"gaze_targets.MIRROR\] needs relative_to"):
        load_cabin(bad)


def _wheel_clearance_by_hand(state: dict, topology: dict, cabin: dict) -> dict[str, float]:
    """Each hand's nearest approach to the steering wheel (m): the left hand lies towards cabin +y."""
    from isu_validate.render.cabin_geometry import wheel_solids
    v = state["vertices"].astype(np.float64)
    hands = topology["hands"].astype(bool)
    middle = float(np.median(v[hands][:, 1]))
    wheel = wheel_solids(cabin["steering_wheel"])
    sides = {"left": hands & (v[:, 1] > middle), "right": hands & (v[:, 1] <= middle)}
    return {side: float(min(s.sdf(v[mask]).min() for s in wheel)) for side, mask in sides.items()}


def test_a_phone_position_with_a_malformed_finger_direction_is_refused_with_the_fix(tmp_path):
    from isu_validate.render.cabin import CabinRigError
    text = (Path(__file__).parents[1] / "rigs" / "cabins" / "default.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("fingers = [-1.0, 0.0, 0.5]", "fingers = \"back\"", 1))
    with pytest.raises(CabinRigError, match=r"phone_positions.P1\] fingers must be a direction \[x, y, z\]"):
        load_cabin(bad)


def test_creases_mark_skin_an_expression_gathers_and_nothing_else():
    """The crease field is the skin's compression against the face at rest: 0 at rest, 0 where the skin
    stretches, up to 1 where it gathers, 0 outside its mask; a degenerate (zero-length) edge is no NaN."""
    from isu_validate.render.people.creases import FULL, crease_field
    n = 6
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    rest = np.column_stack([x.ravel(), y.ravel(), np.zeros(n * n)]) * 0.01
    quads = [(j * n + i, j * n + i + 1, (j + 1) * n + i) for j in range(n - 1) for i in range(n - 1)]
    quads += [(j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i) for j in range(n - 1) for i in range(n - 1)]
    faces = np.array(quads)
    everywhere = np.ones(n * n, bool)
    assert np.all(crease_field(faces, rest, rest, everywhere) == 0.0)
    squeezed = rest * np.array([1.0 - FULL, 1.0, 1.0])          # gathered across x by a full crease's share
    field = crease_field(faces, rest, squeezed, everywhere)
    assert 0.2 < field.mean() < 1.0 and field.max() <= 1.0
    assert np.all(crease_field(faces, rest, rest * 1.3, everywhere) == 0.0)          # stretched: no fold
    half = rest[:, 0] < 0.025
    assert np.all(crease_field(faces, rest, squeezed, half)[~half] == 0.0)
    rest_dup = rest.copy()
    rest_dup[1] = rest_dup[0]                                     # two vertices on one point at rest
    assert np.isfinite(crease_field(faces, rest_dup, squeezed, everywhere)).all()


def test_the_bob_has_its_locks_behind_the_forehead_and_short_hair_stays_the_shell(people, model):
    """87 tapered cards over the bob, rooted on its shell and lying along it, none over the forehead (no
    fringe: the planners' decision on issue 32) nor below the bob's edge; short hair and the buzz cut have none."""
    from isu_validate.render.people import hair

    for style in ("short", "buzz"):
        topology = _load(people.topology("male", style))
        assert len(topology["lock_face"]) == 0 and len(topology["lock_faces"]) == 0, style
    topology = _load(people.topology("female"))
    state = _load(people.driver_state("FEMALE", "H3", "W2", "HAPPY", "NONE"))
    n = len(topology["lock_face"])
    assert n == hair.LOCKS["bob"] == 87 and state["locks"].shape == (n * 2 * hair.LOCK_POINTS, 3)
    assert topology["lock_faces"].max() == len(state["locks"]) - 1 and np.isfinite(state["locks"]).all()
    rest = people_module.Body(model, people_module.driver_phenotype("FEMALE", "H3", "W2")).evaluate({})
    style = hair.HairStyle("bob", topology["hair_i"], topology["hair_j"], topology["hair_t"], topology["hair_faces"],
                           topology["hair_thickness"], topology["field_scalp"])
    v = rest.vertices.astype(np.float64)
    shell = hair.hair_vertices(style, v, hair.vertex_normals(v, topology["faces"])).astype(np.float64)
    locks = hair.Locks(topology["lock_face"], topology["lock_bary"], topology["lock_length"], topology["lock_width"],
                       topology["lock_lift"], int(topology["lock_crown"]))
    cards = hair.lock_vertices(locks, topology["hair_faces"], shell).astype(np.float64)
    nearest = np.min(np.linalg.norm(cards[:, None] - shell[None], axis=2), axis=1)
    assert np.median(nearest) < 0.01                                     # they lie on the bob, not off it
    across = np.linalg.norm(cards[0::2] - cards[1::2], axis=1).reshape(n, hair.LOCK_POINTS)
    assert np.allclose(across[:, -1] / across[:, 0], hair.TIP_SHARE, atol=0.01)   # tapered to the tip
    head = hair.head_frame(rest)
    bearing = head.bearing(cards)
    knots = np.array(hair._HAIRLINES["bob"])
    hairline = head.eyes[2] + head.size * np.interp(bearing, knots[:, 0], knots[:, 1])
    z = cards[:, 2]
    forehead = (bearing > 0.45) & (z > head.eyes[2] - 0.01) & (z < hairline)   # between the brows and the hairline
    face = (bearing > 0.7) & (z < hairline)
    assert not forehead.any() and not face.any(), f"{forehead.sum()} over the forehead, {face.sum()} over the face"
    # none hangs below the bob: wherever a lock is, the shell (within 6 cm across) reaches at least as low
    across_m = np.linalg.norm(cards[:, None, :2] - shell[None, :, :2], axis=2)
    lowest = np.where(across_m < 0.06, shell[None, :, 2], np.inf).min(axis=1)
    assert (lowest <= z + 0.005).all(), f"{(lowest > z + 0.005).sum()} lock vertices below the bob"
    roots = cards.reshape(n, hair.LOCK_POINTS, 2, 3)[:, 0].mean(axis=1)
    assert (head.bearing(roots) <= hair.FACE_SIDE + 0.05).all()         # rooted behind the face's side


READ_PHONES = ("P3", "P4", "P6", "P7", "P10")   # held up to be read: the screen faces the driver's eyes
EDGE_ON = 0.25   # |cos| under this: the screen is seen at more than 75 degrees from face-on, a sliver at most


def _screen_towards(camera_position, pose) -> float:
    """Cosine between the phone's screen normal (its local +z) and the direction to the camera."""
    centre, rotation = pose.phone
    to_camera = np.asarray(camera_position, dtype=float) - centre
    return float(rotation[:, 2] @ to_camera / np.linalg.norm(to_camera))


@pytest.mark.parametrize("gender, height, weight", [("MALE", "H2", "W2"), ("FEMALE", "H1", "W1")])
def test_a_phone_held_to_be_read_shows_its_back_or_edge_to_the_passenger_side_camera(model, gender, height, weight):
    """As in the distracted-driver photos the rig stands for: a phone held to the face turns its dark back to
    the camera. From the rig's earlier place, behind the face, every one showed its lit screen."""
    from capture.camera import load_camera
    from isu_validate.render.people.seated import seat_and_pose
    camera, cabin = load_camera("passenger-side"), load_cabin("default")
    before = (0.05, -0.40, 1.10)
    body = people_module.Body(model, people_module.driver_phenotype(gender, height, weight))
    for position in READ_PHONES:
        pose = seat_and_pose(body, cabin, position)
        (u, v), = camera.project(pose.phone[0][None, :])
        assert 0 <= u < camera.width and 0 <= v < camera.height, position   # the phone is in the frame
        assert _screen_towards(camera.position, pose) < EDGE_ON, position
        assert _screen_towards(before, pose) > 0.15, position


def test_a_tilt_turns_the_phone_about_its_own_axes_by_the_positions_shares():
    """seated.tilted: tip brings the phone's top towards its screen's side, roll turns it about its length, turn
    about its screen's normal; a position's `tilt` shares scale each (at the ear only the turn, along the cheek);
    no tilt is the rig's angle itself."""
    from isu_validate.render.people.seated import _euler_xyz, tilted
    positions = load_cabin("default")["phone_positions"]
    reading, ear = positions["P5"], positions["P1"]
    rig = _euler_xyz(reading["rotation_deg"])
    assert tilted(reading, (0.0, 0.0, 0.0)) is reading and tilted(None, (10.0, 0.0, 0.0)) is None

    def turned(spec, tilt):
        return tilted(spec, tilt)["rotation"]

    tip = turned(reading, (20.0, 0.0, 0.0))
    np.testing.assert_allclose(tip[:, 0], rig[:, 0], atol=1e-9)                       # about the width
    assert tip[:, 1] @ rig[:, 2] == pytest.approx(np.sin(np.radians(20.0)), abs=1e-9)  # top to the screen's side
    roll = turned(reading, (0.0, 20.0, 0.0))
    np.testing.assert_allclose(roll[:, 1], rig[:, 1], atol=1e-9)
    assert roll[:, 2] @ rig[:, 2] == pytest.approx(np.cos(np.radians(20.0)), abs=1e-9)
    turn = turned(reading, (0.0, 0.0, 20.0))
    np.testing.assert_allclose(turn[:, 2], rig[:, 2], atol=1e-9)
    assert turn[:, 1] @ rig[:, 1] == pytest.approx(np.cos(np.radians(20.0)), abs=1e-9)
    # at the ear the phone lies against the cheek: tip and roll are ignored, the turn is kept
    assert ear["tilt"] == [0.0, 0.0, 1.0]
    at_ear, rig_ear = turned(ear, (20.0, -20.0, 15.0)), _euler_xyz(ear["rotation_deg"])
    np.testing.assert_allclose(at_ear[:, 2], rig_ear[:, 2], atol=1e-9)
    assert at_ear[:, 1] @ rig_ear[:, 1] == pytest.approx(np.cos(np.radians(15.0)), abs=1e-9)


def test_a_scenes_phone_tilt_is_zero_without_a_phone_and_keys_the_store_to_a_tenth_only_when_set(people):
    tilt_of = people_module.phone_tilt_of
    assert tilt_of({"phone_position": "NONE", "phone_tip": 12.0}) == (0.0, 0.0, 0.0)   # an inactive feature's value
    assert tilt_of({"phone_position": "P5"}) == (0.0, 0.0, 0.0)                        # isu-paper: the rig's angle
    assert tilt_of({"phone_position": "P5", "phone_tip": 12.34, "phone_roll": -3.06, "phone_turn": None}) == \
        (12.34, -3.06, 0.0)
    assert people_module._tilt_input((0.0, 0.0, 0.0)) == {}   # entries posed before the tilt keep their keys
    assert people_module._tilt_input((12.3, 0.0, 0.0)) == {"phone_tilt": [12.3, 0.0, 0.0]}
    # one pose per tenth of a degree: the key and the pose alike
    near = [people.driver_state("MALE", "H2", "W2", "SERIOUS", "P5", None, "WHEEL", "ROAD", (t, 0.0, 0.0))
            for t in (12.34, 12.26)]
    assert near[0] == near[1]
    np.testing.assert_allclose(_load(near[0])["phone_rotation"],
                               _load(people.driver_state("MALE", "H2", "W2", "SERIOUS", "P5", None, "WHEEL", "ROAD",
                                                         (12.3, 0.0, 0.0)))["phone_rotation"], atol=1e-6)


@pytest.mark.parametrize("gender, height, weight, position, tilt", [
    ("FEMALE", "H1", "W1", "P5", (20.0, -20.0, 20.0)), ("MALE", "H4", "W4", "P9", (-20.0, 20.0, -20.0)),
    ("MALE", "H2", "W2", "P10", (20.0, 20.0, -20.0)), ("FEMALE", "H3", "W2", "P1", (0.0, 0.0, 20.0))])
def test_a_phone_tilted_in_the_hand_is_gripped_as_at_the_rigs_angle(people, gender, height, weight, position, tilt):
    """isu-diverse's phone_tip, phone_roll and phone_turn at their limits: the pose holds the phone at the tilted
    angle, the fingers close round its edge, and the body still clears seat and wheel."""
    from isu_validate.render.people.seated import _euler_xyz, tilted
    spec = people.cabin["phone_positions"][position]
    state = _load(people.driver_state(gender, height, weight, "SERIOUS", position, None, "WHEEL", "ROAD", tilt))
    np.testing.assert_allclose(state["phone_rotation"], tilted(spec, tilt)["rotation"], atol=1e-5)
    moved = np.degrees(np.arccos(np.clip((np.trace(_euler_xyz(spec["rotation_deg"]).T @ state["phone_rotation"])
                                          - 1) / 2, -1, 1)))
    assert moved > 15.0, f"{position}: the phone turned only {moved:.1f} deg from the rig's angle"
    m = driver_measures(state, _load(people.topology("female" if gender == "FEMALE" else "male")), people.cabin)
    for part in ("cushion", "back", "base", "headrest0", "wheel_body"):
        assert m[f"clear_{part}"] >= 0.0, (position, tilt, part, m)
    assert m["clear_wheel_hands"] >= -HAND_TOUCH, (position, tilt, m)
    assert m["phone_to_palm"] < 0.016 and m["phone_clear_hand"] > -PHONE_PRESS, (position, tilt, m)
    assert m["phone_front_touch"] >= 20, (position, tilt, m)


def test_a_phone_position_with_malformed_tilt_shares_is_refused_with_the_fix(tmp_path):
    from isu_validate.render.cabin import CabinRigError
    text = (Path(__file__).parents[1] / "rigs" / "cabins" / "default.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("tilt = [0.0, 0.0, 1.0]", "tilt = [0.0, 1.5]", 1))
    with pytest.raises(CabinRigError, match=r"phone_positions.P1\] tilt must be three shares \[tip, roll, turn\] "
                                            r"between 0 and 1"):
        load_cabin(bad)
