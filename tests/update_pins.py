"""Recompute the pinned reference values deliberately and rewrite ``tests/data/pins/*.json``.

  PYTHONPATH=. .venv/bin/python -m tests.update_pins                        # every pin
  PYTHONPATH=. .venv/bin/python -m tests.update_pins reference_isu          # after retraining the shipped reference ISU
  PYTHONPATH=. .venv/bin/python -m tests.update_pins reference_isu --render # ... for a changed scene space

Prints each value that moves beyond its tolerance as ``old -> new`` before writing, so the
change can be read and justified in the commit that carries it.  ``--render`` first renders
the reference ISU's test images again: the first scenes of the model card's held-out set,
with the card's render preset (needed when the scene space changed, so that the label files
name the space's features; a renderer change alone moves nothing and needs no re-render).
"""
from __future__ import annotations

import argparse
import json
import sys

from tests import pins


def render_reference_images(n: int = pins.N_RENDERS) -> None:
    import numpy as np

    from isu_validate.reference.training import balanced_scenes
    from isu_validate.render import open_renderer
    from isu_validate.space import load_space

    card = pins.model_card()
    space = load_space(card["space"])
    held_out = balanced_scenes(space, card["held_out_scenes"], np.random.default_rng(card["seed"] + 10_000))
    pins.RENDERS.mkdir(parents=True, exist_ok=True)
    for old in pins.RENDERS.iterdir():
        old.unlink()
    with open_renderer(preset=card["render_preset"], space=space) as renderer:
        for i, scene in enumerate(held_out[:n]):
            renderer.render(scene, pins.RENDERS / f"{i:02d}.png")
            print(f"rendered {i + 1}/{n}", file=sys.stderr)


def update(name: str) -> None:
    pin = pins.PINS[name]
    new = pins.record(pin, pin.compute())
    path = pins.pin_path(name)
    if path.exists():
        old = json.loads(path.read_text())
        moved = pins.differences(old["values"], new["values"], pin.rel, pin.abs)
        noise = pins.differences(old["values"], new["values"], 0.0, 0.0)
        inputs = pins.changed_inputs(pin, old)
        print(f"{name}: {len(moved)} value(s) moved beyond the tolerance, {len(noise) - len(moved)} within it"
              + (f"; {len(inputs)} input file(s) changed" if inputs else ""))
        for line in inputs + moved:
            print(f"  {line}")
    else:
        print(f"{name}: new pin")
    path.write_text(json.dumps(new, indent=1) + "\n")
    print(f"  wrote {path}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.update_pins", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("names", nargs="*", metavar="NAME",
                        help=f"pins to update (default all: {', '.join(pins.PINS)})")
    parser.add_argument("--render", action="store_true", help="render the reference ISU's test images again first")
    args = parser.parse_args(argv)
    unknown = [n for n in args.names if n not in pins.PINS]
    if unknown:
        parser.error(f"unknown pin(s) {', '.join(unknown)}; pins: {', '.join(pins.PINS)}")
    from tests.conftest import few_threads

    with few_threads():
        if args.render:
            render_reference_images()
        for name in args.names or list(pins.PINS):
            update(name)
    return 0


if __name__ == "__main__":
    sys.exit(main())
