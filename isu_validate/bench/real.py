"""``isu-validate bench real``: the sim-to-real tools on public real photographs, beside OpenCV and colour-science
run on the same photos.

- ``--charuco DIR --board SPEC [--reference YML]``: calibration (pinhole and opencv8) against OpenCV's
  ``calibrateCameraExtended`` on the same detections, with each side's standard deviations, and a published
  OpenCV calibration of the photos when given;
- ``--bracket PHOTOS...``: photos through ``capture import`` and the response fit of ``exposure fit``, against
  colour-hdri's Debevec 1997 with its defaults and OpenCV's ``CalibrateDebevec`` on the same frames: each
  curve predicts every frame of the bracket from its neighbour (RMS in codes) and is compared with ours;
- ``--chart PHOTO [--chart-box BOX]``: ``exposure colour --sim reference``'s dE2000 before/after against
  colour-science's own correction (``matrix_colour_correction``, Cheung 2004, 3x3) fitted on the same patches.

tests/data/real/README.md names the public sets and how to fetch them."""
from __future__ import annotations

import json
import tempfile
from pathlib import Path

OPENCV_FLAGS = {"pinhole": "CALIB_FIX_K1|K2|K3|ZERO_TANGENT_DIST", "opencv8": "CALIB_RATIONAL_MODEL"}


def register_bench(sub) -> None:
    p = sub.add_parser("real", help="real photographs: calibration, response, colour beside OpenCV and "
                                    "colour-science on the same photos")
    p.add_argument("--charuco", type=Path, help="folder of ChArUco photos")
    p.add_argument("--board", help="their board spec (charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT)")
    p.add_argument("--reference", type=Path, help="a published OpenCV calibration of the photos (YAML)")
    p.add_argument("--bracket", nargs="+", help="an exposure bracket: photos with EXIF")
    p.add_argument("--no-colour-hdri-defaults", action="store_true",
                   help="leave out colour-hdri's Debevec with its default sampling (~1 min on 3 frames)")
    p.add_argument("--chart", type=Path, help="a photo with a ColorChecker 24")
    p.add_argument("--chart-box", help="where the chart is, when no detector finds it (see exposure colour)")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..errors import InputError
    if not (args.charuco or args.bracket or args.chart):
        raise InputError("give --charuco DIR --board SPEC, --bracket PHOTOS..., --chart PHOTO, or several "
                         "(tests/data/real/README.md names public sets)")
    out = {}
    if args.charuco:
        if not args.board:
            raise InputError("--charuco needs --board SPEC")
        out["calibration"] = calibration_rows(args.charuco, args.board, args.reference)
    if args.bracket:
        out["response"] = response_rows(args.bracket, with_defaults=not args.no_colour_hdri_defaults)
    if args.chart:
        out["colour"] = colour_rows(args.chart, args.chart_box)
    print(json.dumps(out, indent=1) if args.json else _table(out))
    return 0


def detections(folder: Path, board: str):
    from capture.board import BoardSpec
    from capture.calibrate import detect_images
    from isu_validate.image_files import expand_images
    found, _ = detect_images(expand_images([folder]), BoardSpec.parse(board))
    return found


def opencv_calibration(found, model: str) -> dict:
    """OpenCV's own calibration of the same detections: intrinsics, their standard deviations, RMS."""
    import cv2
    import numpy as np
    flags = (cv2.CALIB_FIX_K1 | cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3 | cv2.CALIB_ZERO_TANGENT_DIST
             if model == "pinhole" else cv2.CALIB_RATIONAL_MODEL)
    rms, K, _, _, _, sd, _, _ = cv2.calibrateCameraExtended(
        [d.board_points.astype(np.float32) for d in found], [d.pixels.astype(np.float32) for d in found],
        found[0].image_size, None, None, flags=flags)
    sd = np.ravel(sd)
    return {"fx": K[0, 0], "fy": K[1, 1], "cx": K[0, 2], "cy": K[1, 2], "sd": sd[:4].tolist(), "rms_px": rms}


def calibration_rows(folder: Path, board: str, reference: Path | None = None) -> list[dict]:
    from capture.checks import intrinsics_intervals, undetermined_intrinsics
    from capture.solve import solve
    found = detections(folder, board)
    rows = []
    for model in ("pinhole", "opencv8"):
        sol = solve(model, found, found[0].image_size)
        iv = intrinsics_intervals(sol)
        rows.append({"model": model, "tool": "isu-validate", "views": len(found), "corners": sol.n_corners,
                     **{k: v["value"] for k, v in iv.items()}, "sd": [v["stdev"] for v in iv.values()],
                     "rms_px": sol.rms_px(), "determined": undetermined_intrinsics(sol, iv) is None})
        rows.append({"model": model, "tool": f"OpenCV calibrateCameraExtended ({OPENCV_FLAGS[model]})",
                     "views": len(found), **opencv_calibration(found, model)})
    if reference:
        rows.append(published(reference))
    return rows


def published(path: Path) -> dict:
    import cv2
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    K, D = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat()
    return {"model": f"opencv{D.size}", "tool": f"published: {path.name}", "fx": K[0, 0], "fy": K[1, 1],
            "cx": K[0, 2], "cy": K[1, 2], "rms_px": fs.getNode("avg_reprojection_error").real()}


def response_rows(photos, with_defaults: bool = True) -> list[dict]:
    """The bracket imported as a user would, then each response curve on the same frames."""
    import cv2
    import numpy as np

    from capture.camera_model import frames as frames_mod
    from capture.camera_model.model import Response
    from capture.camera_model.response_fit import bracket, bracket_residual, finish_curve, fit_response
    from capture.photo_import import import_photos
    with tempfile.TemporaryDirectory(prefix="isu-bench-real-") as tmp:
        imported = import_photos(photos, Path(tmp) / "import")
        folder = next(iter(imported.folders))
        data = frames_mod.load([imported.out / folder])
        frames = bracket(data.frames)
        curves = {"isu-validate (exposure fit)": fit_response(data.frames).linear}
        # the frames as the fit saw them (repeats of a setting averaged), and their exposure time x gain
        bgr = [np.ascontiguousarray((f.image[..., ::-1] * 255.0).round().astype(np.uint8)) for f in frames]
        times = np.array([f.product * 1e-6 for f in frames], np.float32)
        opencv = cv2.createCalibrateDebevec().process(bgr, times)[:, 0, ::-1].astype(float)
        curves["OpenCV CalibrateDebevec"] = finish_curve(opencv)
        if with_defaults:
            curves["colour-hdri Debevec 1997 (defaults)"] = finish_curve(_colour_hdri_defaults(frames))
        rows = []
        ours = curves["isu-validate (exposure fit)"]
        mid = slice(32, 225)
        for name, curve in curves.items():
            r = bracket_residual(Response(curve), frames)
            a, b = np.log(ours[mid] / ours[128]), np.log(curve[mid] / curve[128])
            rows.append({"tool": name, "frames": len(frames), "exposure_s": [f.exposure_us / 1e6 for f in frames],
                         "neighbour_rms_codes": r["rms"], "neighbour_p95_codes": r["p95"],
                         "log_curve_rms_vs_ours": float(np.sqrt(np.mean((a - b) ** 2)))})
        return rows


def _colour_hdri_defaults(frames):
    import numpy as np
    from colour_hdri import Image, ImageStack, Metadata, camera_response_functions_Debevec1997
    from threadpoolctl import threadpool_limits
    stack = ImageStack()
    for f in frames:
        stack.append(Image(data=f.image.astype(np.float64),
                           metadata=Metadata(f_number=1.0, exposure_time=f.exposure_us * 1e-6, iso=f.gain * 100)))
    with threadpool_limits(limits=1):
        return np.asarray(camera_response_functions_Debevec1997(stack), dtype=float)


def colour_rows(photo: Path, box: str | None) -> list[dict]:
    """Ours (``exposure colour --sim reference``) against colour-science's plain 3x3 Cheung 2004 on the same
    patches, both ways: reference -> camera (ours' direction) and camera -> reference (colour-science's usual)."""
    import numpy as np
    from colour.characterisation import apply_matrix_colour_correction, matrix_colour_correction

    from capture.camera_model.chart import parse_box
    from capture.camera_model.colour_align import align, read_real, read_sim
    from capture.camera_model.colour_fit import de2000, stats
    from isu_validate.srgb import srgb_decode, srgb_encode_float
    real = read_real(photo, None, "auto", parse_box(box) if box else None)
    ref = read_sim("reference")
    fit, report = align(real, ref, None)
    use = real.patches.usable & ref.patches.usable
    cam, reference = real.patches.colours[use], ref.linear[use]
    rows = [{"tool": f"isu-validate exposure colour ({report['method']} "
                     f"{report.get('terms', report.get('degree', ''))}, white balance first)",
             "direction": "reference -> camera", "patches": int(use.sum()), "found_by": real.detector,
             "before": fit.de2000_before, "after": fit.de2000_after,
             "leave_one_out_mean": min(v for v in fit.cross_validation.values() if isinstance(v, float))}]
    for direction, source, target, shown in (("reference -> camera", reference, srgb_decode(cam), cam),
                                             ("camera -> reference", srgb_decode(cam), reference,
                                              srgb_encode_float(reference))):
        m = matrix_colour_correction(source, target, method="Cheung 2004", terms=3)
        after = srgb_encode_float(np.clip(apply_matrix_colour_correction(source, m, method="Cheung 2004",
                                                                        terms=3), 0, 1))
        rows.append({"tool": "colour-science matrix_colour_correction (Cheung 2004, 3x3)", "direction": direction,
                     "patches": int(use.sum()), "found_by": real.detector,
                     "before": stats(de2000(srgb_encode_float(source), shown)), "after": stats(de2000(after, shown))})
    return rows


def _table(out: dict) -> str:
    lines = []
    for row in out.get("calibration", []):
        sd = row.get("sd")
        sds = " sd " + "/".join(f"{v:.1f}" for v in sd) if sd else ""
        flag = "" if row.get("determined", True) else "  NOT DETERMINED"
        lines.append(f"calib {row['model']:8s} {row['tool'][:60]:60s} fx {row['fx']:7.2f} fy {row['fy']:7.2f} "
                     f"cx {row['cx']:7.2f} cy {row['cy']:7.2f}{sds} RMS {row['rms_px']:.3f} px{flag}")
    for row in out.get("response", []):
        lines.append(f"response {row['tool']:40s} neighbour RMS {row['neighbour_rms_codes']:.2f} codes (p95 "
                     f"{row['neighbour_p95_codes']:.2f}), log-curve RMS vs ours {row['log_curve_rms_vs_ours']:.3f}")
    for row in out.get("colour", []):
        lines.append(f"colour {row['tool'][:70]:70s} {row['direction']:20s} dE2000 mean {row['before']['mean']:.2f} "
                     f"-> {row['after']['mean']:.2f} (max {row['after']['max']:.2f}) on {row['patches']} patches")
    return "\n".join(lines)
