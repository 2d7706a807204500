"""The one reader of a run directory (isu_validate/archive/run_dir.py): what it finds and how it refuses."""
from __future__ import annotations

import pytest

from isu_validate.archive import Archive, RunDir, RunDirError, TestRecord as Record, find_runs, open_run
from isu_validate.archive.run_file import RunError, read_run_file, write_run_file
from isu_validate.errors import UserError


def _run(folder, tests=2):
    write_run_file(folder, {"config": {"pipeline": {"sut": "s"}}})
    archive = Archive(folder / "archive.sqlite")
    for i in range(tests):
        archive.add(Record(test_id=f"g0000-i{i:03d}", generation=0, index=i, algorithm="rs", seed=1,
                           scene_key=str(i), scene={}, canonical={}, image=f"images/g0000-i{i:03d}.png"))
    archive.close()
    return folder


def test_a_run_reads_its_file_tests_and_paths(tmp_path):
    run = open_run(_run(tmp_path / "r"))
    assert run.info()["config"]["pipeline"]["sut"] == "s"
    records = run.records()
    assert [r.test_id for r in records] == ["g0000-i000", "g0000-i001"]
    assert run.label_file("g0000-i001") == tmp_path / "r" / "labels" / "g0000-i001.json"
    assert run.image_path(records[0]) is None                       # not rendered: no file
    run.image_file("g0000-i000").parent.mkdir()
    run.image_file("g0000-i000").write_bytes(b"png")
    assert run.image_path(records[0]) == tmp_path / "r" / "images" / "g0000-i000.png"
    assert RunDir(tmp_path / "nothing").records() == []             # and no archive is created
    assert not (tmp_path / "nothing").exists()


def test_what_is_not_a_run_is_refused_with_one_user_error(tmp_path):
    with pytest.raises(RunDirError, match="is not a run directory") as caught:
        open_run(tmp_path)
    assert isinstance(caught.value, UserError) and isinstance(caught.value, FileNotFoundError)
    (tmp_path / "run.json").write_text("{half")
    with pytest.raises(RunDirError, match="is not valid JSON"):
        open_run(tmp_path).info()
    with pytest.raises(RunError, match="is not valid JSON .*the run cannot be resumed"):
        read_run_file(tmp_path)
    with pytest.raises(RunDirError, match="neither a run directory nor a folder of runs"):
        find_runs([tmp_path / "empty"])


def test_a_folder_of_runs_stands_for_the_runs_in_it(tmp_path):
    a, b = _run(tmp_path / "all" / "a"), _run(tmp_path / "all" / "b")
    assert find_runs([tmp_path / "all", a]) == [a.resolve(), b.resolve()]
