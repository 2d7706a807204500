"""Atomic writes (isu_validate/atomic.py): the old file or the whole new one, never half, never litter."""
from __future__ import annotations

import json
import os
import stat

import pytest

from isu_validate.atomic import atomic_open, atomic_path, write_bytes, write_json, write_text


def test_writes_replace_the_file_whole_and_leave_nothing_beside_it(tmp_path):
    target = tmp_path / "deep" / "run.json"          # missing folders are made
    write_json(target, {"a": 1}, indent=2)
    assert json.loads(target.read_text()) == {"a": 1}
    write_text(target, "second")
    assert target.read_text() == "second"
    write_bytes(target, b"\x00third")
    assert target.read_bytes() == b"\x00third"
    with atomic_open(target, newline="") as fh:
        fh.write("fourth,é\r\n")
    assert target.read_bytes() == "fourth,é\r\n".encode()
    assert os.listdir(target.parent) == ["run.json"]


def test_a_failed_write_keeps_the_old_file_and_removes_the_temporary_one(tmp_path):
    target = tmp_path / "summary.json"
    target.write_text("old")
    with pytest.raises(TypeError):
        write_json(target, {"not json": object()})
    with pytest.raises(RuntimeError, match="disk full"):
        with atomic_open(target) as fh:
            fh.write("half a fi")
            raise RuntimeError("disk full")
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise KeyboardInterrupt
    assert target.read_text() == "old"
    assert os.listdir(tmp_path) == ["summary.json"]


def test_the_temporary_path_is_hidden_beside_the_target_and_keeps_its_suffix_when_asked(tmp_path):
    target = tmp_path / "frame_0001.png"
    with atomic_path(target) as tmp:
        assert tmp.parent == tmp_path and tmp.name.startswith(".tmp-frame_0001.png.") and tmp.suffix == ".tmp"
        tmp.write_bytes(b"png")
    with atomic_path(target, keep_suffix=True) as tmp:   # for writers that pick the format by the name
        assert tmp.name.startswith(".tmp-") and tmp.name.endswith(".tmp.png")
        tmp.write_bytes(b"png2")
    assert target.read_bytes() == b"png2"


def test_the_file_gets_the_permissions_a_plain_open_gives(tmp_path):
    plain, atomic = tmp_path / "plain.txt", tmp_path / "atomic.txt"
    plain.write_text("x")
    write_text(atomic, "x")
    assert stat.S_IMODE(atomic.stat().st_mode) == stat.S_IMODE(plain.stat().st_mode)


def test_atomic_open_refuses_appending(tmp_path):
    with pytest.raises(ValueError, match="whole file"):
        with atomic_open(tmp_path / "log.txt", "a"):
            pass
