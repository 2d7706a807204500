"""The diversity objective: novelty by hand on small scenes, and the objectives NSGA-II receives.

Novelty (README "Search and runs", paper "Fitness Function Definition") is the distance to
the *nearest* scene proposed before, averaged per feature: categorical mismatch 1, ordered
features |a-b|/range, a feature active in only one of the two scenes 1, inactive in both 0.
The search minimises [response fitness, -novelty]; a sign slip or a constant there makes
NSGA-II minimise diversity or ignore it, and nothing else in the suite would notice.
"""
import numpy as np
import pytest

from isu_validate.archive import Archive
from isu_validate.pipeline import PipelineConfig
from isu_validate.search import RunConfig, loop, run_search
from isu_validate.search.diversity import DiversityTracker
from isu_validate.space import load_space, space_from_dict

# five features: the distance of two scenes is (sum of per-feature distances) / 5
SMALL = space_from_dict({"features": {
    "colour": {"type": "categorical", "values": ["RED", "GREEN", "BLUE"]},
    "size": {"type": "ordinal", "values": ["S", "M", "L"]},                   # range 2
    "angle": {"type": "continuous", "low": 0.0, "high": 10.0},                # range 10
    "bag": {"type": "categorical", "values": ["NO", "YES"]},
    "bag_colour": {"type": "categorical", "values": ["BLACK", "WHITE"], "active_when": {"bag": "YES"}}}})

S1 = {"colour": "RED", "size": "S", "angle": 0.0, "bag": "NO", "bag_colour": "BLACK"}
S2 = {"colour": "RED", "size": "L", "angle": 10.0, "bag": "NO", "bag_colour": "WHITE"}
S3 = {"colour": "GREEN", "size": "S", "angle": 5.0, "bag": "YES", "bag_colour": "BLACK"}
S4 = {"colour": "RED", "size": "M", "angle": 2.5, "bag": "NO", "bag_colour": "BLACK"}


def novelties(scenes, capacity=1024):
    tracker = DiversityTracker(SMALL, capacity=capacity)
    return [tracker.add(s) for s in scenes]


def test_first_scene_has_nothing_to_compare_with_and_gets_one():
    assert novelties([S4]) == [1.0]
    assert novelties([S4, S4]) == [1.0, 0.0]


def test_hand_computed_novelty_is_the_nearest_distance_not_the_mean():
    # S2 vs S1: size |2-0|/2 = 1, angle 10/10 = 1, bag_colour inactive in both = 0       -> 2/5
    # S3 vs S1: colour 1, angle 0.5, bag 1, bag_colour active in S3 only 1                 -> 3.5/5
    # S3 vs S2: colour 1, size 1, angle 0.5, bag 1, bag_colour 1                           -> 4.5/5
    # S4 vs S1: size 0.5, angle 0.25 -> 0.75/5; vs S2: 0.5 + 0.75 -> 1.25/5; vs S3: 1 + 0.5 + 0.25 + 1 + 1 -> 3.75/5
    got = novelties([S1, S2, S3, S4])
    assert got == pytest.approx([1.0, 0.4, 0.7, 0.15], abs=1e-6)
    mean_instead = [1.0, 0.4, (0.7 + 0.9) / 2, (0.15 + 0.25 + 0.75) / 3]
    assert got[2:] != pytest.approx(mean_instead[2:], abs=1e-3)


def test_inactive_features_do_not_count_and_latent_values_are_ignored():
    # S1 with another latent bag colour is the same canonical scene: novelty 0
    assert novelties([S1, dict(S1, bag_colour="WHITE")])[1] == 0.0
    # the bag colour is active in both here and differs: only that feature counts
    assert novelties([S3, dict(S3, bag_colour="WHITE")])[1] == pytest.approx(1 / 5)
    # a bag appears: bag differs (1) and bag_colour is active in one scene only (1)
    assert novelties([S1, dict(S1, bag="YES")])[1] == pytest.approx(2 / 5)


def test_novelty_is_against_earlier_scenes_only_and_survives_growth():
    scenes = [S1, S2, S3, S4, dict(S4, angle=3.5), dict(S3, colour="BLUE")]
    expected = [1.0, 0.4, 0.7, 0.15, 0.1 / 5, 1 / 5]
    assert novelties(scenes, capacity=2) == pytest.approx(expected, abs=1e-6)  # storage grows twice
    assert novelties(scenes[::-1])[0] == 1.0


def test_the_paper_space_counts_every_feature_of_the_scene():
    space = load_space()
    base = space.sample(np.random.default_rng(4), 1)[0]
    base.update(luggage="NO", child_seat="NO", tshirt_colour="WHITE", driver_gender="MALE")
    tracker = DiversityTracker(space)
    tracker.add(base)
    tracker.add(dict(base, luggage="YES"))  # farther from what follows than the first scene
    # nearest of the earlier scenes is the first: one categorical change out of all features
    assert tracker.add(dict(base, tshirt_colour="BLACK")) == pytest.approx(1 / len(space.names))
    assert tracker.add(dict(base, tshirt_colour="BLACK", driver_gender="FEMALE")) == pytest.approx(
        1 / len(space.names))
    assert len(tracker) == 4


def hand_novelty(space, scenes):
    """Novelty from ``SceneSpace.distances`` (the NaN route, independent of the tracker's)."""
    vectors = np.array([space.canonical_vector(s) for s in scenes])
    return [1.0] + [float(space.distances(vectors[i], vectors[:i]).min()) for i in range(1, len(scenes))]


def test_nsga2_receives_fitness_and_minus_novelty_from_the_run_loop(tmp_path, monkeypatch):
    """Through the loop's objective function: the rows NSGA-II is told are [f_qa, -novelty]."""
    told = []

    def recording(name, space, pop_size, seed):
        algorithm = real_make_algorithm(name, space, pop_size, seed)
        tell = algorithm.tell
        algorithm.tell = lambda F, *records: told.append(np.array(F, dtype=float)) or tell(F, *records)
        return algorithm

    real_make_algorithm = loop.make_algorithm
    monkeypatch.setattr(loop, "make_algorithm", recording)
    pipeline = PipelineConfig(run_dir=str(tmp_path / "run"), factory="tests.doubles:build")
    summary = run_search(RunConfig(pipeline=pipeline, algorithm="nsga2", pop_size=6, seed=5, budget_tests=24))
    assert summary.tests == 24 and [len(F) for F in told] == [6, 6, 6, 6]
    archive = Archive(tmp_path / "run" / "archive.sqlite")
    records = sorted(archive, key=lambda r: (r.generation, r.index))
    archive.close()
    space = load_space()
    F = np.concatenate(told)
    expected_novelty = hand_novelty(space, [r.scene for r in records])
    assert [r.f_div for r in records] == pytest.approx(expected_novelty, abs=1e-6)
    assert F[:, 1] == pytest.approx([-n for n in expected_novelty], abs=1e-6)   # -diversity: maximised
    assert F[:, 0] == pytest.approx([r.primary for r in records])
    assert len(set(np.round(F[:, 1], 6))) > 3 and len(set(F[:, 0])) > 1          # neither objective constant
