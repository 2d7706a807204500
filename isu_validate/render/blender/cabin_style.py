"""The car's style (isu-diverse's unasked `cabin_trim` and `seat_material`): the colours of the cabin's
plastics, trims, headliner, carpet and seats, and fabric or leather seat covers. Each material is built once;
a scene sets its colour and the covers' leather share as node values, so a new style rebuilds nothing."""
from __future__ import annotations

from . import materials
from . import mesh as M

# linear-RGB colours per trim: a dark dashboard top in every car (glare), the rest in the trim's tone
TRIMS = {
    "BLACK": {"plastic": (0.016, 0.016, 0.018), "dash": (0.014, 0.014, 0.016), "trim": (0.026, 0.026, 0.028),
              "insert": (0.036, 0.036, 0.037), "headliner": (0.10, 0.098, 0.095), "carpet": (0.012, 0.012, 0.012),
              "seat": (0.028, 0.028, 0.029)},
    "GREY": {"plastic": (0.025, 0.025, 0.028), "dash": (0.022, 0.022, 0.025), "trim": (0.06, 0.058, 0.055),
             "insert": (0.09, 0.087, 0.083), "headliner": (0.32, 0.31, 0.29), "carpet": (0.02, 0.02, 0.02),
             "seat": (0.12, 0.115, 0.11)},
    "BEIGE": {"plastic": (0.15, 0.118, 0.082), "dash": (0.03, 0.025, 0.02), "trim": (0.28, 0.22, 0.15),
              "insert": (0.34, 0.27, 0.19), "headliner": (0.48, 0.42, 0.33), "carpet": (0.05, 0.04, 0.03),
              "seat": (0.32, 0.245, 0.16)},
}
# what each surface role is made of: (roughness, specular)
ROLES = {"plastic": (0.55, 0.5), "dash": (0.7, 0.35), "trim": (0.7, 0.5), "insert": (0.95, 0.15),
         "headliner": (0.9, 0.2), "carpet": (1.0, 0.1)}
SEAT_MATERIALS = {"FABRIC": 0.0, "LEATHER": 1.0}


class CabinStyle:
    """The style materials: ``self[role]`` for the builders, ``apply(trim, seat_material)`` per scene."""

    def __init__(self):
        grey = TRIMS["GREY"]
        self.materials = {role: M.material(role, grey[role], roughness=r, specular=s) for role, (r, s) in ROLES.items()}
        self.covers = [materials.seat_cover("seat_cover", grey["seat"]),
                       materials.seat_cover("headrest_cover", grey["seat"], quilted=False)]
        self.state = None

    def __getitem__(self, role: str):
        return self.materials[role]

    def apply(self, trim: str, seat_material: str) -> None:
        if (trim, seat_material) == self.state:
            return
        colours = TRIMS[trim]
        for role, mat in self.materials.items():
            M.set_colour(mat, colours[role])
        for cover in self.covers:
            materials.set_cover(cover, colours["seat"], SEAT_MATERIALS[seat_material])
        self.state = (trim, seat_material)
