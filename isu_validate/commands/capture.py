"""``isu-validate capture``: list cameras, and shoot frames with exposure sidecars.

    isu-validate capture list [--json]
    isu-validate capture shoot --source SPEC --frames N --out DIR [--exposure-us U --iso I | --auto-exposure]
"""
from __future__ import annotations

import json
import sys

SOURCE_HELP = "v4l2:/dev/videoN[@WxH], depthai[:MXID][@WxH], or replay:DIR|VIDEO (a recorded session)"


def register(sub) -> None:
    p = sub.add_parser("capture", help="camera capture: list devices, shoot frames with exposure metadata")
    csub = p.add_subparsers(dest="capture_command", metavar="ACTION")
    lp = csub.add_parser("list", help="every camera found: V4L2, DepthAI, Luxonis USB devices")
    lp.add_argument("--json", action="store_true")
    lp.set_defaults(func=run_list)
    sp = csub.add_parser("shoot", help="take frames as PNG with a JSON sidecar each")
    sp.add_argument("--source", required=True, help=SOURCE_HELP)
    sp.add_argument("--frames", type=int, default=1)
    sp.add_argument("--out", required=True, help="session folder (replay it later with --source replay:DIR)")
    sp.add_argument("--exposure-us", type=int, help="manual exposure time, microseconds")
    sp.add_argument("--iso", type=int, help="manual ISO (DepthAI) or raw gain (V4L2)")
    sp.add_argument("--auto-exposure", action="store_true")
    sp.add_argument("--json", action="store_true", help="print the session summary as JSON")
    sp.set_defaults(func=run_shoot)
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
    from capture.sources import CaptureError, ExposureRequest, open_source
    request = ExposureRequest(args.exposure_us, args.iso, args.auto_exposure)
    source = open_source(args.source)

    def progress(i, n, meta):
        exp = meta.get("exposure_us")
        print(f"\rframe {i}/{n}" + (f" exposure {exp:.0f} us" if exp else ""), end="", file=sys.stderr)

    try:
        session = shoot(source, args.frames, args.out, request, progress)
    except CaptureError as exc:
        print(file=sys.stderr)
        raise ValueError(str(exc)) from None  # the CLI prints ValueErrors as one clear line
    print(file=sys.stderr)
    for w in session.warnings:
        print(f"warning: {w}", file=sys.stderr)
    if args.json:
        print(json.dumps({"out": str(session.out), "frames": [str(p) for p in session.frames],
                          "warnings": session.warnings}, indent=2))
    else:
        print(f"wrote {len(session.frames)} frame(s) with sidecars to {session.out}")
    return 0
