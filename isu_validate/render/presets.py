"""Render presets: speed against error. Measured with ``isu-validate bench render`` (see the issue)."""
from __future__ import annotations

from dataclasses import asdict, dataclass, replace

from ..errors import InputError


@dataclass(frozen=True)
class Preset:
    name: str
    scale: float            # resolution relative to the camera rig's image
    samples: int            # Cycles samples per pixel (fixed; adaptive sampling gave nothing here)
    denoise: bool           # OpenImageDenoise
    prefilter: str          # OIDN prefilter of albedo/normal guides: NONE, FAST, ACCURATE
    max_bounces: int
    diffuse_bounces: int
    glossy_bounces: int
    clamp_indirect: float   # firefly clamp (0 = off)
    filter_width: float     # pixel filter (px)
    threads: int = 0        # 0 = all cores
    device: str = "cpu"     # Cycles' compute device: cpu or a GPU type (render/gpu.py resolves auto)

    def to_worker(self) -> dict:
        d = asdict(self)
        d.pop("name")
        d.pop("scale")
        return d


# Measured on the 2-core machine with `isu-validate bench render` and in-process timings (render/README.md):
# at 640x480 path tracing costs 1.25 CPU-s (0.62 s) a sample with the people, OpenImageDenoise HIGH 1.57
# CPU-s (0.80 s; its FAST quality 0.83 CPU-s but standard's SSIM drops to 0.9695), so presets trade samples
# and resolution. OIDN with albedo/normal guides makes 1-2 samples usable; extra bounces beyond 2 changed
# SSIM by < 0.001 here.
PRESETS = {
    # draft's guides unfiltered (prefilter NONE) since isu-blender-11: at 1 spp the albedo and normal passes are
    # already clean, and FAST's joint filtering of them smeared a 64 px face's eyes and brows. Same 72 scenes
    # (isu-paper, seed 5151): faces found 90 -> 99 % (lamps on at night 77 -> 92 %), HAPPY read happy 53 -> 60 %,
    # phone top-5 54 -> 62 %; SSIM 0.898 -> 0.899; 1.33x the worker CPU-s (OIDN's HIGH network for clean guides
    # is larger). NONE with OIDN's BALANCED or FAST quality cost 1.0x / 0.9x and also found the faces, but read the
    # phone worse than before (42 %, 40 %) (render/README.md, "Draft faces at night")
    "draft": Preset("draft", 0.5, 1, True, "NONE", 2, 1, 1, 3.0, 1.5),
    # 3 samples since isu-blender-6: the auto-exposing camera gains night frames up to 16x, and at 2 samples
    # those fell to SSIM 0.972 and the mean of lit and night frames to 0.967 (3 samples: 0.9706, 1.42x the
    # seconds of isu-blender-5's standard; render/README.md)
    "standard": Preset("standard", 1.0, 3, True, "FAST", 2, 1, 1, 5.0, 1.5),
    "final": Preset("final", 1.0, 16, True, "ACCURATE", 4, 3, 2, 10.0, 1.5),
    # calibration targets (render_board): no denoiser, whose edge artefacts move ChArUco corners by
    # ~0.3 px at 2 spp; 64 plain samples give 0.08 px RMS corner error against the rig's projection
    "calibration": Preset("calibration", 1.0, 64, False, "NONE", 1, 1, 0, 3.0, 1.5),
    # the converged reference of `bench render` (not meant for runs)
    "reference": Preset("reference", 1.0, 512, True, "ACCURATE", 8, 4, 4, 0.0, 1.5),
}


# the least mean SSIM against the converged reference that `bench render` must show for a preset (its own
# default scenes or `--scenes 8 --seed 1`): standard's was 0.97 until the bob's locks (issue 32's decision:
# their loss is coverage noise on lock edges, not shading), 0.969 since `isu-blender-9`
SSIM_FLOORS = {"standard": 0.969}


def get_preset(name: str, **overrides) -> Preset:
    if name not in PRESETS:
        raise InputError(f"unknown render preset {name!r}; presets: {', '.join(PRESETS)}")
    return replace(PRESETS[name], **overrides) if overrides else PRESETS[name]
