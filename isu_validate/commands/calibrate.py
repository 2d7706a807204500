"""``isu-validate calibrate``: camera calibration from ChArUco images, judged the mrcal way.

    isu-validate calibrate IMAGES... --board SPEC --model M --out CAMERA.toml [--json] [--report R.html]
    isu-validate calibrate diff A.toml B.toml [--json]
    isu-validate calibrate register CAMERA.toml IMAGE --markers MARKERS.toml [--out NEW.toml]
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..errors import InputError, InputNotFound
from ..image_files import IMAGE_SUFFIXES

EPILOG = """forms:
  calibrate IMAGES... --board SPEC --model M --out CAMERA.toml   calibrate (IMAGES: files or folders)
  calibrate diff A.toml B.toml                                    projection difference of two calibrations
  calibrate register CAMERA.toml IMAGE --markers FILE             camera pose in the cabin from ArUco markers
example: isu-validate calibrate shots/ --board charuco:11x8:0.030:0.022:DICT_5X5_100 --model opencv8 --out cam.toml
"""


def register(sub) -> None:
    from capture.lens_models import MODELS as LENS_MODELS   # the one list of lens models (loads no OpenCV)
    p = sub.add_parser("calibrate", help="calibrate a camera from ChArUco images (also: diff, register)",
                       epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("inputs", nargs="+", metavar="IMAGES", help="images or folders; or 'diff A B' / 'register CAM IMG'")
    p.add_argument("--board", help="charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT")
    p.add_argument("--model", default="opencv8", choices=LENS_MODELS)
    p.add_argument("--out", help="camera file to write (TOML)")
    p.add_argument("--name", help="camera name in the file (default: the output file's stem)")
    p.add_argument("--json", action="store_true", help="print the camera file's content as one JSON object")
    p.add_argument("--report", help="write the HTML calibration report here")
    p.add_argument("--cameramodel", help="also write mrcal's .cameramodel here")
    p.add_argument("--working-distance", type=float, default=1.0, help="metres, for the uncertainty (default 1)")
    p.add_argument("--outlier-sigma", type=float, default=4.0, help="reject corners beyond this many sigmas")
    p.add_argument("--no-cross-validation", action="store_true")
    p.add_argument("--force", action="store_true",
                   help="write the camera file even when the views do not determine the intrinsics")
    p.add_argument("--extrinsics-from", metavar="RIG", help="copy the cabin pose from this camera rig")
    p.add_argument("--markers", help="marker table (TOML file, or a shipped name such as 'example') for 'register', "
                                     "or with --register-image; see rigs/markers/example.toml")
    p.add_argument("--register-image", help="image with cabin markers: register the pose right away")
    p.add_argument("--no-fit", action="store_true", help="diff: do not fit the implied transform between the frames")
    p.add_argument("--distance", type=float, default=1.0,
                   help="diff: metres to the compared points (default 1; 'inf' compares directions only)")
    p.set_defaults(func=run)


def run(args) -> int:
    head = args.inputs[0]
    if head == "diff":
        return _diff(args)
    if head == "register":
        return _register(args)
    return _calibrate(args)


def _expand(inputs) -> list[Path]:
    paths = []
    for s in inputs:
        p = Path(s)
        if p.is_dir():
            paths += sorted(q for q in p.iterdir() if q.suffix.lower() in IMAGE_SUFFIXES)
        else:
            paths.append(p)
    if not paths:
        raise InputError(f"no images found in {', '.join(inputs)} (looked for {', '.join(sorted(IMAGE_SUFFIXES))})")
    return paths


def _calibrate(args) -> int:
    from capture.board import BoardSpec
    from capture.calibrate import calibrate, detect_images
    from capture.camera import to_json, write_toml
    if not args.board or not args.out:
        raise InputError("calibrate needs --board SPEC and --out CAMERA.toml (see --help)")
    spec = BoardSpec.parse(args.board)
    paths = _expand(args.inputs)

    def progress(i, n, path, corners):
        print(f"\rdetecting {i}/{n}: {corners:3d} corners in {Path(path).name}", end="", file=sys.stderr)

    detections, skipped = detect_images(paths, spec, progress)
    print(file=sys.stderr)
    for path, why in skipped:  # the user must see which shots did not count, not only the camera file
        print(f"skipped {path}: {why}", file=sys.stderr)
    if skipped:
        print(f"used {len(detections)} of {len(paths)} images", file=sys.stderr)
    name = args.name or Path(args.out).stem
    res = calibrate(detections, args.model, board=spec, name=name, working_distance_m=args.working_distance,
                    skipped=skipped, cross_validate=not args.no_cross_validation, outlier_sigma=args.outlier_sigma)
    if res.undetermined and not args.force:
        from capture.solve import CalibrationError
        raise CalibrationError(f"{res.undetermined}. No camera file written; pass --force to write {args.out} "
                               "anyway (its [quality] keeps the intervals)")
    cam = res.camera
    if args.extrinsics_from:
        cam = _with_pose_from(cam, args.extrinsics_from)
    if args.register_image:
        cam = _registered(cam, args.register_image, args.markers)
    elif not cam.registered:
        res.warnings.append("camera pose not registered: [extrinsics] is a placeholder (origin, looking forward); "
                            "run 'calibrate register' with cabin markers or pass --extrinsics-from RIG")
    write_toml(cam, args.out)
    if args.cameramodel:
        from capture.mrcal_file import write_cameramodel
        write_cameramodel(cam, args.cameramodel)
    if args.report:
        from capture.report import write_report
        res.camera = cam
        write_report(res, args.report)
    if args.json:
        print(to_json(cam))
    else:
        _print_summary(cam, res, args)
    return 0


def _print_summary(cam, res, args) -> None:
    q = cam.quality
    u = q["uncertainty_px"]
    cv = q.get("cross_validation_diff_px") or {}
    print(f"{cam.model} {cam.width}x{cam.height}: fx {cam.intrinsics[0]:.2f} fy {cam.intrinsics[1]:.2f} "
          f"cx {cam.intrinsics[2]:.2f} cy {cam.intrinsics[3]:.2f}")
    print(f"frames {q['frames']}, corners {q['corners']} ({q['outliers']} outliers), RMS {q['rms_px']:.3f} px, "
          f"noise {q['noise_px']:.3f} px")
    print(f"uncertainty at {u['distance_m']:g} m: centre {u['centre']:.3f}, edge {u['edge']:.3f}, "
          f"corner {u['corner']:.3f} px" + (f"; cross-validation diff median {cv['median']:.3f} px" if cv else ""))
    for w in res.warnings:
        print(f"warning: {w}", file=sys.stderr)
    print(f"wrote {args.out}" + (f", {args.report}" if args.report else ""))


def _with_pose_from(cam, rig_path):
    from dataclasses import replace

    from capture.camera import load_camera, require_registered
    rig = load_camera(rig_path)
    require_registered(rig, "the --extrinsics-from rig")   # a placeholder pose copied would pass as measured
    return replace(cam, position=rig.position, rotation=rig.rotation, registered=True,
                   registration={"copied_from": str(rig.source)})


def _registered(cam, image_path, markers_path):
    import cv2

    from capture.registration import load_markers, register
    from isu_validate.paths import resolve_rig
    if not markers_path:
        raise InputError("registration needs --markers FILE (marker ids and their corners in the cabin; "
                         "start from the shipped example rigs/markers/example.toml)")
    markers_path = resolve_rig("markers", markers_path)  # a file, or the name of a shipped one
    img = cv2.imread(str(image_path), cv2.IMREAD_GRAYSCALE)
    if img is None:
        raise InputNotFound(f"cannot read registration image {image_path}")
    dictionary, markers = load_markers(markers_path)
    return register(cam, img, dictionary, markers, str(image_path))


def _register(args) -> int:
    from capture.camera import read_toml, to_json, write_toml
    if len(args.inputs) != 3:
        raise InputError("usage: calibrate register CAMERA.toml IMAGE --markers FILE [--out NEW.toml]")
    cam = read_toml(args.inputs[1])
    cam = _registered(cam, args.inputs[2], args.markers)
    out = args.out or args.inputs[1]
    write_toml(cam, out)
    if args.json:
        print(to_json(cam))
    else:
        reg = cam.registration
        print(f"camera at {[round(float(v), 4) for v in cam.position]} m in the cabin; markers {reg['markers']}, "
              f"reprojection RMS {reg['rms_px']:.3f} px; wrote {out}")
        if "warning" in reg:
            print(f"warning: {reg['warning']}", file=sys.stderr)
    return 0


def _diff(args) -> int:
    from capture.camera import read_toml
    from capture.projection_diff import projection_diff
    if len(args.inputs) != 3:
        raise InputError("usage: calibrate diff A.toml B.toml")
    a, b = (read_toml(p) for p in args.inputs[1:])
    if a.size != b.size:
        raise InputError(f"the two cameras have different image sizes ({a.width}x{a.height} vs {b.width}x{b.height}); "
                         "a projection diff compares one sensor mode")
    d = projection_diff(a.model, a.intrinsics, b.model, b.intrinsics, a.size, fit=not args.no_fit,
                        distance_m=args.distance)
    out = {"a": args.inputs[1], "b": args.inputs[2], "distance_m": str(args.distance), "diff_px": d.stats(),
           "fitted_rotation_deg": d.rotation_deg, "fitted_translation_m": list(d.translation_m),
           "grid": [len(d.us), len(d.vs)]}
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        s = out["diff_px"]
        print(f"projection diff {args.inputs[1]} vs {args.inputs[2]} at {args.distance:g} m: "
              f"median {s['median']:.3f} px, p90 {s['p90']:.3f} px, max {s['max']:.3f} px "
              f"(fitted rotation {d.rotation_deg:.4f} deg)")
    return 0
