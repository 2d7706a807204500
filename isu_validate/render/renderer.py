"""The Blender renderer behind the ``Renderer`` protocol: validates a scene, looks it up in the cache,
asks the warm worker for the passes and the parts' unoccluded footprints, writes the outputs and the
label (per-feature visibility, frame checks), and survives a worker crash or hang (one restart and
retry, then RenderError)."""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, Mapping

from capture.camera import Camera, load_render_camera
from capture.camera_model.apply import apply as apply_imaging

from ..protocols import RenderError, RenderResult
from ..space import SceneSpace, load_space
from ..srgb import srgb_encode
from .cabin import cabin_hash, load_cabin
from .cache import RenderCache
from .camera import pinhole_plan
from .frame_check import frame_problem, frame_stats
from .gpu import FIRST_FRAME_COMPILE_S, device_identity, first_frame_compiles, resolve_render_device
from .object_axes import seat_objects_up
from .outputs import channel_paths, footprint_pixels, parse_channels, write_outputs
from .people import People, PeopleStore
from .people.store import code_version as people_version
from .presets import Preset, get_preset
from .visibility import feature_visibility, min_visible_for, needed_parts, part_shares
from .worker import BlenderWorker, WorkerCrashed, WorkerFailed, WorkerTimeout

# bump when the scene content or the outputs change: it is part of every cache key
# 2: driver_face part, footprints; 3: the phone, can and bottle lie on the co-driver seat; 4: anny people;
# 5: the camera frames tall drivers' heads, P8 by the door in view, light tree off; 6: people and things
# that read as real (issues 32, 33); 7: the phone gripped at P1-P10, upright at the ears, portrait when read;
# 8: short hair fuller on top with sideburns, brows darker than the hair, GREY hair darker; 9 (issues 32, 44): locks
# over the bob, a world outside the windows (HDRI by light and surroundings, the sun in HIGH light), a furnished
# cabin in car styles, garments and accessories
# 10 (issue 44): hands off the wheel without a phone (isu-diverse's driver_hands), the phone's screen dark in a
# call at the ear; later driver_hands DRINK (a can held to the mouth) and TEMPLE, new values that change no earlier
# scene's frame (so no bump: the people's code hash in every cache key re-poses them)
# 11 (issue 44): draft denoises with its guides unfiltered (OIDN prefilter NONE): faces at night no longer wash out
# 12 (issue 44): the view outside as bright as the light the windows let in (MEDIUM x4.8, HIGH x16), the sky seen
# by camera rays alone
# 13 (issue 44): the steering wheel leans as a real one does (the rim's top away from the driver, its face up to the
# chest; it leaned the other way), its centre moved so that the grips at ten and two stay where they were along the car
# (5 cm higher: the rim clears the knees); the belt rests on cloth the rays that lift it missed
# later (issue 44) driver_hands DRINK_LOW (a drink held below the chin) and `drink` (cups, a bottle, a mug besides the
# can): new values that change no earlier scene's frame, so no bump
# later (issue 44) driver_gaze (the head turned down to the hands, to the passenger or to the mirror): a new feature
# whose ROAD is every earlier scene's frame, so no bump
# later (issue 44) phone_case and phone_tip/roll/turn (the held phone's colour and angle in the hand): new features
# whose GRAPHITE and 0 are every earlier scene's frame, so no bump. With them the held phone is placed as the pose
# turned it: with the head turned and the phone at it (driver_gaze off the road, P1-P4 and P10) it kept the rig's
# angle while the hand closed round the turned one (up to 30 deg apart). That changes isu-diverse frames that
# driver_gaze added, never an isu-paper one; the people's code hash in every cache key renders them anew
# later (issue 44) seat_belt_colour (the webbing: black, grey, beige besides charcoal): a new feature whose CHARCOAL
# is every earlier scene's frame, so no bump
RENDERER_VERSION = "isu-blender-13"

# what the worker shows for a feature the scene space does not have (or that is inactive)
DEFAULTS = {"driver_gender": "MALE", "driver_emotion": "SERIOUS", "driver_height": "H2", "driver_weight": "W2",
            "phone_position": "NONE", "seat_belt": "YES", "tshirt_colour": "WHITE", "child_seat": "NO",
            "child": "NO", "child_seat_orientation": "FRONT_FACING", "car_lights": "OFF",
            "external_light": "MEDIUM", "luggage": "NO", "luggage_orientation": 60.0,
            "luggage_position": "BACK", "luggage_colour": "YELLOW", "phone_codriver_seat": "NO",
            "colacan_codriver_seat": "NO", "colabottle_codriver_seat": "NO",
            # the people's looks: not features of the paper's space (isu-paper renders these); isu-diverse varies them
            "driver_skin_tone": "MEDIUM", "driver_hair_colour": "BROWN", "driver_hair_style": "BY_GENDER",
            # the world outside and the car's style: likewise (rigs/cabins/default.toml [lighting.surroundings])
            "surroundings": "TOWN", "sun_direction": "FRONT", "cabin_trim": "GREY", "seat_material": "FABRIC",
            # what the driver wears beyond the T-shirt's colour (isu-diverse varies it; isu-paper: a plain T-shirt)
            "driver_top": "TSHIRT", "driver_top_print": "PLAIN", "driver_print_colour": "NAVY",
            "driver_jacket_colour": "BLACK", "driver_trousers_colour": "NAVY", "driver_eyewear": "NONE",
            "driver_cap": "NO", "driver_watch": "NO",
            # what the hands do besides holding a phone (isu-diverse varies it; isu-paper: both on the wheel)
            "driver_hands": "WHEEL", "drink": "CAN",
            # where the driver looks (isu-diverse varies it; isu-paper: the road)
            "driver_gaze": "ROAD",
            # the phone in the hand: lit while read, dark at the ear in a call (isu-diverse: also always on or off)
            "phone_screen": "BY_USE",
            # ... its case and the angle it is held at (isu-diverse varies them; isu-paper: graphite, the rig's angle)
            "phone_case": "GRAPHITE", "phone_tip": 0.0, "phone_roll": 0.0, "phone_turn": 0.0,
            # the seat belt's webbing (isu-diverse varies it; isu-paper: charcoal)
            "seat_belt_colour": "CHARCOAL"}


class BlenderRenderer:
    def __init__(self, preset: str | Preset = "draft", camera: str | os.PathLike | Camera = "default",
                 cabin: str | os.PathLike | dict = "default", channels=(), cache_dir=None, log_dir=None,
                 timeout_s: float = 240.0, space: SceneSpace | str | None = None, threads: int = 0,
                 extrinsics_from: str | os.PathLike | Camera | None = None, min_visible=None,
                 people_cache: str | os.PathLike | None = None, device: str | None = "auto"):
        self.preset = get_preset(preset, threads=threads) if isinstance(preset, str) else preset
        if device is not None:   # None keeps a Preset's own device (a pool's copy of a resolved one)
            self.preset = replace(self.preset, device=resolve_render_device(device))
        self.cabin = cabin if isinstance(cabin, dict) else load_cabin(cabin)
        self._look_through(load_render_camera(camera, extrinsics_from))   # refuses an unregistered pose
        self.channels = parse_channels(channels)
        self.space = space if isinstance(space, SceneSpace) else load_space(space or "isu-paper")
        self.parts = needed_parts(self.space)                        # whose footprints each frame needs
        self.min_visible = min_visible_for(self.space, min_visible)  # feature -> threshold
        self.cache = RenderCache(cache_dir) if cache_dir else None
        self.log_path = (Path(log_dir or Path(tempfile.gettempdir()) / "isu-validate-logs")
                         / f"blender-{os.getpid()}.log")
        self.timeout_s = timeout_s
        self._tmp = Path(tempfile.mkdtemp(prefix="isu-render-"))
        self._worker: BlenderWorker | None = None
        self._owner = os.getpid()
        self._count = 0
        self.unrendered = sorted(set(self.space.names) - set(DEFAULTS))
        self.people = People(self.cabin, PeopleStore(people_cache) if people_cache else None)
        self.show_people = True     # False renders the cabin without driver and child (bench render's people cost)
        self._identity = self._identity_hash()
        self._device_confirmed = False
        self._kernels_ready = self.preset.device == "cpu"   # a GPU's first frame may compile its kernels

    def _look_through(self, rig: Camera) -> None:
        """Render through ``rig`` from now on: its pinhole plan and the labels' `up` (fixed by the camera)."""
        self.rig = rig
        self.render_rig = rig.scaled(self.preset.scale)
        self.plan = pinhole_plan(self.render_rig)
        self.seat_up = seat_objects_up(self.cabin, self.render_rig)
        self.imaging = rig.imaging            # the camera's imaging model; None = linear light as sRGB

    def use_camera(self, camera: Camera) -> None:
        """Render the next scenes through ``camera`` (e.g. the rig jittered per scene, ``render/variety.py``):
        frames, labels and cache keys follow it. A camera whose pose was never registered is refused."""
        if camera is self.rig:
            return
        self._look_through(load_render_camera(camera))
        self._identity = self._identity_hash()

    def _identity_hash(self) -> str:
        settings = self.preset.to_worker()
        device = settings.pop("device")
        identity = [RENDERER_VERSION, people_version(), self.render_rig.hash, cabin_hash(self.cabin),
                    settings, self.preset.scale, self.channels, self.parts, *device_identity(device)]
        if self.imaging is not None:          # a camera without a model keeps its cache keys
            identity.append(self.imaging.hash)
        return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()

    # ------------------------------------------------------------------ protocol
    def render(self, scene: Mapping[str, Any], out: Path) -> RenderResult:
        """Render a valid scene to ``out`` (PNG) with its label: what each feature's parts show
        (``visibility``, ``occluded``). An invalid scene raises SpaceError (a ValueError) naming the
        problem before Blender sees it; a failed render, or a frame that cannot show the scene (black,
        saturated, no driver: written, then refused), raises RenderError."""
        t0 = time.perf_counter()
        out = Path(out)
        canonical = self.space.check(scene)
        developed: dict = {}
        paths, visible, parts, timings, cached, key = self._frame(canonical, out, developed)
        timings["total_s"] = time.perf_counter() - t0
        shares, occluded = feature_visibility(self.space, canonical, parts, self.min_visible)
        frame = frame_stats(out)
        problem = frame_problem(frame, visible, driver_expected=self.show_people)
        label = channel_paths(out)["label"]
        up = {name: u for name, u in self.seat_up.items() if name in visible}
        self._write_label(label, canonical, key, cached, timings, {
            "visible": visible, "parts": parts, "up": up, "frame": frame, "frame_problem": problem,
            "visibility": shares, "occluded": occluded, "min_visible": self.min_visible,
            **({"imaging": {"model": self.imaging.hash, "exposure": developed.get("exposure")}}
               if self.imaging is not None else {})})
        if problem:
            raise RenderError(f"unusable frame: {problem}", image=out)
        return RenderResult(out, {**paths, "label": label}, timings, cached=cached, visibility=shares,
                            occluded=occluded, up=up)

    def _frame(self, canonical: dict, out: Path, developed: dict):
        """(files by channel, visible instances, part shares, timings, cached, cache key): from the cache
        when it holds the scene, else rendered and put there (under the key of the device that renders it: a
        GPU that falls back to the CPU renders CPU pixels). ``developed`` receives what the camera's imaging
        model chose (exposure time, gain, metered level)."""
        t0 = time.perf_counter()
        key = self.cache_key(canonical)
        try:
            hit = self.cache.get(key, out, channel_paths(out)) if self.cache else None
        except OSError as exc:   # the output cannot be written (the cached files are intact)
            raise RenderError(f"could not write the render of this scene to {out}: {exc}") from exc
        if hit:
            timings = {"update_s": 0.0, "render_s": 0.0, "write_s": time.perf_counter() - t0}
            developed["exposure"] = hit["meta"].get("exposure")
            return hit["channels"], hit["meta"]["visible"], hit["meta"]["parts"], timings, True, key
        if self._confirm_device():   # the GPU is absent: the CPU's cache may hold the scene
            return self._frame(canonical, out, developed)
        paths, visible, footprints, timings = self._render_with_retry({**DEFAULTS, **canonical}, out, {},
                                                                      tag=key[:12], parts=self.parts,
                                                                      developed=developed)
        parts = part_shares(visible, footprints)
        if self.cache:
            self.cache.put(key, out, paths, {"scene": canonical, "visible": visible, "parts": parts,
                                             "timings": timings, "exposure": developed.get("exposure")})
        return paths, visible, parts, timings, False, key

    def close(self) -> None:
        if self._worker is not None and os.getpid() == self._owner:
            self._worker.close()
        self._worker = None
        shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------------ extras
    def render_extras(self, scene: Mapping[str, Any] | None, out: Path, extras: dict) -> RenderResult:
        """Render a scene (None: the empty cabin, no driver) with extras such as a board; never cached."""
        t0 = time.perf_counter()
        features = {**DEFAULTS, **(self.space.check(scene) if scene is not None else {})}
        if scene is None:
            extras = {"hide_driver": True, **extras}
        paths, _, _, timings = self._render_with_retry(features, Path(out), extras, tag="extras")
        timings["total_s"] = time.perf_counter() - t0
        return RenderResult(Path(out), paths, timings)

    def bounds(self, scene: Mapping[str, Any]) -> dict[str, tuple[list[float], list[float]]]:
        """Where the scene puts things, without rendering: each visible render instance's axis-aligned
        box (min, max corner) in the cabin frame, metres. For checking a rig's geometry."""
        features = {**DEFAULTS, **self.space.check(scene)}
        try:
            reply = self._ensure_worker().request({"op": "bounds", "features": features,
                                                   "people": self._people_for(features, {})}, self.timeout_s)
        except (WorkerCrashed, WorkerTimeout, WorkerFailed) as exc:
            raise RenderError(f"Blender could not place this scene: {exc} (log: {self.log_path})") from exc
        return {name: (box[0], box[1]) for name, box in reply["bounds"].items()}

    def cache_key(self, canonical: Mapping[str, Any]) -> str:
        people = "" if self.show_people else ":without-people"
        return hashlib.sha256(f"{self._identity}{people}:{self.space.key(canonical)}".encode()).hexdigest()

    @property
    def worker_pid(self) -> int | None:
        return self._worker.pid if self._worker else None

    # ------------------------------------------------------------------ internals
    def _ensure_worker(self) -> BlenderWorker:
        if os.getpid() != self._owner:   # a copy in a forked pool process: start its own worker
            self._worker, self._owner = None, os.getpid()
            self._tmp = Path(tempfile.mkdtemp(prefix="isu-render-"))
        if self._worker is None or not self._worker.alive:
            if self._worker is not None:
                self._worker.kill()
            self._worker = BlenderWorker(self.log_path)
            try:
                self._worker.start(self.cabin, timeout_s=max(self.timeout_s, 120.0))
            except (WorkerCrashed, WorkerTimeout, WorkerFailed) as exc:
                self._worker.kill()
                self._worker = None
                raise RenderError(f"could not start the Blender worker: {exc}") from exc
        return self._worker

    def _render_with_retry(self, features: dict, out: Path, extras: dict, tag: str, parts=(),
                           developed: dict | None = None):
        last = None
        for _attempt in (1, 2):
            try:
                return self._render_once(features, out, extras, tag, list(parts), developed)
            except (WorkerCrashed, WorkerTimeout) as exc:   # restart and retry once
                last = exc
                if self._worker is not None:
                    self._worker.kill()
                self._worker = None
            except WorkerFailed as exc:                      # a Python error in Blender: deterministic
                raise RenderError(f"Blender failed on this scene: {exc} (log: {self.log_path})") from exc
        raise RenderError(f"render failed twice (worker restarted in between): {last}")

    def _render_once(self, features: dict, out: Path, extras: dict, tag: str, parts: list[str],
                     developed: dict | None = None):
        t_people = time.perf_counter()
        people = self._people_for(features, extras)
        people_s = time.perf_counter() - t_people
        worker = self._ensure_worker()
        self._count += 1
        exr = self._tmp / f"frame-{self._count}.exr"
        masks = self._tmp / f"frame-{self._count}.parts.npy"
        camera = {**self.plan.blender_camera(), "f": self.plan.f, "cx": self.plan.cx, "cy": self.plan.cy,
                  "position": list(self.render_rig.position), "rotation": [list(r) for r in self.render_rig.rotation]}
        reply = worker.request({"op": "render", "features": features, "camera": camera, "extras": extras,
                                "people": people, "preset": self.preset.to_worker(), "exr": str(exr), "tag": tag,
                                "footprints": parts, "footprint_file": str(masks)}, self._frame_timeout())
        self._kernels_ready = True
        self._note_device(reply)
        t = time.perf_counter()
        try:
            paths, visible = write_outputs(exr, self.plan, out, self.channels,
                                           self._developer(tag, {} if developed is None else developed))
            footprints = footprint_pixels(masks, self.plan, parts) if parts else {}
        except (OSError, KeyError, ValueError) as exc:   # unreadable passes or an unwritable output
            raise RenderError(f"could not write the render of this scene to {out}: {exc}") from exc
        finally:
            exr.unlink(missing_ok=True)
            masks.unlink(missing_ok=True)
        timings = {"people_s": people_s, "update_s": reply["update_s"], "render_s": reply["render_s"],
                   "write_s": reply["save_s"] + time.perf_counter() - t, "worker_cpu_s": reply["cpu_s"]}
        if parts:
            timings["footprint_s"] = reply["footprint_s"]
        return paths, visible, footprints, timings

    def _frame_timeout(self) -> float:
        """The render request's limit: longer for a GPU's first frame while Cycles compiles its kernels."""
        if self._kernels_ready:
            return self.timeout_s
        note = first_frame_compiles(self.preset.device)
        if note is None:
            self._kernels_ready = True
            return self.timeout_s
        print(note, file=sys.stderr, flush=True)
        return max(self.timeout_s, FIRST_FRAME_COMPILE_S)

    def _confirm_device(self) -> bool:
        """Before the first GPU frame: ask the worker whether Blender has the device; True when it fell back."""
        if self.preset.device == "cpu" or self._device_confirmed:
            return False
        try:
            reply = self._ensure_worker().request({"op": "device", "device": self.preset.device}, self.timeout_s)
        except (WorkerCrashed, WorkerTimeout, WorkerFailed) as exc:
            raise RenderError(f"Blender could not select render device {self.preset.device}: {exc} "
                              f"(log: {self.log_path})") from exc
        self._device_confirmed = True
        return self._note_device(reply)

    def _note_device(self, reply: dict) -> bool:
        """The worker fell back to the CPU: say so once, and key frames as the CPU's from now on."""
        used = reply.get("device", self.preset.device)
        if used == self.preset.device:
            return False
        print(reply.get("device_note") or f"warning: Cycles renders on the {used}", file=sys.stderr, flush=True)
        self.preset = replace(self.preset, device=used)
        self._identity = self._identity_hash()
        return True

    def _people_for(self, features: dict, extras: dict) -> dict:
        """The host's posed driver and child files for the worker (None: absent)."""
        if not self.show_people:
            return {"driver": None, "child": None}
        return self.people.for_scene(features, with_driver=not extras.get("hide_driver"))

    def _developer(self, tag: str, developed: dict):
        """The post-render step: linear light through the camera's imaging model (or plain sRGB).
        Its noise is seeded by the scene's cache key, so a scene renders to the same frame every time."""
        if self.imaging is None:
            return srgb_encode

        def develop(rgb):
            seed = int(hashlib.sha256(tag.encode()).hexdigest()[:8], 16)
            image, exposure = apply_imaging(rgb, self.imaging, seed=seed)
            developed["exposure"] = exposure.to_dict() if exposure is not None else None
            return image
        return develop

    def _write_label(self, path: Path, canonical: dict, key: str, cached: bool, timings: dict, seen: dict):
        label = {"scene": canonical, "space": self.space.name, "preset": self.preset.name,
                 "render_device": self.preset.device,
                 "renderer": RENDERER_VERSION, "cache_key": key, "cached": cached,
                 "camera": self.render_rig.geometry(), "camera_source": self.rig.source,
                 "extrinsics_from": self.rig.pose_source or None,
                 "cabin": self.cabin.get("source"), **seen, "timings": timings}
        if self.unrendered:
            label["unrendered_features"] = self.unrendered
        path.write_text(json.dumps(label, indent=1))
