"""The public real photo sets of docs/real-sets/ read with their label maps: counts as their sources give them.
The photos are not in the repository (their licences do not allow it): set ISU_VALIDATE_REAL_SETS to a folder
holding them under the names of docs/real-sets/README.md, which says where each comes from."""
import os
from collections import Counter
from pathlib import Path

import pytest

from isu_validate.realphotos import label_photos, load_label_map, read_photo_set
from isu_validate.space import load_space

ROOT = Path(os.environ.get("ISU_VALIDATE_REAL_SETS", "/nonexistent"))
MAPS = Path(__file__).resolve().parents[1] / "docs" / "real-sets"
# set -> (label map, photos, {feature: {answer: count}}, conflicts skipped)
EXPECTED = {
    "statefarm-dakp": ("statefarm.toml", 800, {"phone_position": {"YES": 320, "NO": 480}}, 0),
    "hcl-seatbelt-phone": ("hcl-seatbelt-phone.toml", 581,
                           {"phone_position": {"YES": 255}, "seat_belt": {"YES": 217, "NO": 234}}, 13),
    "revitsone-front": ("revitsone-front.toml", 183, {"phone_position": {"YES": 38, "NO": 145}}, 0),
}


@pytest.mark.parametrize("name", list(EXPECTED))
def test_a_public_real_set_reads_as_its_source_says(name):
    if not (ROOT / name).is_dir():
        pytest.skip(f"{name} is not in ISU_VALIDATE_REAL_SETS ({ROOT}): fetch it as docs/real-sets/README.md says")
    label_map, photos, answers, conflicts = EXPECTED[name]
    photo_set = read_photo_set(ROOT / name)
    labelled = label_photos(photo_set, load_label_map(MAPS / label_map, load_space("isu-paper")), skip_conflicts=True)
    assert len(photo_set.photos) == photos
    counted = {f: dict(Counter(p.answers[f] for p in labelled.photos if f in p.answers)) for f in answers}
    assert counted == answers and sum(labelled.conflicts.values()) == conflicts
