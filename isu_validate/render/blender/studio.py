"""The Blender scene a worker holds: cabin, lights, driver and objects built once from the cabin rig;
each render applies only what changed, sets camera and render settings, renders, and writes the
passes (colour, depth, object index) to one uncompressed multilayer EXR for the host to read."""
from __future__ import annotations

import math
import time
from pathlib import Path

import bpy
from mathutils import Matrix, Vector

from ..labels import INSTANCE_ID
from .cabin import build_cabin
from .device import select_device
from .lighting import Lighting
from .objects import Group, Objects
from .people import Child, Driver

_CV_TO_BLENDER = Matrix(((1, 0, 0), (0, -1, 0), (0, 0, -1)))  # OpenCV camera axes -> Blender camera axes


class Studio:
    def __init__(self, rig: dict):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        self.scene = bpy.context.scene
        self.rig = rig
        coll = self.scene.collection
        self.coll = coll
        self.parts, self.style = build_cabin(rig, coll)
        self.lighting = Lighting(rig, self.scene, coll)
        self.driver = Driver(rig, coll, self.parts["driver_seat"] + [bpy.data.objects["belt_buckle"]])
        self.child = Child(coll)
        self.objects = Objects(rig, coll, importer=self._import_part)
        self._replace_fixed_parts()
        self.camera = self._camera()
        self._passes()
        self.board: Group | None = None
        self.preset_key = None
        self.device, self.device_note = "cpu", None   # what set_preset chose, and why not the asked one

    # ------------------------------------------------------------------ setup
    def _camera(self):
        cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
        self.coll.objects.link(cam)
        self.scene.camera = cam
        cam.data.sensor_fit = "HORIZONTAL"
        cam.data.clip_start, cam.data.clip_end = 0.02, 200.0
        return cam

    def _passes(self) -> None:
        layer = self.scene.view_layers[0]
        layer.use_pass_z = True
        layer.use_pass_object_index = True
        settings = self.scene.render.image_settings
        settings.media_type = "MULTI_LAYER_IMAGE"
        settings.file_format = "OPEN_EXR_MULTILAYER"
        settings.color_depth = "32"
        settings.exr_codec = "NONE"
        # colour stays scene-linear in the EXR; the host applies the sRGB transfer (view transform Standard)
        self.scene.view_settings.view_transform = "Standard"

    def set_preset(self, p: dict) -> None:
        key = tuple(sorted(p.items()))
        if key == self.preset_key:
            return
        r, c = self.scene.render, self.scene.cycles
        r.engine = "CYCLES"
        self.device, self.device_note = select_device(self.scene, p.get("device", "cpu"))
        c.samples = p["samples"]
        c.use_adaptive_sampling = False
        c.use_denoising = p["denoise"]
        c.denoiser = "OPENIMAGEDENOISE"
        c.denoising_prefilter = p["prefilter"]
        c.denoising_input_passes = "RGB_ALBEDO_NORMAL"
        c.max_bounces, c.diffuse_bounces, c.glossy_bounces = p["max_bounces"], p["diffuse_bounces"], p["glossy_bounces"]
        # see-through is a Transparent BSDF mix (blender/materials.py): a ray through a bottle crosses two
        # walls, and Cycles shades nothing past the last allowed transparent hit (black), so 4, not 2
        c.transmission_bounces, c.transparent_max_bounces, c.volume_bounces = 0, 4, 0
        c.caustics_reflective = c.caustics_refractive = False
        # six lights (four window areas, two lamps): the light tree's traversal cost more than it saved,
        # 12-17% of the path-tracing CPU at 2 spp 640x480 for an SSIM 0.0003 higher without it (bench render)
        c.use_light_tree = False
        c.sample_clamp_indirect = p["clamp_indirect"]
        c.filter_width = p["filter_width"]
        c.use_auto_tile = False
        c.seed = 0
        r.use_persistent_data = True          # keep the BVH and shaders of unchanged objects between frames
        r.resolution_percentage = 100
        if p.get("threads"):
            r.threads_mode, r.threads = "FIXED", int(p["threads"])
        self.preset_key = key

    def set_camera(self, cam: dict) -> None:
        r, data = self.scene.render, self.camera.data
        r.resolution_x, r.resolution_y = cam["width"], cam["height"]
        r.pixel_aspect_x = r.pixel_aspect_y = 1.0
        data.sensor_width, data.lens = cam["sensor_width"], cam["lens"]
        data.shift_x, data.shift_y = cam["shift_x"], cam["shift_y"]
        R = Matrix(cam["rotation"]) @ _CV_TO_BLENDER
        self.camera.matrix_world = Matrix.Translation(Vector(cam["position"])) @ R.to_4x4()

    # ------------------------------------------------------------------ assets
    def _import_part(self, part: str) -> Group | None:
        spec = self.rig.get("assets", {}).get(part)
        if not spec:
            return None
        before = set(bpy.data.objects)
        path = spec["file"]
        suffix = Path(path).suffix.lower()
        if suffix in (".glb", ".gltf"):
            bpy.ops.import_scene.gltf(filepath=path)
        elif suffix == ".obj":
            bpy.ops.wm.obj_import(filepath=path)
        else:
            bpy.ops.import_scene.fbx(filepath=path)
        group = Group(f"asset_{part}", self.coll)
        group.asset = True
        # the rig's location/rotation/scale sit on an inner empty: the group's root stays free for
        # placing a movable part (luggage, phone...) at its anchor
        inner = bpy.data.objects.new(f"asset_{part}_transform", None)
        self.coll.objects.link(inner)
        inner.parent = group.root
        inner.location = spec.get("location", (0, 0, 0))
        inner.rotation_euler = [math.radians(a) for a in spec.get("rotation_deg", (0, 0, 0))]
        scale = spec.get("scale", 1.0)
        inner.scale = scale if isinstance(scale, list) else [scale] * 3
        pid = INSTANCE_ID.get(part, INSTANCE_ID["cabin"])
        if part in ("driver_seat", "passenger_seat", "rear_bench"):
            pid = INSTANCE_ID[part]
        for obj in set(bpy.data.objects) - before:
            if obj.parent is None:
                obj.parent = inner
            obj.pass_index = pid
            group.parts.append(obj)
        return group

    def _replace_fixed_parts(self) -> None:
        """Fixed parts named in [assets] replace their procedural builds (which are hidden, not removed,
        so seat anchors keep working)."""
        for part in ("cabin", "driver_seat", "passenger_seat", "rear_bench", "steering_wheel"):
            if part in self.rig.get("assets", {}):
                self._import_part(part)
                for obj in self.parts.get(part, []):
                    obj.hide_render = True

    # ------------------------------------------------------------------ per scene
    def apply(self, features: dict, extras: dict, people: dict) -> None:
        """``people``: the host's topology and state files of the driver and the child (None: absent)."""
        self.lighting.apply(features["external_light"], features["car_lights"], features["surroundings"],
                            features["sun_direction"])
        self.style.apply(features["cabin_trim"], features["seat_material"])
        if people.get("driver") is None:
            self.driver.hide()
        else:
            self.driver.apply(features, people["driver"])
        self.child.apply(people.get("child"), features)
        self.objects.apply(features, self.driver.hand_pose(), self.driver.can_pose())
        self._board(extras.get("board"))

    def _board(self, spec: dict | None) -> None:
        if spec is None:
            if self.board:
                self.board.show(False)
            return
        if self.board is None or self.board.root.get("image") != spec["image"] or \
                tuple(self.board.root.get("size", ())) != tuple(spec["size_m"]):
            self.board = _build_board(spec, self.coll)
        self.board.root.matrix_world = Matrix.Translation(Vector(spec["position"])) @ Matrix(spec["rotation"]).to_4x4()
        self.board.show(True)

    def bounds(self) -> dict[str, list[list[float]]]:
        """World-space axis-aligned box [min, max] of every render instance that shows (cabin frame,
        metres): lets the host check where things stand without rendering."""
        bpy.context.view_layer.update()
        names = {i: name for name, i in INSTANCE_ID.items()}
        boxes: dict[str, list[list[float]]] = {}
        for obj in self.scene.objects:
            if obj.type != "MESH" or obj.hide_render or obj.pass_index not in names:
                continue
            corners = [obj.matrix_world @ Vector(c) for c in obj.bound_box]
            lo = [min(c[k] for c in corners) for k in range(3)]
            hi = [max(c[k] for c in corners) for k in range(3)]
            box = boxes.setdefault(names[obj.pass_index], [lo, hi])
            box[0] = [min(a, b) for a, b in zip(box[0], lo)]
            box[1] = [max(a, b) for a, b in zip(box[1], hi)]
        return boxes

    def render(self, exr_path: str) -> dict:
        t0 = time.perf_counter()
        bpy.ops.render.render(write_still=False)
        t1 = time.perf_counter()
        bpy.data.images["Render Result"].save_render(exr_path, scene=self.scene)
        return {"render_s": t1 - t0, "save_s": time.perf_counter() - t1}


def _build_board(spec: dict, coll) -> Group:
    """A flat board (calibration target) spanning [0, w] x [0, h] in its own frame: x along the
    image's columns, y along its rows (down), z = x cross y (into the board), OpenCV-style. It is
    self-lit (emission) so its pixels equal the image regardless of the cabin's light."""
    w, h = spec["size_m"]
    mesh = bpy.data.meshes.new("board")
    mesh.from_pydata([(0, 0, 0), (w, 0, 0), (w, h, 0), (0, h, 0)], [], [(0, 1, 2, 3)])
    uv = mesh.uv_layers.new(name="UVMap")
    for loop, co in zip(uv.data, ((0, 1), (1, 1), (1, 0), (0, 0))):
        loop.uv = co
    mat = bpy.data.materials.new("board")
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = bpy.data.images.load(spec["image"], check_existing=True)
    tex.interpolation = "Cubic"
    emit, out = nodes.new("ShaderNodeEmission"), nodes.new("ShaderNodeOutputMaterial")
    links.new(tex.outputs["Color"], emit.inputs["Color"])
    links.new(emit.outputs["Emission"], out.inputs["Surface"])
    mesh.materials.append(mat)
    group = Group("board", coll)
    obj = bpy.data.objects.new("board", mesh)
    obj.pass_index = INSTANCE_ID["board"]
    coll.objects.link(obj)
    group.add(obj)
    group.root["image"], group.root["size"] = spec["image"], list(spec["size_m"])
    return group
