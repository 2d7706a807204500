"""Exterior and interior light: the world outside (a CC0 studio-light HDRI shipped in the bpy wheel, chosen
by the scene's external light and surroundings) seen through the windows, area lights in the window openings
(so the interior is lit with little noise at few samples), the sun in bright light, and the car's lamps."""
from __future__ import annotations

import math
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

from ..cabin import environment_for, environments
from ..labels import INSTANCE_ID
from . import mesh as M

WARM = (1.0, 0.78, 0.55)   # ~3000 K interior lamps
LAMP_SPREAD_DEG = 180.0    # the lamps shine down with a flush diffuser's cosine falloff (Cycles' area-light spread)
# where the sun shines in from, as its azimuth in the cabin frame (x forward, y to the driver's left)
SUN_AZIMUTH_DEG = {"FRONT": 0.0, "LEFT": 90.0, "BEHIND": 180.0, "RIGHT": -90.0}
SUN_ELEVATION_DEG = (12.0, 60.0)   # the HDRI's own sun height, kept within: grazing or overhead suns light nothing


def studio_light(name: str) -> Path:
    """A studio-light EXR shipped inside the bpy wheel (no download; CC0, see its license.txt)."""
    root = Path(bpy.utils.system_resource("DATAFILES")) / "studiolights" / "world"
    path = root / f"{name}.exr"
    if not path.is_file():
        names = sorted(p.stem for p in root.glob("*.exr"))
        raise ValueError(f"environment {name!r} is not a bundled studio light; use one of {', '.join(names)}")
    return path


class Sky:
    """One HDRI and what the lights take from it: a scale that brings its horizon to a common brightness
    (the rig's strengths mean the same for every image), the colour of its sky, and where its sun is."""

    def __init__(self, name: str):
        self.image = bpy.data.images.load(str(studio_light(name)), check_existing=True)
        w, h = self.image.size
        pixels = np.empty(w * h * 4, np.float32)
        self.image.pixels.foreach_get(pixels)
        rgb = pixels.reshape(h, w, 4)[::-1, :, :3]          # rows from the top (elevation +90 deg) down
        lum = rgb @ np.array([0.2126, 0.7152, 0.0722], np.float32)
        row, col = np.unravel_index(int(np.argmax(lum)), lum.shape)
        self.sun_elevation = math.radians(90.0 - 180.0 * (row + 0.5) / h)
        # Blender's equirectangular map: u = 0.5 - atan2(y, x) / 2pi in the dome's own frame
        self.sun_azimuth = math.pi * (1.0 - 2.0 * (col + 0.5) / w)
        band = slice(int(h * 0.33), int(h * 0.55))           # +30 .. -10 deg: what windows show
        clipped = np.minimum(lum[band], 8.0 * np.median(lum[band]))   # the sun's disc would dominate a mean
        self.horizon = float(clipped.mean())
        sky = rgb[: h // 2].reshape(-1, 3)
        sky = sky[lum[: h // 2].ravel() < 8.0 * np.median(lum[: h // 2])].mean(0)
        colour = sky / max(float(sky @ np.array([0.2126, 0.7152, 0.0722])), 1e-6)
        self.colour = tuple(float(c) for c in 0.5 + 0.5 * colour)   # half tinted: window light is mostly skylight


class Lighting:
    def __init__(self, rig: dict, scene, coll):
        self.rig, self.scene = rig, scene
        light = rig["lighting"]
        self.env_strength = light["environment_strength"]
        self.window_w = light["window_light_w"]
        self.lamp_w = light["interior_light_w"]
        self.sun_w = light.get("sun_strength", {})
        self.light = light
        self.skies = {name: Sky(name) for name in environments(light)}
        # the rig's strengths were set for the courtyard: every other sky is brought to its horizon's level
        self.reference = Sky("courtyard").horizon if "courtyard" not in self.skies else self.skies["courtyard"].horizon
        self._world(coll)
        self.windows = self._window_lights(rig["shell"], coll)
        self.sun = self._sun(coll)
        self.lamps, self.lamp_lens = self._interior_lamps(rig["anchors"], coll)
        self.state = self.on = None

    def _world(self, coll) -> None:
        """The exterior as a large self-lit dome carrying the HDRI, inside a black world.

        Why not the world itself: changing a world's strength makes Cycles rebuild the background
        (~1.5-2 CPU-seconds a frame here); changing a material's emission strength costs nothing."""
        world = bpy.data.worlds.new("black")
        world.use_nodes = True
        world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
        world.cycles.sampling_method = "NONE"
        self.scene.world = world
        mat = bpy.data.materials.new("exterior")
        mat.use_nodes = True
        nodes, links = mat.node_tree.nodes, mat.node_tree.links
        nodes.clear()
        coords, self.env = nodes.new("ShaderNodeTexCoord"), nodes.new("ShaderNodeTexEnvironment")
        self.background = nodes.new("ShaderNodeEmission")
        out = nodes.new("ShaderNodeOutputMaterial")
        links.new(coords.outputs["Object"], self.env.inputs["Vector"])   # direction from the dome's centre
        links.new(self.env.outputs["Color"], self.background.inputs["Color"])
        links.new(self.background.outputs["Emission"], out.inputs["Surface"])
        mat.cycles.emission_sampling = "NONE"   # seen by rays only: the window lights carry its light
        # the dome's centre at eye height, so the HDRI's horizon is level with the eyes as outdoors
        self.dome = M.new_object("exterior_dome", M.unit_sphere(48, 24), mat, coll, 0)
        self.dome.location = (0.0, 0.0, 1.1)
        self.dome.scale = (40.0, 40.0, 40.0)
        self.dome.visible_shadow = False
        # seen by camera rays (and through glass) only: as a light source its noise costs standard's SSIM floor
        # (0.9648 against 0.9708) and 13% more seconds, and the window lights already carry the sky's light in
        self.dome.visible_diffuse = self.dome.visible_glossy = False

    def _window_lights(self, s, coll):
        """One area light per opening, just outside it, facing in: sky light without path-tracing noise."""
        hw, roof, belt = s["half_width"], s["roof"], s["belt_line"]
        xr, xf = s["x_rear"], s["x_front"]
        specs = [  # (name, centre, size x, size y, direction the light faces)
            ("win_front", (xf - 0.2, 0, (s["dashboard_top"] + roof) / 2 + 0.05), 2 * hw, 0.6, (-1, 0, -0.5)),
            ("win_rear", (xr - 0.1, 0, (0.9 + roof) / 2), 2 * hw, 0.35, (1, 0, -0.3)),
            ("win_left", (-0.3, hw + 0.1, (belt + roof) / 2), 1.6, roof - belt, (0, -1, -0.35)),
            ("win_right", (-0.3, -hw - 0.1, (belt + roof) / 2), 1.6, roof - belt, (0, 1, -0.35)),
        ]
        lights = []
        for name, centre, sx, sy, facing in specs:
            data = bpy.data.lights.new(name, "AREA")
            data.shape, data.size, data.size_y = "RECTANGLE", sx, sy
            data.color = (0.95, 0.97, 1.0)
            obj = bpy.data.objects.new(name, data)
            obj.location = centre
            # an area light emits along its local -z
            obj.rotation_euler = (-Vector(facing)).to_track_quat("Z", "Y").to_euler()
            obj.visible_camera = obj.visible_glossy = False  # light the cabin, do not show as a panel
            coll.objects.link(obj)
            lights.append(obj)
        return lights

    def _sun(self, coll):
        """The sun of bright light: hard shadows of pillars, roof and people cast into the cabin."""
        data = bpy.data.lights.new("sun", "SUN")
        data.angle = math.radians(0.53)
        data.color = (1.0, 0.96, 0.9)
        obj = bpy.data.objects.new("sun", data)
        obj.hide_render = True
        coll.objects.link(obj)
        return obj

    def _interior_lamps(self, anchors, coll):
        lens_mat = M.material("lamp_lens", (0.8, 0.8, 0.78), roughness=0.3, emission=WARM, emission_strength=0.0)
        lamps, lenses = [], []
        for key in ("interior_light", "rear_light"):
            pos = Vector(anchors[key])
            # a lamp flush in the headliner shines down through its lens, not round: an area light facing
            # down whose light fades out towards LAMP_SPREAD_DEG lights the laps and seats below it more than
            # the faces beside it (a point light there washed the driver's face out at night: it is ~0.45 m
            # from the front lamp, facing it)
            data = bpy.data.lights.new(key, "AREA")
            data.shape, data.size, data.size_y = "RECTANGLE", 0.12, 0.20
            data.color, data.spread = WARM, math.radians(LAMP_SPREAD_DEG)
            obj = bpy.data.objects.new(key, data)
            obj.location = pos - Vector((0, 0, 0.012))   # just under the lens, facing down (its local -z)
            coll.objects.link(obj)
            lamps.append(obj)
            lenses.append(M.box(f"{key}_lens", pos, (0.14, 0.22, 0.02), lens_mat, coll,
                                INSTANCE_ID["interior_light"], rounded=0.3))
        return lamps, lens_mat

    def apply(self, external: str, car_lights: str, surroundings: str, sun_direction: str) -> None:
        state = (external, surroundings, sun_direction)
        if state != self.state:
            self._exterior(external, self.skies[environment_for(self.light, surroundings, external)], sun_direction)
            self.state = state
        on = car_lights == "ON"
        if on != self.on:
            for obj in self.lamps:
                obj.data.energy = self.lamp_w if on else 0.0
                obj.hide_render = not on  # a zero-energy light still costs light-tree time
            M.set_emission(self.lamp_lens, 6.0 if on else 0.0)
            self.on = on

    def _exterior(self, external: str, sky: Sky, sun_direction: str) -> None:
        """Show ``sky`` at the level's brightness, turned so that its sun stands where ``sun_direction``
        says; the window lights take its sky's colour, and in bright light the sun lamp shines from there."""
        self.env.image = sky.image
        self.background.inputs["Strength"].default_value = self.env_strength[external] * self.reference / sky.horizon
        azimuth = math.radians(SUN_AZIMUTH_DEG[sun_direction])
        self.dome.rotation_euler = (0.0, 0.0, azimuth - sky.sun_azimuth)
        for obj in self.windows:
            obj.data.energy = self.window_w[external] * obj.data.size * obj.data.size_y
            obj.data.color = sky.colour
        strength = float(self.sun_w.get(external, 0.0))
        self.sun.hide_render = strength <= 0.0   # no cost when it does not shine
        if strength > 0.0:
            elevation = min(max(sky.sun_elevation, math.radians(SUN_ELEVATION_DEG[0])),
                            math.radians(SUN_ELEVATION_DEG[1]))
            towards_sun = Vector((math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth),
                                  math.sin(elevation)))
            # a sun lamp shines along its local -z
            self.sun.rotation_euler = towards_sun.to_track_quat("Z", "Y").to_euler()
            self.sun.data.energy = strength

