"""``PAIRS/review.html``: each pair's render and photos side by side, for annotators voting on validity.
A stand-in frame (a render taken for the photo) is captioned as one."""
from __future__ import annotations

from pathlib import Path

from ..analysis.html import esc, page, paragraph, section
from ..atomic import write_text
from ..pairs import PairsDir


def write_review(pairs: PairsDir) -> Path:
    parts = []
    for sample in pairs.samples():
        stand_ins = sample.provenance().stand_in
        images = [("render (sim.png)", sample.sim)] + [
            (f"stand-in render {f.name} (not a photo)" if f in stand_ins else f"photo {f.name}", f)
            for f in sample.real_frames()]
        figures = "".join(f'<figure><img src="{esc(path.relative_to(pairs.root))}" alt="{esc(name)}" '
                          f'style="width:420px"><figcaption>{esc(name)}</figcaption></figure>' for name, path in images)
        votes = (", ".join(f"{a}: {'same' if v else 'not the same'}" for a, v in sample.votes().items())
                 or "no votes yet")
        parts.append(section(sample.name, figures, paragraph(votes), anchor=sample.name))
    path = pairs.root / "review.html"
    intro = paragraph("Does each photo show the same scenario as the render (same people, objects, places, "
                      "light)? Vote with: isu-validate agree votes PAIRS --annotator NAME")
    write_text(path, page("Pairs to review", str(pairs.root), [section("How to vote", intro)] + parts))
    return path
