"""The command protocol (JSON on stdin, JSON on stdout), repeats, and ``isu-validate sut check``."""
from __future__ import annotations

import json
import sys
import textwrap

import pytest

from isu_validate.cli import main
from isu_validate.space import load_space
from isu_validate.sut import build_request, open_sut

SCENE = {"driver_gender": "FEMALE", "driver_emotion": "SERIOUS", "driver_height": "H1", "driver_weight": "W1",
         "phone_position": "NONE", "seat_belt": "NO", "tshirt_colour": "WHITE", "child_seat": "NO",
         "car_lights": "OFF", "external_light": "MEDIUM", "luggage": "YES", "luggage_orientation": 45.0,
         "luggage_position": "BACK", "luggage_colour": "YELLOW", "phone_codriver_seat": "NO",
         "colabottle_codriver_seat": "YES", "colacan_codriver_seat": "NO"}

# A small industrial-prototype stand-in: answers every question with its first option,
# except what the environment tells it to do (so one script covers every behaviour).
SCRIPT = textwrap.dedent('''
    import json, os, sys, time
    msg = json.load(sys.stdin)
    behaviour = os.environ.get("FAKE_ISU", "ok")
    if behaviour == "crash":
        print("model weights not found", file=sys.stderr); sys.exit(3)
    if behaviour == "hang":
        time.sleep(10)
    if behaviour == "garbage":
        print("Segmentation fault (core dumped)"); sys.exit(0)
    if behaviour == "echo":
        print(json.dumps({"answers": {}, "received": msg})); sys.exit(0)
    if msg["mode"] == "vc":
        print(json.dumps({"caption": "A woman in a white T-shirt drives; a yellow suitcase is on the back seat."}))
    else:
        counter = os.environ.get("FAKE_COUNTER")
        n = 0
        if counter:
            n = int(open(counter).read() or 0) if os.path.exists(counter) else 0
            open(counter, "w").write(str(n + 1))
        answers = {q["key"]: q["options"][0] for q in msg["questions"]}
        if n % 3 == 1:
            answers["seat_belt"] = "NO"
        print("loading model...")  # prose before the JSON: tolerated
        print(json.dumps({"answers": answers}))
''')


@pytest.fixture()
def space():
    return load_space()


@pytest.fixture()
def program(tmp_path):
    path = tmp_path / "fake_isu.py"
    path.write_text(SCRIPT)
    return f"command:{sys.executable} {path}"


@pytest.fixture()
def image(tmp_path):
    path = tmp_path / "cabin.png"
    path.write_bytes(b"\x89PNG\r\n\x1a\nfake")
    return path


def test_command_answers_and_receives_the_protocol(space, program, image, monkeypatch):
    sut = open_sut(program, space=space)
    response = sut.query(build_request(space, SCENE, image, "vqa"))
    assert response.error is None and response.extra["outcome"] == "answered"
    assert response.answers["seat_belt"] == "YES" and response.answers["luggage_colour"] == "YELLOW"

    monkeypatch.setenv("FAKE_ISU", "echo")
    echoed = json.loads(sut.query(build_request(space, SCENE, image, "vqa")).raw)["received"]
    assert echoed["mode"] == "vqa" and echoed["image"] == str(image.resolve())
    assert echoed["questions"][0] == {"key": "driver_gender", "question": "Is the driver male or female?",
                                      "options": ["MALE", "FEMALE"]}
    assert "child" not in {q["key"] for q in echoed["questions"]}  # inactive: not asked


def test_command_caption(space, program, image):
    response = open_sut(program, space=space).query(build_request(space, SCENE, image, "vc"))
    assert response.caption.startswith("A woman in a white T-shirt")


@pytest.mark.parametrize("behaviour, message", [
    ("crash", "exited with status 3"),
    ("garbage", "unparseable: no JSON object"),
    ("hang", "timed out after 1 s"),
])
def test_command_failures_are_sut_errors(space, program, image, monkeypatch, behaviour, message):
    monkeypatch.setenv("FAKE_ISU", behaviour)
    response = open_sut(program, space=space, timeout_s=1.0).query(build_request(space, SCENE, image, "vqa"))
    assert message in response.error and response.answers is None
    if behaviour == "crash":
        assert "model weights not found" in response.error


def _running(pid: int) -> bool:
    """Alive and not a zombie (an orphan's zombie may wait for a reaper that a container lacks)."""
    try:
        state = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state != "Z"


def test_a_timeout_kills_the_whole_process_group(space, image, tmp_path):
    """A shell-script SUT that starts a child and hangs: after the timeout neither may live on."""
    import os
    import signal
    import time

    pids = tmp_path / "pids"
    script = tmp_path / "slow_isu.sh"
    script.write_text(f"#!/bin/sh\nsleep 300 &\necho $! >> {pids}\necho $$ >> {pids}\nwait\n")
    script.chmod(0o755)
    try:
        response = open_sut(f"command:{script}", space=space, timeout_s=1.0).query(
            build_request(space, SCENE, image, "vqa"))
        assert "timed out after 1 s" in response.error
        started = [int(p) for p in pids.read_text().split()]
        assert len(started) == 2
        deadline = time.monotonic() + 5  # SIGKILL is delivered asynchronously
        while [pid for pid in started if _running(pid)] and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not [pid for pid in started if _running(pid)], "the SUT's children outlived its timeout"
    finally:  # never leave a sleeping orphan behind, even when the test fails
        for pid in (int(p) for p in pids.read_text().split()) if pids.exists() else ():
            if _running(pid):
                os.kill(pid, signal.SIGKILL)


def test_missing_program_fails_at_open(space):
    with pytest.raises(ValueError, match="not found"):
        open_sut("command:/no/such/isu-program --fast", space=space)
    with pytest.raises(ValueError, match="write command:PROGRAM ARGS"):
        open_sut("command:", space=space)


def test_repeats_vote_and_consistency(space, program, image, tmp_path, monkeypatch):
    monkeypatch.setenv("FAKE_COUNTER", str(tmp_path / "n"))
    sut = open_sut(program, space=space, repeats=3, cache_dir=tmp_path / "cache")
    response = sut.query(build_request(space, SCENE, image, "vqa"))
    # repeats answer YES, NO, YES for the seat belt: the majority is YES, 2 of 3 agree
    assert response.answers["seat_belt"] == "YES"
    assert response.extra["consistency_by_feature"]["seat_belt"] == pytest.approx(2 / 3)
    n = len(response.extra["consistency_by_feature"])
    assert response.extra["consistency"] == pytest.approx((n - 1 + 2 / 3) / n)
    assert response.extra["unanimous"] == pytest.approx((n - 1) / n)
    assert [r["answers"]["seat_belt"] for r in response.extra["per_repeat"]] == ["YES", "NO", "YES"]
    assert (tmp_path / "n").read_text() == "3"
    sut.query(build_request(space, SCENE, image, "vqa"))
    assert (tmp_path / "n").read_text() == "3"  # cached: the program was not run again
    image.write_bytes(image.read_bytes() + b"changed")
    sut.query(build_request(space, SCENE, image, "vqa"))
    assert (tmp_path / "n").read_text() == "6"  # a different image is a different key


def test_errors_are_not_cached(space, program, image, tmp_path, monkeypatch):
    monkeypatch.setenv("FAKE_ISU", "crash")
    sut = open_sut(program, space=space, cache_dir=tmp_path / "cache")
    assert sut.query(build_request(space, SCENE, image, "vqa")).error
    monkeypatch.setenv("FAKE_ISU", "ok")
    assert sut.query(build_request(space, SCENE, image, "vqa")).error is None


def test_sut_check_json(program, image, capsys):
    assert main(["sut", "check", "--sut", program, str(image), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) >= {"answers", "problems", "latency_s"}
    assert len(out["answers"]) == len(load_space().predicted)  # no scene: every predicted feature asked


def test_sut_check_with_scene_judges(program, image, tmp_path, capsys):
    label = tmp_path / "t0001.json"
    label.write_text(json.dumps({"test_id": "t0001", "scene": SCENE}))
    assert main(["sut", "check", "--sut", program, str(image), "--scene", str(label)]) == 0
    out = capsys.readouterr().out
    assert "verdict: f_qa" in out and "failed=True" in out  # first options are wrong for this scene
    assert main(["sut", "check", "--sut", program, str(image), "--mode", "vc", "--json",
                 "--scene", str(label)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert (result["caption"].startswith("A woman")
            and "yellow suitcase" in result["verdict"]["details"]["reference_caption"])


def test_sut_check_reports_errors_and_bad_input(program, image, capsys, monkeypatch):
    monkeypatch.setenv("FAKE_ISU", "garbage")
    assert main(["sut", "check", "--sut", program, str(image)]) == 1
    assert "SUT error: unparseable" in capsys.readouterr().out
    empty = image.parent / "no-model"
    empty.mkdir()
    assert main(["sut", "check", "--sut", "reference", "--sut-option", f"model_dir={empty}", str(image)]) == 2
    assert "no trained reference ISU" in capsys.readouterr().err
    assert main(["sut", "check", "--sut", program, str(image.parent / "nope.png")]) == 2
    assert "nope.png does not exist" in capsys.readouterr().err
    assert main(["sut", "check", "--sut", program, str(image.parent)]) == 2
    err = capsys.readouterr().err
    assert f"{image.parent} is a folder; sut check asks about one image" in err and "does not exist" not in err
    assert f"e.g. {image}" in err
