"""Duplicate elimination in spaces small enough for collisions: within one batch, against
earlier batches, and with scenes that differ only in inactive features."""
import numpy as np
import pytest
from pymoo.core.population import Population

from isu_validate.search import make_algorithm
from isu_validate.search.operators import CanonicalDuplicateElimination
from isu_validate.search.problem import SceneProblem
from isu_validate.space import space_from_dict

# 16 scenes: random offspring of a population of 6 collide all the time
SIXTEEN = space_from_dict({"features": {n: {"type": "categorical", "values": ["0", "1"]} for n in "abcd"}})
# a bag colour exists only with a bag: "bag NO" scenes differing in colour are the same scene
BAGS = space_from_dict({"features": {
    "a": {"type": "categorical", "values": ["0", "1"]},
    "bag": {"type": "categorical", "values": ["NO", "YES"]},
    "colour": {"type": "categorical", "values": ["RED", "BLUE"], "active_when": {"bag": "YES"}}}})


def population(space, scenes):
    problem = SceneProblem(space)
    return problem, Population.new(X=np.array([problem.to_x(s) for s in scenes], dtype=object))


def test_duplicates_within_one_batch_are_marked_after_their_first():
    problem, pop = population(BAGS, [
        {"a": "0", "bag": "NO", "colour": "RED"},
        {"a": "0", "bag": "NO", "colour": "BLUE"},    # same canonical scene as the first
        {"a": "1", "bag": "YES", "colour": "RED"},
        {"a": "1", "bag": "YES", "colour": "BLUE"},   # the colour is active here: a new scene
        {"a": "1", "bag": "YES", "colour": "RED"}])   # the third again
    dedup = CanonicalDuplicateElimination(problem, seen=set())
    _, kept, dropped = dedup.do(pop, return_indices=True)
    assert (kept, dropped) == ([0, 2, 3], [1, 4])


def test_scenes_already_proposed_and_those_of_other_batches_are_duplicates():
    scenes = [{"a": "0", "bag": "NO", "colour": "RED"}, {"a": "1", "bag": "NO", "colour": "RED"}]
    problem, pop = population(BAGS, scenes)
    _, earlier = population(BAGS, [{"a": "1", "bag": "NO", "colour": "BLUE"}])
    dedup = CanonicalDuplicateElimination(problem, seen={BAGS.key(scenes[0])})
    _, kept, dropped = dedup.do(pop, earlier, return_indices=True)
    assert (kept, dropped) == ([], [0, 1])


def test_nsga2_never_proposes_a_scene_twice_in_a_sixteen_scene_space():
    """Collisions are certain here: without the within-batch check, dozens of repeats over these seeds."""
    repeats = 0
    for seed in range(40):
        algorithm = make_algorithm("nsga2", SIXTEEN, pop_size=6, seed=seed)
        keys = []
        for _ in range(2):  # 12 of the 16 scenes
            scenes = algorithm.ask(6)
            keys += [SIXTEEN.key(s) for s in scenes]
            algorithm.tell(np.array([[float(s["a"] == "1"), -0.5] for s in scenes]))
        assert len(keys) == 12, seed
        repeats += len(keys) - len(set(keys))
    assert repeats == 0


@pytest.mark.parametrize("name", ["nsga2", "rs"])
def test_batches_run_until_the_space_is_exhausted_without_a_repeat(name):
    keys = []
    algorithm = make_algorithm(name, BAGS, pop_size=4, seed=3)  # 6 canonical scenes: 4, then 2, then none
    while scenes := algorithm.ask(4):
        keys += [BAGS.key(s) for s in scenes]
        algorithm.tell(np.array([[0.5, -0.5]] * len(scenes)))
    assert len(keys) == len(set(keys)) == 6
