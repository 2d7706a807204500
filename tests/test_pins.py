"""Known values for the real weights: the FID Inception, the VGG19 of style transfer and the
shipped reference ISU give today what they gave when pinned (``tests/pins.py``), and the
reference ISU's accuracy on its shipped renders is what its model card claims."""
import json

import numpy as np
import pytest

from tests import pins, update_pins

pytestmark = pytest.mark.usefixtures("few_torch_threads")


@pytest.fixture(scope="module")
def computed():
    cache = {}

    def values(name):
        if name not in cache:
            cache[name] = pins.PINS[name].compute()
        return cache[name]
    return values


@pytest.mark.parametrize("name", list(pins.PINS))
def test_real_weights_give_the_pinned_values(name, computed):
    pin, pinned = pins.PINS[name], pins.read(name)
    assert pins.changed_inputs(pin, pinned) == [], f"pinned inputs changed: re-pin with `{pinned['update']}`"
    moved = pins.differences(pinned["values"], computed(name), pin.rel, pin.abs)
    assert not moved, (f"{len(moved)} value(s) left the tolerance (rel {pin.rel}, abs {pin.abs}); if the change "
                       f"is deliberate, re-pin with `{pinned['update']}`:\n" + "\n".join(moved[:20]))


def upper_tail(probabilities: list[float], k: int) -> float:
    """P(at least k successes) of independent events with these probabilities (Poisson binomial)."""
    dist = np.zeros(len(probabilities) + 1)
    dist[0] = 1.0
    for p in probabilities:
        dist[1:] = dist[1:] * (1 - p) + dist[:-1] * p
        dist[0] *= 1 - p
    return float(dist[k:].sum())


def test_reference_isu_on_its_shipped_renders_is_as_accurate_as_its_model_card_says(computed):
    """The pin alone would bless any retrained model; the card keeps it honest: the number of
    wrong answers on the shipped renders (first scenes of the card's held-out set) must be
    plausible for the card's per-feature accuracies (one-sided, 0.1% false-alarm rate)."""
    card = pins.model_card()["held_out"]["per_feature"]
    images = computed("reference_isu")["images"]
    assert len(images) == pins.N_RENDERS
    error_rates = [1.0 - card[feature]["accuracy"] for image in images.values() for feature in image["answers"]]
    wrong = sum(len(image["wrong"]) for image in images.values())
    assert len(error_rates) >= 8 * pins.N_RENDERS  # every render asks most features
    assert upper_tail(error_rates, wrong) > 1e-3, (
        f"{wrong} wrong answers where the model card expects {sum(error_rates):.1f}")
    for image in images.values():  # F_qa is the weighted share of right answers: 1 exactly when none is wrong
        assert (image["f_qa"] == 1.0) == (not image["wrong"])


def test_the_tail_probability_by_hand():
    assert upper_tail([0.5, 0.5], 1) == pytest.approx(0.75)
    assert upper_tail([0.1, 0.2, 0.0], 2) == pytest.approx(0.02)
    assert upper_tail([0.3], 0) == pytest.approx(1.0)


# ------------------------------------------------------------------ the regeneration command
def test_update_prints_old_to_new_and_rewrites_the_pin(tmp_path, monkeypatch, capsys):
    (tmp_path / "input.txt").write_text("fixed input")
    state = {"value": 1.0}
    pin = pins.Pin("toy", "a toy pin", lambda: [tmp_path / "input.txt"],
                   lambda: {"x": state["value"], "label": "A"}, rel=1e-3, abs=0.0)
    monkeypatch.setattr(pins, "PINS_DIR", tmp_path)
    monkeypatch.setitem(pins.PINS, "toy", pin)
    update_pins.update("toy")
    assert "toy: new pin" in capsys.readouterr().out
    assert pins.read("toy")["values"] == {"x": 1.0, "label": "A"}
    state["value"] = 1.0005  # within the tolerance: noise, reported but not listed
    update_pins.update("toy")
    assert "0 value(s) moved beyond the tolerance, 1 within it" in capsys.readouterr().out
    state["value"] = 2.0
    (tmp_path / "input.txt").write_text("another input")
    update_pins.update("toy")
    out = capsys.readouterr().out
    assert "1 value(s) moved beyond the tolerance" in out and "/x: pinned 1.0005 -> now 2.0" in out
    assert "input input.txt: changed" in out
    stored = json.loads((tmp_path / "toy.json").read_text())
    assert stored["values"]["x"] == 2.0 and stored["update"].endswith("tests.update_pins toy")


def test_differences_name_the_path_and_both_values():
    pinned = {"a": {"b": [1.0, 2.0]}, "answers": {"seat_belt": "YES"}, "gone": 1}
    new = {"a": {"b": [1.0, 2.1]}, "answers": {"seat_belt": "NO"}, "extra": 2}
    assert pins.differences(pinned, new, rel=1e-3, abs_=0.0) == [
        "/extra: pinned '(absent)' -> now 2", "/gone: pinned 1 -> now '(absent)'",
        "/a/b[1]: pinned 2.0 -> now 2.1", "/answers/seat_belt: pinned 'YES' -> now 'NO'"]
    assert pins.differences({"x": 1.0}, {"x": float("nan")}, rel=1.0, abs_=1.0) == ["/x: pinned 1.0 -> now nan"]
    assert pins.differences([1, 2], [1, 2, 3], rel=1.0, abs_=1.0) == [": pinned [1, 2] -> now [1, 2, 3]"]


def test_unknown_pin_names_are_refused(capsys):
    with pytest.raises(SystemExit):
        update_pins.main(["nope"])
    assert "unknown pin(s) nope; pins: inception, vgg, reference_isu" in capsys.readouterr().err
