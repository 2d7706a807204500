"""Frame sources, replayed from recorded device sessions through the real code paths."""
from __future__ import annotations

import json
import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from capture.session import shoot
from capture.sources import (DeviceBusy, DeviceDisconnected, DeviceNotFound, ExposureRequest, PermissionDenied,
                             open_source, parse_spec)
from capture.sources.oak import DepthAISource, frame_meta
from tests.recorded_capture import RecordedCapture, load_depthai_recording
from capture.sources.v4l2 import V4L2Source

DATA = Path(__file__).parent / "data" / "capture"
os.environ.setdefault("DEPTHAI_SEARCH_TIMEOUT", "200")


def recorded_v4l2(name: str, **rec_changes) -> V4L2Source:
    folder = DATA / name
    return V4L2Source("/dev/video0", capture_factory=lambda path: _patched(RecordedCapture(folder), rec_changes),
                      serial="SN-C920-0001")


def _patched(cap: RecordedCapture, changes: dict) -> RecordedCapture:
    for k, v in changes.items():
        setattr(cap, k, v)
    return cap


def test_parse_spec_accepts_the_documented_forms_and_names_them_in_errors():
    assert parse_spec("v4l2:0") == ("v4l2", "0", None)
    assert parse_spec("v4l2:/dev/video2@1280x720") == ("v4l2", "/dev/video2", (1280, 720))
    assert parse_spec("depthai") == ("depthai", "", None)
    assert parse_spec("depthai:18443010D1E8A31200@640x480") == ("depthai", "18443010D1E8A31200", (640, 480))
    assert parse_spec("replay:runs/s1") == ("replay", "runs/s1", None)
    with pytest.raises(ValueError, match="v4l2:/dev/videoN"):
        parse_spec("webcam0")
    with pytest.raises(ValueError, match="needs a target"):
        parse_spec("replay")


def test_manual_exposure_is_read_back_and_a_clamped_value_warns(tmp_path):
    src = recorded_v4l2("v4l2_recorded")
    session = shoot(src, 2, tmp_path / "s", ExposureRequest(exposure_us=5000, iso=64))
    assert session.warnings == []  # 5000 us = 50 units, inside the recorded range
    meta = json.loads((tmp_path / "s" / "frame_0000.json").read_text())
    assert meta["exposure_us"] == pytest.approx(5000)
    assert meta["gain"] == 64 and meta["auto_exposure"] is False
    assert meta["serial"] == "SN-C920-0001" and meta["resolution"] == [64, 48]
    # The recorded driver clamps exposure to 2047 units (204.7 ms): asking for 1 s must warn.
    session = shoot(recorded_v4l2("v4l2_recorded"), 1, tmp_path / "t", ExposureRequest(exposure_us=1_000_000))
    assert any("1e+06 us" in w and "204700" in w for w in session.warnings), session.warnings


def test_a_camera_that_ignores_manual_mode_warns(tmp_path):
    # Some UVC cameras have no manual mode: the auto-exposure control stays in its range [3, 3].
    src = recorded_v4l2("v4l2_recorded", ranges={cv2.CAP_PROP_EXPOSURE: (3, 2047), cv2.CAP_PROP_AUTO_EXPOSURE: (3, 3)})
    session = shoot(src, 1, tmp_path / "s", ExposureRequest(exposure_us=1000))
    assert any("stayed in automatic exposure" in w for w in session.warnings)


def test_unplugging_mid_capture_keeps_the_frames_taken(tmp_path):
    out = tmp_path / "s"
    with pytest.raises(DeviceDisconnected, match=r"after 2.*unplugged.*2 frame\(s\) taken before are kept"):
        shoot(recorded_v4l2("v4l2_unplugged"), 5, out)
    assert sorted(p.name for p in out.glob("frame_*.png")) == ["frame_0000.png", "frame_0001.png"]
    record = json.loads((out / "session.json").read_text())
    assert record["status"] == "failed" and record["frames"] == ["frame_0000.png", "frame_0001.png"]
    assert not list(out.glob(".*tmp*"))  # no half-written files left behind


def test_busy_missing_and_forbidden_devices_get_clear_errors(tmp_path):
    with pytest.raises(DeviceBusy, match="another program"):
        recorded_v4l2("v4l2_recorded", opened=False).open()
    with pytest.raises(DeviceNotFound, match="plugged in"):
        V4L2Source(str(tmp_path / "video9")).open()
    node = tmp_path / "video7"
    node.write_bytes(b"")
    node.chmod(0)
    if os.access(node, os.R_OK):  # root ignores file modes
        pytest.skip("running as root: permissions cannot be denied")
    with pytest.raises(PermissionDenied, match="'video' group"):
        V4L2Source(str(node)).open()


def test_record_then_replay_through_the_same_shoot_path(tmp_path):
    first = shoot(recorded_v4l2("v4l2_recorded"), 3, tmp_path / "rec", ExposureRequest(exposure_us=8000))
    again = shoot(open_source(f"replay:{tmp_path / 'rec'}"), 3, tmp_path / "replayed")
    for a, b in zip(first.frames, again.frames):
        assert np.array_equal(cv2.imread(str(a)), cv2.imread(str(b)))
        ma, mb = (json.loads(p.with_suffix(".json").read_text()) for p in (a, b))
        assert mb["exposure_us"] == ma["exposure_us"] == pytest.approx(8000)
        assert mb["replayed_from"] == str(a)
    with pytest.raises(DeviceDisconnected, match="only 3 frames"):
        shoot(open_source(f"replay:{tmp_path / 'rec'}"), 4, tmp_path / "more")
    assert len(list((tmp_path / "more").glob("frame_*.png"))) == 3


def test_shoot_refuses_to_mix_sessions_and_bad_requests(tmp_path):
    shoot(recorded_v4l2("v4l2_recorded"), 1, tmp_path / "s")
    with pytest.raises(ValueError, match="already holds frames"):
        shoot(recorded_v4l2("v4l2_recorded"), 1, tmp_path / "s")
    with pytest.raises(ValueError, match="either --auto-exposure"):
        ExposureRequest(exposure_us=100, auto=True)
    with pytest.raises(ValueError, match="positive"):
        ExposureRequest(exposure_us=0)


def test_replay_of_a_video_file(tmp_path):
    video = tmp_path / "v.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 10, (64, 48))
    for i in range(4):
        writer.write(np.full((48, 64, 3), 60 * i, np.uint8))
    writer.release()
    session = shoot(open_source(f"replay:{video}"), 4, tmp_path / "s")
    assert len(session.frames) == 4
    with pytest.raises(DeviceNotFound, match="neither a session folder nor a video"):
        open_source(f"replay:{DATA / 'v4l2_recorded' / 'device.json'}").open()


def test_depthai_frame_metadata_from_a_recording_warns_when_exposure_was_capped():
    device_id, frames = load_depthai_recording(DATA / "depthai_recorded")
    request = ExposureRequest(exposure_us=20000, iso=800)
    metas = [frame_meta(f, device_id, "depthai", request) for f in frames]
    assert metas[0]["exposure_us"] == pytest.approx(20000) and metas[0]["iso"] == 800
    assert metas[0]["lens_position"] == 130 and metas[0]["white_balance_k"] == 5200
    assert "warnings" not in metas[0]
    assert any("16600" in w for w in metas[2]["warnings"])


def test_depthai_without_a_device_says_what_to_check():
    with pytest.raises(DeviceNotFound, match="udev rule for vendor 03e7"):
        DepthAISource().open()


def test_capture_list_reports_no_cameras_clearly(capsys):
    from capture.discovery import list_cameras, none_found_message
    found = list_cameras()
    if found["v4l2"] or found["depthai"] or found["usb"]:
        pytest.skip("cameras attached: the empty case cannot be seen here")
    msg = none_found_message(found)
    assert "/dev/video" in msg and "03e7" in msg


def test_capture_list_json_lists_the_same_problems_as_the_text(capsys):
    from isu_validate.cli import main
    text_code = main(["capture", "list"])
    text = [line[2:] for line in capsys.readouterr().out.splitlines() if line.startswith("- ")]
    json_code = main(["capture", "list", "--json"])
    found = json.loads(capsys.readouterr().out)
    if found["v4l2"] or found["depthai"] or found["usb"]:
        pytest.skip("cameras attached: the empty case cannot be seen here")
    assert text_code == json_code == 1  # nothing found: the same exit status either way
    assert len(text) >= 3 and found["problems"] == text


@pytest.mark.hardware
def test_shoot_from_a_real_v4l2_camera(tmp_path):
    if not list(Path("/dev").glob("video*")):
        pytest.skip("no /dev/video* device attached")
    session = shoot(open_source("v4l2:0"), 2, tmp_path / "s", ExposureRequest(exposure_us=10000))
    assert len(session.frames) == 2


@pytest.mark.hardware
def test_shoot_from_a_real_oak(tmp_path):
    import depthai as dai
    if not dai.Device.getAllAvailableDevices():
        pytest.skip("no DepthAI device attached")
    session = shoot(open_source("depthai@640x480"), 2, tmp_path / "s", ExposureRequest(exposure_us=10000, iso=400))
    meta = json.loads(session.frames[0].with_suffix(".json").read_text())
    assert meta["exposure_us"] > 0 and meta["serial"]


def test_capture_commands_shoot_a_replayed_session_and_report_errors(tmp_path, capsys):
    from isu_validate.cli import main
    assert main(["capture", "shoot", "--source", f"replay:{DATA / 'v4l2_recorded'}", "--frames", "3",
                 "--out", str(tmp_path / "s"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["frames"]) == 3 and json.loads((tmp_path / "s" / "session.json").read_text())["status"] == "complete"
    assert main(["capture", "shoot", "--source", "v4l2:/dev/video99", "--frames", "1",
                 "--out", str(tmp_path / "t")]) == 2
    assert "/dev/video99 does not exist" in capsys.readouterr().err
    assert main(["capture", "list", "--json"]) in (0, 1)  # 1: no camera found
    assert set(json.loads(capsys.readouterr().out)) == {"v4l2", "depthai", "usb", "problems"}
