"""Meshes the Blender worker builds, checked in real Blender (bpy in a subprocess): a surface of
revolution through points on its axis is closed, with no coincident vertices and no zero-area faces
(a pole is one vertex, not a ring of them): the bottle, every drink a hand holds and the parts they are built of."""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

pytestmark = pytest.mark.blender

_LATHE = """
import json, bpy, bmesh
from isu_validate.render.blender import mesh as M
from isu_validate.render.blender.objects import _BOTTLE, DRINKS, _band, _split_profile
from isu_validate.render.cabin_geometry import DRINK_PROFILES
profiles = [("bottle", _BOTTLE), ("tube", [(0.02, 0.0), (0.02, 0.1)])]
profiles += [(kind.lower(), list(profile)) for kind, profile in DRINK_PROFILES.items()]
for kind, drink in DRINKS.items():     # the drinks as built: body and lid apart, the sleeve or label
    if drink.lid is not None:
        below, above = _split_profile(list(DRINK_PROFILES[drink.shape]), drink.lid_from)
        profiles += [(kind + "_body", below), (kind + "_lid", above)]
    if drink.band is not None:
        profiles.append((kind + "_band", _band(DRINK_PROFILES[drink.shape], *drink.band[0], 0.0008)))
out = {}
for name, profile in profiles:
    me = M.lathe("test_" + name, profile, 16)
    bm = bmesh.new()
    bm.from_mesh(me)
    positions = {tuple(round(c, 7) for c in v.co) for v in bm.verts}
    out[name] = {"verts": len(bm.verts), "distinct": len(positions),
                 "min_area": min(f.calc_area() for f in bm.faces),
                 "open_edges": sum(1 for e in bm.edges if len(e.link_faces) != 2)}
print("RESULT " + json.dumps(out))
"""


def test_a_lathe_through_its_axis_is_closed_without_degenerate_faces():
    proc = subprocess.run([sys.executable, "-c", _LATHE], capture_output=True, text=True, timeout=300)
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    assert proc.returncode == 0 and line, proc.stderr[-2000:]
    for name, m in json.loads(line[0][len("RESULT "):]).items():
        assert m["verts"] == m["distinct"], (name, m)           # no ring of vertices on one point
        assert m["min_area"] > 1e-9, (name, m)
        assert m["open_edges"] == 0, (name, m)                  # closed: caps at both ends
