"""``isu-validate render``: render one scene file, or N random scenes of the space (with a contact sheet)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from ..devices import add_render_device_argument
from ..errors import UserError
from . import add_overwrite_option


def register(sub) -> None:
    p = sub.add_parser("render", help="render scenes with Blender (one scene file, or --random N)",
                       description="Render a scene JSON to a PNG, or N random valid scenes of the space "
                                   "into a folder with a contact sheet. Timings go to stderr.")
    p.add_argument("scene", nargs="?", type=Path,
                   help="scene JSON: {feature: value, ...}, or a run's label file (labels/<test>.json, "
                        "a pair's scene.json)")
    p.add_argument("--out", type=Path, required=True, help="output PNG (one scene) or folder (--random)")
    p.add_argument("--random", type=int, metavar="N", help="render N random valid scenes instead of a file")
    p.add_argument("--seed", type=int, default=0, help="seed of the random scenes (default 0)")
    p.add_argument("--preset", default="standard", help="draft | standard | final (default standard)")
    p.add_argument("--rig", "--camera", dest="rig", default="default",
                   help="camera rig name or .toml path (default: default); a rig with an imaging model "
                        "([exposure]/[response]/[noise]/[colour], see `isu-validate exposure`) develops the "
                        "linear render the way that camera would")
    p.add_argument("--extrinsics-from", metavar="RIG",
                   help="take the camera's pose in the cabin from this registered rig (for a calibrated camera "
                        "file whose pose was never registered)")
    p.add_argument("--min-visible", action="append", default=[], metavar="SHARE|FEATURE=SHARE",
                   help="visibility threshold for the label's `occluded` features (default: the space's)")
    p.add_argument("--cabin", default="default", help="cabin rig name or .toml path (default: default)")
    p.add_argument("--space", default="isu-paper", help="scene space name or .toml path (default isu-paper)")
    p.add_argument("--channels", default="", help="comma list of extra outputs: seg,depth,exr")
    p.add_argument("--cache", type=Path, help="render cache folder (a scene seen before costs nothing)")
    p.add_argument("--log", type=Path, help="folder for Blender's console log (default: <out folder>/logs)")
    p.add_argument("--timeout", type=float, default=240.0, help="seconds per render before the worker is killed")
    add_overwrite_option(p, "another command's output (--random)")
    add_render_device_argument(p)
    p.add_argument("--sheet-tile", type=int, default=320, metavar="PX",
                   help="width of each frame on the contact sheet of --random (default 320)")
    p.set_defaults(func=run)


def run(args) -> int:
    import numpy as np

    from ..protocols import RenderError
    from ..render import open_renderer
    from ..render.visibility import parse_min_visible
    from ..space import load_space, read_scene_file

    if (args.scene is None) == (args.random is None):
        raise UserError("give either a SCENE.json or --random N")
    space = load_space(args.space)
    if args.random is not None:
        from ..archive.output_dir import claim_output
        folder = args.out
        claim_output(folder, "render", {"random": args.random, "seed": args.seed, "preset": args.preset,
                                        "rig": args.rig, "cabin": args.cabin, "space": space.hash},
                     overwrite=args.overwrite).mark()
        scenes = [(f"scene-{i:04d}", s)
                  for i, s in enumerate(space.sample(np.random.default_rng(args.seed), args.random))]
        targets = [(folder / f"{name}.png", scene) for name, scene in scenes]
    else:
        scene = read_scene_file(args.scene)   # a plain scene, or a run's label file (a pair's scene.json)
        space.check(scene)  # a clear error before Blender starts
        folder = args.out.parent
        targets = [(args.out, scene)]
    log_dir = args.log or folder / "logs"
    unusable = 0
    with open_renderer(args.preset, args.rig, args.cabin, args.channels, args.cache, log_dir, args.timeout,
                       space, extrinsics_from=args.extrinsics_from,
                       min_visible=parse_min_visible(args.min_visible), device=args.render_device) as renderer:
        for k, (out, scene) in enumerate(targets, 1):
            if args.random is not None:
                out.parent.mkdir(parents=True, exist_ok=True)
                out.with_suffix(".scene.json").write_text(json.dumps(space.canonical(scene), indent=1))
            try:
                result = renderer.render(scene, out)
            except RenderError as exc:   # reported, and the other scenes still render
                unusable += 1
                print(f"[{k}/{len(targets)}] {out}  render error: {exc}", file=sys.stderr)
                continue
            t = result.timings
            hidden = f"; occluded: {', '.join(result.occluded)}" if result.occluded else ""
            print(f"[{k}/{len(targets)}] {out}  update {t['update_s']:.3f}s render {t['render_s']:.2f}s "
                  f"write {t['write_s']:.2f}s total {t['total_s']:.2f}s{' (cached)' if result.cached else ''}"
                  f"{hidden}", file=sys.stderr)
    frames = [out for out, _ in targets if out.exists()]
    if args.random is not None and frames:   # no sheet when no frame was written (each failure is listed above)
        from ..render.contact import contact_sheet
        from ..render.outputs import CONTACT_SHEET
        sheet = contact_sheet(frames, folder / CONTACT_SHEET, tile_width=args.sheet_tile)
        print(f"contact sheet: {sheet}", file=sys.stderr)
    print(f"Blender log: {log_dir}", file=sys.stderr)
    if unusable:
        print(f"isu-validate render: {unusable} of {len(targets)} frame(s) could not show the scene (see above)",
              file=sys.stderr)
    return 1 if unusable else 0
