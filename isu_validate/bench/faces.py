"""``isu-validate bench faces``: can a SUT read the driver's emotion at a preset's resolution?

Renders seeded drivers twice, HAPPY and SERIOUS (everything else equal), at each preset, and measures
on the ``driver_face`` instance of the segmentation: how wide the face is in pixels, how much the two
expressions differ there (mean absolute difference of 8-bit luma, share of face pixels changing by
more than 12 levels), and writes side-by-side face crops to look at. The reference ISU's emotion
accuracy per preset (MODEL_CARD.md) is the other half of the answer."""
from __future__ import annotations

import json
import statistics
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:   # numpy, OpenCV and the render labels load when the bench runs, not for its --help
    import numpy as np

CHANGED = 12   # luma levels: a visible change


def register_bench(sub) -> None:
    p = sub.add_parser("faces", help="driver's face: size in pixels and HAPPY/SERIOUS difference per preset")
    p.add_argument("--presets", default="draft,standard", help="comma list (default draft,standard)")
    p.add_argument("--drivers", type=int, default=6, help="seeded random drivers (default 6)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--rig", default="default")
    p.add_argument("--out", type=Path, default=Path("runs/bench-faces"), help="folder for frames, crops and faces.json")
    p.set_defaults(func=run)


def run(args) -> int:
    import cv2
    import numpy as np

    from isu_validate.space import load_space
    from isu_validate.render import open_renderer

    space = load_space()
    rng = np.random.default_rng(args.seed)
    drivers = []
    for scene in space.sample(rng, args.drivers):
        scene.update(phone_position="NONE", external_light="MEDIUM", car_lights="OFF")
        drivers.append(space.repair(scene, rng))
    args.out.mkdir(parents=True, exist_ok=True)
    rows = []
    for preset in [p.strip() for p in args.presets.split(",") if p.strip()]:
        measures, crops = [], []
        with open_renderer(preset, args.rig, channels=("seg",), log_dir=args.out / "logs") as r:
            for i, scene in enumerate(drivers):
                frames = {}
                for emotion in ("HAPPY", "SERIOUS"):
                    out = args.out / f"{preset}-{i}-{emotion.lower()}.png"
                    result = r.render({**scene, "driver_emotion": emotion}, out)
                    frames[emotion] = (cv2.imread(str(out)),
                                       cv2.imread(str(result.channels["seg"]), cv2.IMREAD_UNCHANGED))
                m, crop = face_difference(frames["HAPPY"], frames["SERIOUS"])
                measures.append(m)
                crops.append(crop)
        row = {"preset": preset, "drivers": len(drivers),
               **{k: statistics.median([m[k] for m in measures]) for k in measures[0]}}
        rows.append(row)
        _save_crops(crops, args.out / f"faces-{preset}.png")
        print(f"{preset:>9}  face width {row['face_width_px']:.0f} px ({row['face_pixels']:.0f} px)  "
              f"HAPPY vs SERIOUS: mean |diff| {row['mean_abs_diff']:.1f} levels, "
              f"{row['changed_share']:.0%} of the face changes by > {CHANGED}", flush=True)
    (args.out / "faces.json").write_text(json.dumps({"seed": args.seed, "presets": rows}, indent=1))
    print(f"face crops and faces.json in {args.out}", file=sys.stderr)
    return 0


def face_difference(happy: tuple, serious: tuple) -> tuple[dict, np.ndarray]:
    """Measures of one driver's two expressions, and the two face crops side by side (enlarged)."""
    import cv2
    import numpy as np

    from isu_validate.render.labels import INSTANCE_ID

    (img_h, seg_h), (img_s, seg_s) = happy, serious
    face = (seg_h == INSTANCE_ID["driver_face"]) | (seg_s == INSTANCE_ID["driver_face"])
    if not face.any():
        return {"face_width_px": 0.0, "face_pixels": 0.0, "mean_abs_diff": 0.0, "changed_share": 0.0}, \
            np.zeros((64, 128, 3), np.uint8)
    luma = [cv2.cvtColor(img, cv2.COLOR_BGR2GRAY).astype(np.int16) for img in (img_h, img_s)]
    diff = np.abs(luma[0] - luma[1])[face]
    ys, xs = np.nonzero(face)
    y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
    crop = np.hstack([cv2.resize(img[y0:y1, x0:x1], (96, 96 * (y1 - y0) // max(x1 - x0, 1) or 1),
                                 interpolation=cv2.INTER_NEAREST) for img in (img_h, img_s)])
    return {"face_width_px": float(x1 - x0), "face_pixels": float(face.sum()),
            "mean_abs_diff": float(diff.mean()), "changed_share": float((diff > CHANGED).mean())}, crop


def _save_crops(crops: list, path: Path) -> None:
    import cv2
    import numpy as np

    height = max(c.shape[0] for c in crops)
    padded = [np.pad(c, ((0, height - c.shape[0]), (0, 4), (0, 0))) for c in crops]
    cv2.imwrite(str(path), np.hstack(padded))
