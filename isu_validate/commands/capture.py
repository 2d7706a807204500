"""``isu-validate capture``: list cameras, and shoot frames with exposure sidecars.

    isu-validate capture list [--json]
    isu-validate capture shoot --source SPEC --frames N --out DIR [--exposure-us U --iso I | --auto-exposure]
    isu-validate capture shoot --source SPEC --pair PAIRS/<sample>   (frames into real/, with the alignment aid)
    isu-validate capture align --source SPEC --pair PAIRS/<sample>   (live: the aid only, nothing stored)
    isu-validate capture import PHOTOS... --out DIR | --pair PAIRS/<sample> [--exposure-us U[,U...]] [--iso I]
                                 (phone or DSLR photos: sidecars from their EXIF, pixels unchanged)
"""
from __future__ import annotations

import json
import sys
from contextlib import ExitStack

SOURCE_HELP = ("v4l2:/dev/videoN[@WxH], depthai[:MXID][@WxH], replay:DIR|VIDEO (a recorded session), or "
               "standin[:RIG] (no camera: the pair's scene rendered another way, marked as a stand-in)")


def register(sub) -> None:
    p = sub.add_parser("capture", help="camera capture: list devices, shoot frames with exposure metadata")
    csub = p.add_subparsers(dest="capture_command", metavar="ACTION")
    lp = csub.add_parser("list", help="every camera found: V4L2, DepthAI, Luxonis USB devices")
    lp.add_argument("--json", action="store_true")
    lp.set_defaults(func=run_list)
    sp = csub.add_parser("shoot", help="take frames as PNG with a JSON sidecar each")
    sp.add_argument("--source", required=True, help=SOURCE_HELP)
    sp.add_argument("--frames", type=int, default=1)
    sp.add_argument("--out", help="session folder (replay it later with --source replay:DIR)")
    sp.add_argument("--pair", help="a sample of a pairs directory (PAIRS/<sample>): frames go to its real/, "
                                   "each aligned against its sim.png (images in align/, scores printed)")
    sp.add_argument("--exposure-us", type=int, help="manual exposure time, microseconds")
    sp.add_argument("--iso", type=int, help="manual ISO (DepthAI) or raw gain (V4L2)")
    sp.add_argument("--auto-exposure", action="store_true")
    sp.add_argument("--json", action="store_true", help="print the session summary as JSON")
    sp.set_defaults(func=run_shoot)
    ap = csub.add_parser("align", help="live alignment aid for a pair: frames compared with the render, not stored")
    ap.add_argument("--source", required=True, help=SOURCE_HELP)
    ap.add_argument("--pair", required=True, help="PAIRS/<sample>")
    ap.add_argument("--frames", type=int, default=0, help="stop after N frames (default: until Ctrl-C)")
    ap.set_defaults(func=run_align)
    ip = csub.add_parser("import", help="photos from any camera (JPEG, PNG, TIFF) as frames with sidecars from EXIF")
    ip.add_argument("photos", nargs="+", help="photos or folders of photos")
    ip.add_argument("--out", help="folder: one subfolder per burst (set_01, ...: a bracket stays together), each "
                                  "with a nominal camera.toml")
    ip.add_argument("--pair", help="a sample of a pairs directory (PAIRS/<sample>): the photos become its real/ "
                                   "frames (frame_NNNN), for `agree`")
    ip.add_argument("--exposure-us", type=_exposures, metavar="U[,U...]",
                    help="exposure time in microseconds where EXIF has none: one for all photos or one per photo")
    ip.add_argument("--iso", type=float, help="ISO where EXIF has none (gain x 100)")
    mode = ip.add_mutually_exclusive_group()
    mode.add_argument("--auto-exposure", dest="auto", action="store_const", const=True,
                      help="the camera chose the exposures (overrides EXIF's exposure mode)")
    mode.add_argument("--manual", dest="auto", action="store_const", const=False,
                      help="the exposures were set by hand, e.g. a bracket (overrides EXIF's exposure mode)")
    ip.add_argument("--burst-gap", type=float, default=60.0, metavar="SECONDS",
                    help="a longer pause between two photos starts a new folder (default 60)")
    ip.set_defaults(func=run_import)
    p.set_defaults(func=lambda args: p.print_help() or 2)


def run_list(args) -> int:
    from capture.discovery import any_camera, list_cameras, none_found_message
    found = list_cameras()
    if args.json:
        print(json.dumps(found, indent=2))
        return 0 if any_camera(found) else 1
    if not any_camera(found):
        print(none_found_message(found))
        return 1
    for e in found["v4l2"]:
        fmts = "; ".join(f"{k}: {' '.join(v)}" for k, v in e.get("formats", {}).items())
        print(f"{e['spec']:28s} {e.get('name', '')} {e.get('error', '')} {fmts}".rstrip())
    for e in found["depthai"]:
        print(f"{e['spec']:28s} {e['name']} ({e['state']}, {e['protocol']}) NV12: {' '.join(e['formats']['NV12'])}")
    for e in found["usb"]:
        print(f"usb {e['bus']:03d}:{e['address']:03d} {'':16s} Luxonis {e['vendor']}:{e['product']} ({e['note']})")
    for p in found["problems"]:
        print(f"note: {p}", file=sys.stderr)
    return 0


def run_shoot(args) -> int:
    from capture.session import shoot
    from capture.sources import CaptureError, ExposureRequest
    from isu_validate.errors import InputError
    request = ExposureRequest(args.exposure_us, args.iso, args.auto_exposure)
    if (args.out is None) == (args.pair is None):
        raise InputError("give --out DIR (a session folder) or --pair PAIRS/<sample>, one of the two")
    sample = _pair(args.pair) if args.pair else None
    if args.out:   # another command's output is refused here; another session's frames by shoot
        from isu_validate.archive.output_dir import claim_output
        claim_output(args.out, "capture shoot", {}, resume=True, overwrite=None)

    def progress(i, n, meta):
        exp = meta.get("exposure_us")
        end = "\n" if sample else ""
        print(f"\rframe {i}/{n}" + (f" exposure {exp:.0f} us" if exp else ""), end=end, file=sys.stderr)

    try:
        with ExitStack() as renders:
            source = _source(args.source, sample, renders)
            out, first, annotate = (sample.real_dir, sample.next_frame_index(), _aligner(sample)) if sample else (
                args.out, None, None)
            session = shoot(source, args.frames, out, request, progress, first, annotate)
    except CaptureError:
        print(file=sys.stderr)  # end the progress line; the CLI prints the CaptureError (a UserError) as one line
        raise
    print(file=sys.stderr)
    for w in session.warnings:
        print(f"warning: {w}", file=sys.stderr)
    if args.json:
        print(json.dumps({"out": str(session.out), "frames": [str(p) for p in session.frames],
                          "warnings": session.warnings}, indent=2))
    else:
        print(f"wrote {len(session.frames)} frame(s) with sidecars to {session.out}")
    return 0


def _exposures(text: str) -> list[float]:
    import argparse
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if not values or min(values) <= 0:
        raise argparse.ArgumentTypeError(f"expected positive microseconds, e.g. 125000 or 125000,1000000; got {text!r}")
    return values


def run_import(args) -> int:
    from capture.photo_import import import_photos
    from capture.sidecar import load_sidecar
    from isu_validate.errors import InputError
    if (args.out is None) == (args.pair is None):
        raise InputError("give --out DIR (a folder of imported frames) or --pair PAIRS/<sample>, one of the two")
    if args.pair:
        sample = _pair(args.pair)
        result = import_photos(args.photos, sample.real_dir, args.exposure_us, args.iso, args.auto,
                               args.burst_gap, rename="frame_", first_index=sample.next_frame_index())
    else:
        from isu_validate.archive.output_dir import claim_output
        output = claim_output(args.out, "capture import", {}, overwrite=None)
        result = import_photos(args.photos, args.out, args.exposure_us, args.iso, args.auto, args.burst_gap)
        output.mark()      # only once something was imported: a refused import leaves no marked, empty folder
    for folder, frames in result.folders.items():
        where = result.out / folder
        sidecars = [load_sidecar(f) for f in frames]
        times = ", ".join(f"{s['exposure_us'] / 1e6:g}" for s in sidecars)
        isos = ", ".join(sorted({format(s["iso"], "g") for s in sidecars}))
        modes = {"auto" if s["auto_exposure"] else "manual" for s in sidecars}
        print(f"{where}: {len(frames)} frame(s) from {sidecars[0]['device']}, exposure {times} s, ISO "
              f"{isos}, {'/'.join(sorted(modes))}"
              + (f"; nominal camera file {result.cameras[folder]}" if folder in result.cameras else ""))
    for note in result.notes:
        print(f"note: {note}", file=sys.stderr)
    if not args.pair:
        first = next(iter(result.folders))
        print(f"next: isu-validate exposure fit {result.out / first} --camera {result.cameras[first]} "
              f"--out camera-fitted.toml", file=sys.stderr)
    return 0


def _pair(path):
    from isu_validate.errors import InputError
    from isu_validate.pairs import PairsDir
    sample = PairsDir(__import__("pathlib").Path(path).parent).sample(path)
    if not sample.sim.is_file():
        raise InputError(f"{sample.path} has no sim.png to align against; is it a sample written by "
                         "`isu-validate recreate`?")
    return sample


def _source(spec: str, sample, renders: ExitStack):
    """The frame source; a stand-in renders the pair's scene (its renderer closes with ``renders``)."""
    from capture.sources import open_source, parse_spec
    from isu_validate.errors import InputError
    if parse_spec(spec)[0] != "standin":
        return open_source(spec)
    if sample is None:
        raise InputError("the standin source renders a pair's scene: add --pair PAIRS/<sample>")
    return open_source(spec, render=_standin_render(sample, renders))


def _standin_render(sample, renders: ExitStack):
    """The stand-in's render (``capture.sources.standin.RenderScene``): the pair's scene in the pair's space,
    through the stand-in's rig under its light. Blender starts on the first frame, stops with ``renders``."""
    from capture.sources.standin import PRESET, standin_cabin
    from isu_validate.render import load_cabin, open_renderer
    from isu_validate.space import load_space
    scene, space = sample.scene(), load_space(sample.label().get("space", "isu-paper"))

    def render(rig, out):
        renderer = renders.enter_context(open_renderer(PRESET, camera=rig, cabin=standin_cabin(load_cabin("default")),
                                                       log_dir=out.parent, space=space))
        return renderer.render(scene, out).image
    return render


def _render_camera(sample):
    """The pair's camera (camera.toml): its focal length turns the aid's pixels into degrees; None without one."""
    from capture.camera import load_camera
    if not sample.camera.is_file():
        print(f"note: {sample.camera} is missing: the alignment aid advises in pixels, not degrees", file=sys.stderr)
        return None
    return load_camera(sample.camera)


def _aligner(sample):
    """Per frame: the alignment aid image in the pair's align/, the scores printed and kept in the sidecar."""
    from capture.alignment import align, read_bgr
    import cv2
    render, camera = read_bgr(sample.sim), _render_camera(sample)

    def annotate(path, frame) -> dict:
        result, image = align(render, frame.image, camera)
        target = sample.align_image(path)
        target.parent.mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(target), image)
        print(f"  {path.name}: {result.line()} (aid: {target})", file=sys.stderr)
        return {"alignment": {**result.to_json(), "aid_image": str(target.relative_to(sample.path))}}
    return annotate


def run_align(args) -> int:
    """Frames from the source against the pair's render until enough: the aid goes to align/live.png."""
    from capture.alignment import align, read_bgr
    import cv2
    sample = _pair(args.pair)
    render, camera = read_bgr(sample.sim), _render_camera(sample)
    live = sample.align_dir / "live.png"
    live.parent.mkdir(parents=True, exist_ok=True)
    with ExitStack() as renders, _source(args.source, sample, renders) as source:  # a CaptureError is a UserError
        n = 0
        while not args.frames or n < args.frames:
            result, image = align(render, source.read().image, camera)
            cv2.imwrite(str(live), image)
            n += 1
            print(f"frame {n}: {result.line()}", flush=True)
    print(f"aid image: {live} (refreshed each frame)", file=sys.stderr)
    return 0
