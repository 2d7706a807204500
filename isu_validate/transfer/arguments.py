"""The options that name real photo sets and how they are read: one definition for ``transfer`` and
``bench transfer`` (argparse only; nothing heavy is imported)."""
from __future__ import annotations

from ..devices import add_device_argument


def add_real_set_arguments(p) -> None:
    """The real sets and how they are read and asked: shared by ``transfer`` and ``bench transfer``."""
    p.add_argument("real", nargs="+", metavar="REAL",
                   help="labelled real photo set: class folders, YOLO (data.yaml), COCO .json or CSV")
    p.add_argument("--labels", action="append", required=True, metavar="MAP.toml",
                   help="label map: one for every set, or one per set in order")
    p.add_argument("--layout", choices=("classes", "yolo", "coco", "csv"),
                   help="the sets' layout (default: told from the files)")
    p.add_argument("--skip-conflicts", action="store_true",
                   help="leave a photo out of a feature its labels answer two ways (counted), instead of stopping")
    p.add_argument("--groups", action="append", default=[], metavar="SET=CSV",
                   help="which photos of SET (its folder name) belong together (a CSV of image and group: driver, "
                        "clip): intervals then resample whole groups (repeatable)")
    p.add_argument("--limit", type=int,
                   help="ask about N labelled photos of each set only, spread evenly through it (a quick look)")
    p.add_argument("--space", default="isu-paper", help="scene space whose questions are asked (default isu-paper)")
    p.add_argument("--seed", type=int, default=0, help="seed of the bootstrap and of KID's subsets (default 0)")
    p.add_argument("--zero-shot", action="store_true",
                   help="also score every photo and render for the object a YES shows (phone in hand: a phone) with "
                        "ImageNet classes over 25 crops, no training: its AUC on the photos beside the renders' says "
                        "whether the rendered object reads as the real one (25 classifier passes a frame: 1.1 s on "
                        "one CPU thread, 0.7 s on two); where the built-in COCO detector has the object's class "
                        "(phone: 'cell phone'), its score too: what a detector alone does, nothing learnt from renders")
    add_device_argument(p)


def parse_groups(pairs: list[str]) -> dict[str, str]:
    """``--groups SET=CSV`` options as {set: csv}."""
    from ..errors import InputError

    out = {}
    for pair in pairs:
        name, sep, path = pair.partition("=")
        if not sep or not name or not path:
            raise InputError(f"--groups {pair!r} must read SET=CSV (SET: a real set's folder name)")
        out[name] = path
    return out
