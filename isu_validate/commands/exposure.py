"""``isu-validate exposure``: fit a camera's exposure and colour behaviour, apply it to renders, check.

    isu-validate exposure fit FRAMES... --camera CAM.toml --out CAM2.toml [--json] [--plot P.png]
    isu-validate exposure apply RENDER.exr|RUN --camera CAM2.toml [--out PNG|DIR]
    isu-validate exposure chart --real REAL.png --camera CAM.toml --out SIM.png
    isu-validate exposure colour --real REAL.png --sim SIM.png|SIM.exr|reference --out CCM.json [--json]
                                 [--camera CAM.toml [--camera-out CAM3.toml]]
    isu-validate exposure check SIM_DIR REAL_DIR | PAIRS [--out DIR] [--json]

exposure check counts the captures whose sidecar marks them stand-ins (renders taken for photos)
and says so first in its report, check.json and console summary.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from . import add_overwrite_option

CHART_BOX_HELP = ("where the chart is in the real frame when no detector finds it: X,Y,W,H in pixels around "
                  "its 24 patches (dark skin at the top left), or X1,Y1,...,X4,Y4: the corners of the patch "
                  "area from dark skin clockwise (bluish green, black, white)")

EPILOG = """a camera file with an imaging model develops every render through it:
  isu-validate render scene.json --camera CAM2.toml --out sim.png
  isu-validate run --camera CAM2.toml --out runs/cam2
"""


def register(sub) -> None:
    p = sub.add_parser("exposure", help="camera exposure, response, noise and colour: fit, apply, check",
                       epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    s = p.add_subparsers(dest="exposure_command", metavar="ACTION")
    fit = s.add_parser("fit", help="fit response, auto-exposure and noise from frames with sidecars")
    fit.add_argument("frames", nargs="+", help="frames or folders (each frame with its .json sidecar): an exposure "
                                               "bracket, auto-exposed frames under several light levels, repeats")
    fit.add_argument("--camera", required=True, help="the camera file to extend (TOML)")
    fit.add_argument("--out", required=True, help="camera file to write, with [exposure] [response] [noise]")
    fit.add_argument("--exposure-us", type=_range, metavar="MIN:MAX", help="exposure-time limits from the datasheet "
                                                                          "(default: the widest seen)")
    fit.add_argument("--gain", type=_range, metavar="MIN:MAX", help="gain limits (ISO/100) from the datasheet")
    fit.add_argument("--roi", type=_roi, metavar="X0,Y0,X1,Y1", help="a cabin metering region (fractions) to test")
    fit.add_argument("--sim", type=Path, metavar="DIR",
                     help="linear renders <frame stem>.exr of the captured scenes "
                          "(fits the sensitivity that links render light to the camera)")
    fit.add_argument("--plot", type=Path, help="measured against predicted exposure and brightness (PNG)")
    fit.add_argument("--json", action="store_true", help="print the fit summary as JSON")
    fit.set_defaults(func=_fit)

    app = s.add_parser("apply", help="develop a linear render (EXR) or every EXR of a run through a camera")
    app.add_argument("target", type=Path, metavar="RENDER.exr|RUN")
    app.add_argument("--camera", required=True, help="camera file with an imaging model")
    app.add_argument("--out", type=Path, help="PNG (for an EXR) or folder (for a run; default RUN/camera-<name>)")
    app.add_argument("--json", action="store_true")
    app.set_defaults(func=_apply)

    ch = s.add_parser("chart", help="render a virtual ColorChecker where the real one is in REAL.png")
    ch.add_argument("--real", required=True, type=Path)
    ch.add_argument("--camera", required=True, help="the calibrated, registered camera file that took REAL.png")
    ch.add_argument("--out", required=True, type=Path, help="the render (PNG)")
    ch.add_argument("--pitch", type=float, default=None, help="patch centre distance in metres (default 0.0445)")
    ch.add_argument("--preset", default="standard")
    ch.add_argument("--detector", default="auto", choices=["auto", "mcc", "ccd"])
    ch.add_argument("--chart-box", metavar="BOX", help=CHART_BOX_HELP)
    ch.set_defaults(func=_chart)

    col = s.add_parser("colour", help="fit the colour correction on a ColorChecker in a real frame and a render")
    col.add_argument("--real", required=True, type=Path)
    col.add_argument("--sim", required=True, help="render with the chart (PNG, or its linear EXR) or 'reference'")
    col.add_argument("--out", required=True, type=Path, help="JSON with the correction and dE2000 before/after")
    col.add_argument("--camera", help="camera file whose [response] linearises the real frame (default sRGB)")
    col.add_argument("--camera-out", help="write the camera file with the fitted [colour] and white balance here")
    col.add_argument("--detector", default="auto", choices=["auto", "mcc", "ccd"])
    col.add_argument("--chart-box", metavar="BOX", help=CHART_BOX_HELP)
    col.add_argument("--json", action="store_true")
    col.set_defaults(func=_colour)

    chk = s.add_parser("check", help="brightness and colour of renders against captures of the same scenes")
    chk.add_argument("sim_dir", type=Path, metavar="SIM_DIR|PAIRS", help="renders, or a pairs directory alone")
    chk.add_argument("real_dir", type=Path, nargs="?", metavar="REAL_DIR", help="captures named like the renders")
    chk.add_argument("--out", type=Path, default=Path("exposure-check"), help="folder for report.html and check.json")
    chk.add_argument("--json", action="store_true")
    add_overwrite_option(chk, "a check of other folders, or another command's output")
    chk.set_defaults(func=_check)
    p.set_defaults(func=lambda args: p.print_help() or 2)


def _range(text: str) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected MIN:MAX, got {text!r}") from None
    if not 0 < lo <= hi:
        raise argparse.ArgumentTypeError(f"expected 0 < MIN <= MAX, got {text!r}")
    return lo, hi


def _roi(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 4 or not (0 <= values[0] < values[2] <= 1 and 0 <= values[1] < values[3] <= 1):
        raise argparse.ArgumentTypeError(f"expected X0,Y0,X1,Y1 as fractions with X0<X1, Y0<Y1, got {text!r}")
    return values


def _model_of(camera: str):
    from capture.camera import load_camera
    from capture.camera_model.model import ImagingModel
    rig = load_camera(camera)
    return rig.imaging or ImagingModel(source=str(rig.source)), rig


def _fit(args) -> int:
    from capture.camera import write_imaging
    from capture.camera_model.fit import fit_camera, plot_predictions
    base, rig = _model_of(args.camera)
    result = fit_camera(args.frames, base, args.exposure_us, args.gain, args.roi, args.sim)
    write_imaging(rig.source, result.model, args.out, " fitted by isu-validate exposure fit")
    if args.plot:
        plot_predictions(result, args.plot)
    summary = result.summary()
    if args.json:
        print(json.dumps({"camera": str(args.out), **summary}, indent=2, default=str))
    else:
        _print_fit(summary, args)
    for w in result.warnings:
        print(f"warning: {w}", file=sys.stderr)
    return 0


def _print_fit(summary: dict, args) -> None:
    if "response" in summary:
        r = summary["response"]
        rms = r["residual_codes"]
        print(f"response: {r['frames']} bracket exposures, neighbour prediction RMS "
              f"{rms:.2f} codes" if rms is not None else "response: kept")
    if "exposure" in summary:
        e = summary["exposure"]
        print(f"auto-exposure: target {e['target']:.4f} (spread {e['target_relative_std'] or 0:.2%}), metering "
              f"{e['metering']}{' sigma %.2f' % e['centre_sigma'] if e['metering'] == 'centre' else ''}, "
              f"exposure {e['exposure_us'][0]:.0f}-{e['exposure_us'][1]:.0f} us, gain {e['gain'][0]:.2f}-"
              f"{e['gain'][1]:.2f}, {e['order']}, speed {e['speed']:.2f}")
    if "noise" in summary and summary["noise"]:
        n = summary["noise"]
        print(f"noise: shot {n['shot']:.3g}, read {n['read']:.3g} (relative RMS residual "
              f"{n['relative_rms_residual'] or 0:.2f})")
    print(f"wrote {args.out}" + (f", {args.plot}" if args.plot else ""))


def _claim(out: Path, command: str, settings: dict, overwrite: bool | None, resume: bool = False) -> None:
    """``out`` is new or this command's own with these settings (paths as absolute); marked as it."""
    from isu_validate.archive.output_dir import claim_output
    settings = {k: str(Path(v).resolve()) if isinstance(v, Path) else v for k, v in settings.items()}
    claim_output(out, command, settings, overwrite=overwrite, resume=resume).mark()


def _apply(args) -> int:
    from capture.camera_model.develop import develop_file, develop_run
    from isu_validate.errors import InputError
    model, rig = _model_of(args.camera)
    if model.empty:
        raise InputError(f"{args.camera} has no imaging model ([exposure]/[response]/[noise]/[colour]); fit one "
                         "with `isu-validate exposure fit`")
    if args.target.is_dir():
        out = args.out or args.target / f"camera-{rig.name}"
        # another command's output is refused here; renders of another camera by develop_run, which resumes
        _claim(out, "exposure apply", {"run": args.target}, overwrite=None, resume=True)

        def progress(i, n, row):
            print(f"\r[{i}/{n}] {Path(row['image']).name}", end="", file=sys.stderr)

        rows = develop_run(args.target, model, out, progress)
        print(file=sys.stderr)
        print(json.dumps(rows, indent=1) if args.json else f"{len(rows)} renders developed into {out}")
        return 0
    out = args.out or args.target.with_suffix(".camera.png")
    row = develop_file(args.target, model, out)
    if args.json:
        print(json.dumps(row, indent=1))
    else:
        e = row.get("exposure")
        chosen = (f": exposure {e['exposure_us']:.0f} us, gain {e['gain']:.2f}, metered {e['metered']:.3f}"
                  + (f" (at its {e['at_limit']} limit)" if e["at_limit"] else "")) if e else ""
        print(f"wrote {out}{chosen}")
    return 0


def _chart(args) -> int:
    from capture.camera_model.virtual_chart import DEFAULT_PITCH_M
    from isu_validate.render.virtual_chart import render_virtual_chart
    info = render_virtual_chart(args.real, args.camera, args.out, args.preset, args.pitch or DEFAULT_PITCH_M,
                                args.detector, _box(args.chart_box))
    print(f"virtual chart rendered to {args.out} (chart {'pointed at' if info['detector'] == 'box' else 'found'} by "
          f"{info['detector']}, board at "
          f"{[round(v, 3) for v in info['board_position']]} m in the cabin)")
    return 0


def _box(text: str | None):
    from capture.camera_model.chart import parse_box
    return parse_box(text) if text else None


def _colour(args) -> int:
    from capture.camera import write_imaging
    from capture.camera_model.colour_align import align, read_real, read_sim
    from isu_validate.errors import InputError
    model, rig = _model_of(args.camera) if args.camera else (None, None)
    if args.camera_out and not args.camera:
        raise InputError("--camera-out needs --camera (the camera file to extend)")
    response = model.response if model is not None else None
    fit, report = align(read_real(args.real, response, args.detector, _box(args.chart_box)),
                        read_sim(args.sim, args.detector), response)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1))
    if args.camera_out:
        from dataclasses import replace

        base = model.curve
        fitted = replace(model, response=replace(base, white_balance=fit.white_balance, fit={
            **base.fit, "white_balance_from": f"neutral patches of {args.real} against {args.sim}"}),
            colour=replace(fit.correction, fit={k: report[k] for k in ("real", "sim", "de2000_before", "de2000_after",
                                                                      "cross_validation_de2000", "patches")}))
        write_imaging(rig.source, fitted, args.camera_out, " and colour from isu-validate exposure colour")
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        b, a = report["de2000_before"], report["de2000_after"]
        p = report["patches"]
        print(f"{report['method']} {report.get('terms', report.get('degree', ''))}: dE2000 mean {b['mean']:.2f} -> "
              f"{a['mean']:.2f}, max {b['max']:.2f} -> {a['max']:.2f} over {p['used']} patches "
              f"({p['dropped']} dropped: real {p['real']['why'] or 'none'}, sim {p['sim']['why'] or 'none'})")
        print(f"wrote {args.out}" + (f", {args.camera_out}" if args.camera_out else ""))
    return 0


def _check(args) -> int:
    from capture.camera_model.check import compare, stand_in_banner, write_html, write_json
    from isu_validate.render.outputs import by_product
    result = compare(args.sim_dir, args.real_dir, by_product)
    _claim(args.out, "exposure check", {"sim": args.sim_dir, "real": args.real_dir}, overwrite=args.overwrite)
    write_json(result, args.out / "check.json")
    page = write_html(result, args.out / "report.html")
    s = result["summary"]
    if args.json:
        print(json.dumps(s, indent=1))
    else:
        if s["stand_in_frames"]:   # first: a figure on renders must not read as a real-world one
            print(stand_in_banner(s))
        print(f"{s['pairs']} pairs: mean |luma difference| {s['mean_abs_luma_difference']:.3f}, dE2000 of mean "
              f"colours {s['mean_de2000_mean_colour']:.2f} (max {s['max_de2000_mean_colour']:.2f}); report {page}")
        if s["unmatched"]:
            print(f"warning: {len(s['unmatched'])} file(s) without a namesake were left out", file=sys.stderr)
    return 0
