"""``capture import``: photographs from any camera become captured frames, their sidecars read from EXIF.

A phone or a DSLR writes what ``capture shoot`` puts in a sidecar (exposure time, ISO, time) into the
photo's EXIF. Import copies each photo byte for byte (its pixels are never touched: a JPEG stays the
camera's JPEG) and writes the sidecar beside it from the EXIF, read by Pillow. Photos taken in one burst
(same camera, focal length and aperture, no pause longer than ``burst_gap_s``) go into one folder, so an
exposure bracket arrives as the one folder ``exposure fit`` takes as a bracket; each folder also gets a
nominal ``camera.toml`` (image size, focal length from EXIF when it says enough, never calibrated) for the
commands that need a camera file.

Whether the camera chose the exposure (``auto_exposure``) comes from EXIF ExposureMode/ExposureProgram;
a photo that says neither is taken as manual (a bracket) unless told otherwise. RAW files are refused with
what to do: a linear 8-bit development would crush the shadows ``exposure fit`` needs.
"""
from __future__ import annotations

import datetime as _dt
import hashlib
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from isu_validate.atomic import write_json
from isu_validate.errors import InputError
from isu_validate.image_files import expand_images

from .sidecar import sidecar_path

RAW_SUFFIXES = (".dng", ".cr2", ".cr3", ".nef", ".arw", ".orf", ".rw2", ".raf", ".pef", ".srw")
PHOTO_SUFFIXES = (".jpg", ".jpeg", ".png", ".tif", ".tiff", ".webp")
BURST_GAP_S = 60.0
FULL_FRAME_DIAGONAL_MM = 43.27     # the 35 mm film frame (36 x 24 mm) that FocalLengthIn35mmFilm refers to

# EXIF tags (Exif 2.32): IFD0 and the Exif sub-IFD
_EXIF_IFD = 0x8769
_MAKE, _MODEL, _DATETIME = 0x010F, 0x0110, 0x0132
_EXPOSURE_TIME, _F_NUMBER, _PROGRAM, _ISO = 0x829A, 0x829D, 0x8822, 0x8827
_TAKEN, _SUBSEC, _FOCAL, _MODE, _FOCAL_35 = 0x9003, 0x9291, 0x920A, 0xA402, 0xA405
_PROGRAMS = {0: None, 1: False}              # 1 manual; 2-8 program, priorities, scene modes: the camera chose
_MODES = {0: True, 1: False, 2: False}        # auto, manual, auto bracket (each frame fixed by the bracket)


class ImportFailed(InputError):
    """A photo that cannot become a captured frame; the message names the photo, the field and the fix."""


@dataclass
class Photo:
    path: Path
    width: int
    height: int
    exposure_us: float | None = None
    iso: float | None = None
    f_number: float | None = None
    focal_length_mm: float | None = None
    focal_length_35mm: float | None = None
    make: str = ""
    model: str = ""
    taken: str | None = None                 # ISO 8601, camera clock (EXIF carries no time zone)
    auto_exposure: bool | None = None
    given: list[str] = field(default_factory=list)     # fields that came from the command line, not EXIF

    @property
    def camera(self) -> str:
        return " ".join(p for p in (self.make, self.model) if p) or "unknown camera"

    def burst_key(self) -> tuple:
        return (self.camera, self.width, self.height, self.focal_length_mm, self.f_number)


@dataclass
class ImportResult:
    out: Path
    folders: dict[str, list[Path]] = field(default_factory=dict)     # folder name -> frames, in time order
    cameras: dict[str, Path] = field(default_factory=dict)           # folder name -> its nominal camera file
    notes: list[str] = field(default_factory=list)


def read_photo(path: Path) -> Photo:
    """The photo's size and EXIF (nothing guessed: a field EXIF lacks stays None)."""
    from PIL import Image, UnidentifiedImageError
    try:
        with Image.open(path) as im:
            exif = im.getexif()
            width, height = _oriented_size(im.size, exif.get(0x0112))
    except UnidentifiedImageError:
        raise ImportFailed(f"{path} cannot be read as an image (corrupt, or not a photo)") from None
    sub = exif.get_ifd(_EXIF_IFD)
    tag = lambda key: sub.get(key, exif.get(key))   # noqa: E731 (some writers put Exif tags in IFD0)
    exposure_s, iso = _number(tag(_EXPOSURE_TIME)), _number(tag(_ISO))
    mode, program = _code(tag(_MODE)), _code(tag(_PROGRAM))
    auto = _MODES.get(mode) if mode is not None else None
    if auto is None and program is not None:
        auto = _PROGRAMS.get(program, True)
    return Photo(path, width, height, exposure_s * 1e6 if exposure_s else None, iso or None,
                 _number(tag(_F_NUMBER)) or None, _number(tag(_FOCAL)) or None, _number(tag(_FOCAL_35)) or None,
                 _text(exif.get(_MAKE)), _text(exif.get(_MODEL)), _time(tag(_TAKEN) or exif.get(_DATETIME),
                                                                     tag(_SUBSEC)), auto)


def _oriented_size(size, orientation) -> tuple[int, int]:
    """The size as image readers show it: OpenCV and Pillow's exif_transpose turn by EXIF Orientation."""
    w, h = size
    return (h, w) if orientation in (5, 6, 7, 8) else (w, h)


def _number(value) -> float | None:
    if isinstance(value, (tuple, list)):
        value = value[0] if value else None
    try:
        v = float(value)
    except (TypeError, ValueError, ZeroDivisionError):
        return None
    return v if v == v and v > 0 else None    # NaN (a 0/0 rational) and 0 mean "not recorded"


def _code(value) -> int | None:
    """An EXIF enumeration (0 is a value here, unlike for the measured fields)."""
    try:
        return int(value)
    except (TypeError, ValueError):
        return None


def _text(value) -> str:
    return str(value).strip("\x00 ").strip() if value else ""


def _time(value, subsec) -> str | None:
    try:
        when = _dt.datetime.strptime(str(value).strip("\x00 "), "%Y:%m:%d %H:%M:%S")
    except (TypeError, ValueError):
        return None
    digits = "".join(c for c in str(subsec or "") if c.isdigit())
    if digits:
        when = when.replace(microsecond=int((digits + "000000")[:6]))
    return when.isoformat()


def expand_photos(items) -> list[Path]:
    """Photos named or found in the folders named (sorted); RAW files and missing paths are refused."""
    paths = expand_images(items, "photo ", PHOTO_SUFFIXES + RAW_SUFFIXES)
    for p in paths:
        if p.suffix.lower() in RAW_SUFFIXES:
            raise ImportFailed(f"{p} is a RAW file: import takes the camera's JPEG, PNG or TIFF (8-bit). Shoot "
                               "RAW+JPEG and import the JPEGs, or develop the RAW files to 8-bit TIFF or PNG without "
                               "auto-brightening and import those (with --exposure-us and --iso if the developer "
                               "drops the EXIF)")
        if p.suffix.lower() not in PHOTO_SUFFIXES:
            raise ImportFailed(f"{p}: {p.suffix or 'no suffix'} is not a photo this import reads "
                               f"({', '.join(PHOTO_SUFFIXES)})")
    return paths


def complete(photo: Photo, exposure_us: float | None, iso: float | None, auto: bool | None) -> Photo:
    """Fill in what EXIF lacks from the command line (never overriding EXIF); ImportFailed names what is
    still missing and the option that gives it."""
    if photo.exposure_us is None:
        if exposure_us is None:
            raise ImportFailed(f"{photo.path}: EXIF has no ExposureTime; give it with --exposure-us MICROSECONDS "
                               "(one value for every photo, or a comma-separated value per photo in order)")
        photo.exposure_us, photo.given = float(exposure_us), photo.given + ["exposure_us"]
    if photo.iso is None:
        if iso is None:
            raise ImportFailed(f"{photo.path}: EXIF has no ISOSpeedRatings; give it with --iso ISO (the sensor "
                               "gain x 100: 100 at base gain)")
        photo.iso, photo.given = float(iso), photo.given + ["iso"]
    if auto is not None:
        photo.auto_exposure, photo.given = auto, photo.given + ["auto_exposure"]
    return photo


def bursts(photos: list[Photo], gap_s: float = BURST_GAP_S) -> list[list[Photo]]:
    """Photos of one camera setting (camera, size, focal length, aperture) without a pause over ``gap_s``
    between them, in time order (name order where EXIF has no time)."""
    by_key: dict[tuple, list[Photo]] = {}
    for p in sorted(photos, key=lambda p: (p.taken or "", p.path.name)):
        by_key.setdefault(p.burst_key(), []).append(p)
    out = []
    for group in by_key.values():
        current = [group[0]]
        for prev, p in zip(group, group[1:]):
            if prev.taken and p.taken and (_dt.datetime.fromisoformat(p.taken)
                                           - _dt.datetime.fromisoformat(prev.taken)).total_seconds() > gap_s:
                out.append(current)
                current = []
            current.append(p)
        out.append(current)
    return sorted(out, key=lambda g: (g[0].taken or "", g[0].path.name))


def sidecar(photo: Photo, frame_name: str, index: int) -> dict:
    """What ``capture shoot`` writes for a frame, from the photo's EXIF (``camera_model/frames.py`` reads it)."""
    exposure_mode_note = None
    auto = photo.auto_exposure
    if auto is None:
        auto = False
        exposure_mode_note = ("EXIF records neither ExposureMode nor ExposureProgram: taken as manual (a bracket); "
                              "import with --auto-exposure if the camera chose the exposure")
    meta = {"frame": frame_name, "source": f"import:{photo.camera}", "device": photo.camera,
            "exposure_us": photo.exposure_us, "iso": photo.iso, "auto_exposure": auto, "sequence": index,
            "f_number": photo.f_number, "focal_length_mm": photo.focal_length_mm,
            "focal_length_35mm": photo.focal_length_35mm, "make": photo.make, "model": photo.model,
            "timestamp": photo.taken, "width": photo.width, "height": photo.height,
            "imported_from": str(photo.path.resolve()), "sha256": _sha256(photo.path),
            "from_command_line": photo.given}
    if exposure_mode_note:
        meta["note"] = exposure_mode_note
    return meta


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def nominal_camera(photo: Photo, name: str) -> tuple[dict, str]:
    """A camera file's tables for the photos' camera: image size, a pinhole from EXIF's focal length where
    EXIF says enough (35 mm equivalent), else a placeholder focal length, marked as not calibrated; no
    [extrinsics] (the pose is the unregistered placeholder)."""
    w, h = photo.width, photo.height
    if photo.focal_length_35mm:
        f = photo.focal_length_35mm * (w ** 2 + h ** 2) ** 0.5 / FULL_FRAME_DIAGONAL_MM
        how = f"nominal: EXIF 35 mm-equivalent focal length {photo.focal_length_35mm:g} mm, not calibrated"
    else:
        f = float(max(w, h))
        how = ("placeholder: EXIF gives no 35 mm-equivalent focal length, fx = fy = the image width (about a "
               "53 deg field of view); calibrate the camera (`isu-validate calibrate`) before using its geometry")
    tables = {"name": name, "image": {"width": w, "height": h},
              "intrinsics": {"model": "pinhole", "fx": f, "fy": f, "cx": (w - 1) / 2, "cy": (h - 1) / 2,
                             "distortion": []},
              "calibration": {"intrinsics": how, "camera": photo.camera, "tool": "isu-validate capture import"}}
    return tables, how


def import_photos(items, out: str | Path, exposure_us=None, iso: float | None = None, auto: bool | None = None,
                  gap_s: float = BURST_GAP_S, rename: str | None = None, first_index: int = 0) -> ImportResult:
    """Photos into ``out``: one folder per burst (``set_01``...), each photo copied unchanged with its sidecar
    and a nominal ``camera.toml``. ``rename``: put every photo straight into ``out`` as ``frame_NNNN`` numbered
    from ``first_index`` (a pair's ``real/``), no folders, no camera file. ``exposure_us``: a value for every
    photo, or a list with one per photo in the order given."""
    paths = expand_photos(items)
    values = _per_photo(exposure_us, len(paths))
    photos = [complete(read_photo(p), v, iso, auto) for p, v in zip(paths, values)]
    out = Path(out)
    result = ImportResult(out)
    groups = {"": sorted(photos, key=lambda p: (p.taken or "", p.path.name))} if rename else {
        f"set_{i:02d}": g for i, g in enumerate(bursts(photos, gap_s), 1)}
    plan = {folder: [(photo, out / folder / (f"{rename}{first_index + i:04d}{photo.path.suffix.lower()}" if rename
                                             else photo.path.name)) for i, photo in enumerate(group)]
            for folder, group in groups.items()}
    for folder, frames in plan.items():       # every clash is found before anything is written
        _check_names(groups[folder], rename)
        taken = [str(frame) for _, frame in frames if frame.exists() or sidecar_path(frame).exists()]
        if taken:
            raise ImportFailed(f"{taken[0]} already exists; import into a new --out folder")
    for folder, frames in plan.items():
        (out / folder).mkdir(parents=True, exist_ok=True)
        for i, (photo, frame) in enumerate(frames):
            shutil.copyfile(photo.path, frame)           # the camera's bytes, unchanged
            write_json(sidecar_path(frame), sidecar(photo, frame.name, first_index + i), indent=2)
        result.folders[folder] = [frame for _, frame in frames]
        if not rename:
            from .camera import camera_from_dict, write_toml
            first = frames[0][0]
            tables, _ = nominal_camera(first, f"{first.camera} {folder}")   # no [extrinsics]: unregistered
            camera = out / folder / "camera.toml"
            result.cameras[folder] = write_toml(camera_from_dict(tables, str(camera)), camera,
                                                "isu-validate capture import")
    if any(p.auto_exposure is None for p in photos):
        result.notes.append("some photos' EXIF records neither ExposureMode nor ExposureProgram: they were taken as "
                            "manual exposures (a bracket); re-import with --auto-exposure if the camera chose them")
    return result


def _per_photo(exposure_us, n: int) -> list:
    if exposure_us is None or isinstance(exposure_us, (int, float)):
        return [exposure_us] * n
    values = list(exposure_us)
    if len(values) == 1:
        return values * n
    if len(values) != n:
        raise InputError(f"--exposure-us gives {len(values)} values for {n} photos; give one for all or one per "
                         "photo, in the order the photos are named")
    return values


def _check_names(group: list[Photo], rename: str | None) -> None:
    if rename:
        return
    seen: dict[str, Path] = {}
    for p in group:
        if p.path.name in seen:
            raise ImportFailed(f"{seen[p.path.name]} and {p.path} have the same name and belong to one burst; "
                               "import them separately (into two --out folders)")
        seen[p.path.name] = p.path
