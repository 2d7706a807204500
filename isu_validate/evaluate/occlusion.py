"""A scene whose every asked feature is occluded has nothing to judge (the issue-16 contract).

Such a scene gets no verdict, the SUT is not asked about it, and it is counted apart (the run records
it as an unusable frame: a render error), never as a failure. The pipeline asks ``nothing_to_judge``
before it asks the SUT; a judge called on such a scene anyway (``pins``, ``agree``) answers the same
``no_verdict``, so the two can never disagree."""
from __future__ import annotations

from typing import Any, Collection, Mapping

from ..protocols import Verdict
from ..space import SceneSpace


def nothing_to_judge(space: SceneSpace, scene: Mapping[str, Any], occluded: Collection[str]) -> str | None:
    """Why the frame of ``scene`` shows nothing the SUT would be asked about, or None when it shows something."""
    if not occluded:          # the common case: nothing hidden, no questions to work out
        return None
    asked = [q.key for q in space.questions(scene)]
    if asked and set(asked) <= set(occluded):
        return (f"unusable frame: every feature asked about is occluded ({', '.join(asked)}), so the scene has "
                f"no verdict; see the visible shares in the label (lower --min-visible to judge them anyway)")
    return None


def no_verdict(reason: str, **details: Any) -> Verdict:
    """The verdict of a scene with nothing to judge: no fitness measured, not a failure (like a SUT error,
    the search sees 1.0)."""
    return Verdict({}, 1.0, False, {**details, "no_verdict": reason})
