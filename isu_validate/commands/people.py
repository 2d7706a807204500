"""``isu-validate people warm|check``: fill the cache of posed people; measure every body against the cabin."""
from __future__ import annotations

import sys


def register(sub) -> None:
    parser = sub.add_parser("people", help="the anny people of the renders: warm their cache, check their poses")
    act = parser.add_subparsers(dest="people_command", metavar="ACTION")
    warm = act.add_parser("warm", help="pose every driver and child into the people cache (so runs never load anny)")
    check = act.add_parser("check", help="clearances to seat and wheel, belt on the body, phone in the palm")
    for p in (warm, check):
        p.add_argument("--cabin", default="default", help="cabin rig name or .toml path (default: default)")
        p.add_argument("--limit", type=int, help="only this many drivers, spread evenly over all 704")
        p.add_argument("--cache", help="people cache folder (default: $ISU_PEOPLE_CACHE or beside anny's cache)")
    warm.set_defaults(func=cmd_warm)
    check.set_defaults(func=cmd_check)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)


def _people(args):
    from ..render.cabin import load_cabin
    from ..render.people import People, PeopleStore
    return People(load_cabin(args.cabin), PeopleStore(args.cache) if args.cache else None)


def cmd_warm(args) -> int:
    from ..render.people.warm import warm
    people = _people(args)
    counts = warm(people, args.limit)
    print(f"people cache {people.store.root}: {counts['drivers']} drivers and {counts['children']} children, "
          f"{counts['outfits']} outfits, "
          f"{counts['posed']} entries posed now (the rest were cached)")
    return 0


def cmd_check(args) -> int:
    from ..render.people.warm import check
    worst = check(_people(args), args.limit)
    print(f"{'measure':<32} {'worst':>9}  body")
    for name, (value, key) in sorted(worst.items()):
        if name.endswith("_resting"):
            shown, unit = f"{value:.2f}", ""
        elif name.endswith("_touch"):      # a count of vertices
            shown, unit = f"{value:.0f}", " vertices"
        else:
            shown, unit = f"{value * 1000:.1f}", " mm"
        print(f"{name:<32} {shown:>9}{unit}  {' '.join(str(k) for k in key if k is not None)}", file=sys.stdout)
    return 0
