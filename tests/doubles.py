"""Test doubles for the pipeline: a renderer that paints the scene hash, a deterministic
SUT that is wrong in known places, and a weighted exact-match judge.  Used through
``--pipeline-factory tests.doubles:build`` so runs exercise the real search loop.
With ``--sut command:...`` or ``--sut http:...`` the real SUT adapter answers instead of
the double (real processes and real HTTP, with no Blender in the way)."""
from __future__ import annotations

import hashlib
import os
import time
from pathlib import Path

import numpy as np

from isu_validate.pipeline import Components
from isu_validate.protocols import RenderError, RenderResult, SUTRequest, SUTResponse, Verdict


# every PaintRenderer closed in this process (a run must close what its workers opened)
CLOSED: list["PaintRenderer"] = []


class PaintRenderer:
    def __init__(self, space):
        self.space = space
        self.calls = 0

    def close(self) -> None:
        CLOSED.append(self)

    def render(self, scene, out: Path) -> RenderResult:
        import cv2

        self.calls += 1
        if os.environ.get("ISU_TEST_FAIL_RENDER_WITH_CAN") and scene.get("colacan_codriver_seat") == "YES":
            raise RenderError("Blender failed on this scene (test double)")
        digest = hashlib.sha1(self.space.key(scene).encode()).digest()
        img = np.zeros((24, 32, 3), np.uint8) + np.frombuffer(digest[:3], np.uint8)
        cv2.imwrite(str(out), img)
        # tests slow the renderer down to kill a run mid-generation
        time.sleep(float(os.environ.get("ISU_TEST_RENDER_DELAY", "0")))
        visibility, occluded = self._visibility(scene)
        return RenderResult(image=Path(out), timings={"update_s": 0.0, "render_s": 0.001},
                            visibility=visibility, occluded=occluded)

    def _visibility(self, scene):
        """With ISU_TEST_OCCLUDE set, a suitcase is hidden behind a child seat (share 0.05), else seen whole;
        ISU_TEST_OCCLUDE=all hides everything asked about."""
        if os.environ.get("ISU_TEST_OCCLUDE") == "all":
            keys = [q.key for q in self.space.questions(scene)]
            return {k: 0.0 for k in keys}, keys
        if scene.get("luggage") != "YES":
            return {}, []
        hidden = bool(os.environ.get("ISU_TEST_OCCLUDE")) and scene.get("child_seat") == "YES"
        keys = [k for k in ("luggage", "luggage_position", "luggage_colour") if k in self.space.canonical(scene)]
        return {k: 0.05 if hidden else 1.0 for k in keys}, keys if hidden else []


class BlindSUT:
    """Answers from the label file, wrong about seat belts in low light and about luggage on the passenger seat."""
    id = "blind-double"

    def __init__(self, space):
        self.space = space

    def query(self, request: SUTRequest) -> SUTResponse:
        import json

        label = json.loads((Path(request.image).parent.parent / "labels"
                            / (Path(request.image).stem + ".json")).read_text())
        scene = label["scene"]
        if os.environ.get("ISU_TEST_SUT_ERROR_WITH_BOTTLE") and scene.get("colabottle_codriver_seat") == "YES":
            return SUTResponse(raw="<html>502 Bad Gateway</html>", error="HTTP 502 from the SUT (test double)")
        answers = {q.key: q.truth for q in request.questions}
        if scene.get("external_light") == "LOW" and "seat_belt" in answers:
            answers["seat_belt"] = "NO" if answers["seat_belt"] == "YES" else "YES"
        if "luggage_position" in answers:
            answers["luggage_position"] = "BACK"
        time.sleep(float(os.environ.get("ISU_TEST_SUT_DELAY", "0")))  # tests check the SUT timing with it
        return SUTResponse(raw=repr(answers), answers=answers)


class ExactMatchJudge:
    def __init__(self, threshold):
        self.threshold = 1.0 if threshold is None else threshold

    def judge(self, scene, request, response, occluded=()) -> Verdict:
        if response.error:
            return Verdict({}, 1.0, False, {"sut_error": response.error})
        asked = [q for q in request.questions if q.key not in occluded]
        total = sum(q.weight for q in asked) or 1.0
        score = sum(q.weight for q in asked if (response.answers or {}).get(q.key) == q.truth) / total
        return Verdict({"f_qa": score}, score, score < self.threshold)


def build_request(space, scene, image, mode, prompt):
    return SUTRequest(mode=mode, image=Path(image), prompt=prompt or "", questions=space.questions(scene))


def build(config, space) -> Components:
    if config.sut.startswith(("command:", "http:")):
        from isu_validate.sut import open_sut
        sut = open_sut(config.sut, space=space, repeats=config.repeats, timeout_s=config.sut_timeout_s,
                       **config.sut_options)
    else:
        sut = BlindSUT(space)
    return Components(PaintRenderer(space), sut, ExactMatchJudge(config.threshold), build_request)
