"""Exterior and interior light: an HDRI environment seen through the open windows, area lights in the
window openings (so the interior is lit with little noise at few samples), and the car's interior lamps."""
from __future__ import annotations

from pathlib import Path

import bpy
from mathutils import Vector

from ..labels import INSTANCE_ID
from . import mesh as M

WARM = (1.0, 0.78, 0.55)   # ~3000 K interior lamps


def studio_light(name: str) -> Path:
    """A studio-light EXR shipped inside the bpy wheel (no download)."""
    root = Path(bpy.utils.system_resource("DATAFILES")) / "studiolights" / "world"
    path = root / f"{name}.exr"
    if not path.is_file():
        names = sorted(p.stem for p in root.glob("*.exr"))
        raise ValueError(f"environment {name!r} is not a bundled studio light; use one of {', '.join(names)}")
    return path


class Lighting:
    def __init__(self, rig: dict, scene, coll):
        self.rig, self.scene = rig, scene
        light = rig["lighting"]
        self.env_strength = light["environment_strength"]
        self.window_w = light["window_light_w"]
        self.lamp_w = light["interior_light_w"]
        self._world(studio_light(light["environment"]), coll)
        self.windows = self._window_lights(rig["shell"], coll)
        self.lamps, self.lamp_lens = self._interior_lamps(rig["anchors"], coll)
        self.level = self.on = None

    def _world(self, hdri: Path, coll) -> None:
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
        coords, env = nodes.new("ShaderNodeTexCoord"), nodes.new("ShaderNodeTexEnvironment")
        env.image = bpy.data.images.load(str(hdri), check_existing=True)
        self.background = nodes.new("ShaderNodeEmission")
        out = nodes.new("ShaderNodeOutputMaterial")
        links.new(coords.outputs["Object"], env.inputs["Vector"])   # direction from the dome's centre
        links.new(env.outputs["Color"], self.background.inputs["Color"])
        links.new(self.background.outputs["Emission"], out.inputs["Surface"])
        mat.cycles.emission_sampling = "NONE"   # seen by rays only: the window lights carry its light
        dome = M.new_object("exterior_dome", M.unit_sphere(48, 24), mat, coll, 0)
        dome.scale = (40.0, 40.0, 40.0)
        dome.visible_shadow = False

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

    def _interior_lamps(self, anchors, coll):
        lens_mat = M.material("lamp_lens", (0.8, 0.8, 0.78), roughness=0.3, emission=WARM, emission_strength=0.0)
        lamps, lenses = [], []
        for key in ("interior_light", "rear_light"):
            pos = Vector(anchors[key])
            data = bpy.data.lights.new(key, "POINT")
            data.color, data.shadow_soft_size = WARM, 0.06
            obj = bpy.data.objects.new(key, data)
            obj.location = pos - Vector((0, 0, 0.05))
            coll.objects.link(obj)
            lamps.append(obj)
            lenses.append(M.box(f"{key}_lens", pos, (0.14, 0.22, 0.02), lens_mat, coll,
                                INSTANCE_ID["interior_light"], rounded=0.3))
        return lamps, lens_mat

    def apply(self, external: str, car_lights: str) -> None:
        if external != self.level:
            self.background.inputs["Strength"].default_value = self.env_strength[external]
            for obj in self.windows:
                obj.data.energy = self.window_w[external] * obj.data.size * obj.data.size_y
            self.level = external
        on = car_lights == "ON"
        if on != self.on:
            for obj in self.lamps:
                obj.data.energy = self.lamp_w if on else 0.0
                obj.hide_render = not on  # a zero-energy light still costs light-tree time
            M.set_emission(self.lamp_lens, 6.0 if on else 0.0)
            self.on = on
