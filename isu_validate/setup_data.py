"""One-time data setup, run by the Makefile after installing: WordNet for METEOR, and the anny
body model's built data (the people in the renders).

anny builds its model data on first use (about 75 s and 2 GB on two cores, ~824 MB on disk); setup
does it once into ``ANNY_CACHE_DIR`` (default ``<sys.prefix>/share/anny``, inside the virtual
environment), where every run reads it, so no user's first run pays for it.

nltk's WordNet reader wants ``<nltk_data>/corpora/wordnet`` with the WordNet 3.0
database files plus a ``lexnames`` table.  Debian's ``wordnet-base`` and
``wordnet-sense-index`` put the database under ``/usr/share/wordnet`` but ship no
``lexnames`` (and nltk must not download at run time), so we copy the files into
an nltk_data folder inside the virtual environment (``sys.prefix/nltk_data``,
which nltk searches by default) and write the standard 45-line table ourselves.
Files are copied, not linked: nltk's reader resolves the corpus root and rejects
links into other trees on some versions.

Idempotent and quick: files already present with the same size are left alone.

    python -m isu_validate.setup_data [--target DIR] [--source DIR] [--skip-anny]
"""
from __future__ import annotations

import argparse
import os
import shutil
import sys
from pathlib import Path

from .atomic import atomic_path

DEBIAN_WORDNET = Path("/usr/share/wordnet")

# The files nltk's WordNetCorpusReader opens (data/index per part of speech,
# morphological exception lists, the sense index, verb frames and counts).
WORDNET_FILES = [f"{kind}.{pos}" for kind in ("data", "index") for pos in ("noun", "verb", "adj", "adv")] + [
    f"{pos}.exc" for pos in ("noun", "verb", "adj", "adv")] + ["index.sense", "cntlist.rev", "frames.vrb",
                                                                "sentidx.vrb", "sents.vrb"]
REQUIRED = [f"{kind}.{pos}" for kind in ("data", "index") for pos in ("noun", "verb", "adj", "adv")]

# WordNet 3.0 lexicographer files (lexnames(5WN)): number, name, syntactic category
# (1 noun, 2 verb, 3 adjective, 4 adverb).
_LEXNAMES = """adj.all 3|adj.pert 3|adv.all 4|noun.Tops 1|noun.act 1|noun.animal 1|noun.artifact 1|
noun.attribute 1|noun.body 1|noun.cognition 1|noun.communication 1|noun.event 1|noun.feeling 1|noun.food 1|
noun.group 1|noun.location 1|noun.motive 1|noun.object 1|noun.person 1|noun.phenomenon 1|noun.plant 1|
noun.possession 1|noun.process 1|noun.quantity 1|noun.relation 1|noun.shape 1|noun.state 1|noun.substance 1|
noun.time 1|verb.body 2|verb.change 2|verb.cognition 2|verb.communication 2|verb.competition 2|
verb.consumption 2|verb.contact 2|verb.creation 2|verb.emotion 2|verb.motion 2|verb.perception 2|
verb.possession 2|verb.social 2|verb.stative 2|verb.weather 2|adj.ppl 3"""


def lexnames_text() -> str:
    entries = [e.strip().split() for e in _LEXNAMES.replace("\n", "").split("|")]
    return "".join(f"{i:02d}\t{name}\t{cat}\n" for i, (name, cat) in enumerate(entries))


def default_nltk_data() -> Path:
    """The project's nltk_data folder: inside the active environment (nltk searches it)."""
    return Path(os.environ.get("ISU_VALIDATE_NLTK_DATA", Path(sys.prefix) / "nltk_data"))


def wordnet_dir(nltk_data: Path | None = None) -> Path:
    return (nltk_data or default_nltk_data()) / "corpora" / "wordnet"


def wordnet_ready(nltk_data: Path | None = None) -> bool:
    target = wordnet_dir(nltk_data)
    return all((target / name).is_file() for name in REQUIRED + ["lexnames"])


def install_wordnet(nltk_data: Path | None = None, source: Path = DEBIAN_WORDNET) -> Path:
    """Copy WordNet into ``<nltk_data>/corpora/wordnet``; return that folder."""
    target = wordnet_dir(nltk_data)
    missing = [name for name in REQUIRED if not (source / name).is_file()]
    if missing and not wordnet_ready(nltk_data):
        raise FileNotFoundError(
            f"WordNet is not installed under {source} (missing {', '.join(missing)}); METEOR needs it. "
            "Install the Debian packages: sudo apt-get install wordnet-base wordnet-sense-index "
            "(scripts/setup_system.sh does this), then run: python -m isu_validate.setup_data")
    target.mkdir(parents=True, exist_ok=True)
    for name in WORDNET_FILES:
        src, dst = source / name, target / name
        if src.is_file() and not (dst.is_file() and dst.stat().st_size == src.stat().st_size):
            with atomic_path(dst) as tmp:  # a parallel reader never sees half a file
                shutil.copyfile(src, tmp)
    lexnames = target / "lexnames"
    if not lexnames.is_file() or lexnames.read_text() != lexnames_text():
        lexnames.write_text(lexnames_text())
    return target


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m isu_validate.setup_data", description=__doc__.split("\n")[0])
    parser.add_argument("--target", type=Path, default=None,
                        help="nltk_data folder (default: %(default)s -> sys.prefix/nltk_data)")
    parser.add_argument("--source", type=Path, default=DEBIAN_WORDNET, help="WordNet 3.0 database folder")
    parser.add_argument("--skip-anny", action="store_true", help="do not build the anny body model's data")
    args = parser.parse_args(argv)
    try:
        where = install_wordnet(args.target, args.source)
    except FileNotFoundError as exc:
        print(f"setup_data: error: {exc}", file=sys.stderr)
        return 2
    print(f"WordNet ready for METEOR in {where}")
    if not args.skip_anny:
        print(f"anny body model ready in {build_anny()}")
    return 0


def build_anny() -> Path:
    """Build anny's model data into its cache unless it is there already (then this is instant)."""
    from .render.people.model import anny_cache_dir, build_cache, model_cached
    if model_cached():
        return anny_cache_dir()
    print(f"building the anny body model into {anny_cache_dir()} (once; about 75 s and 2 GB)...", flush=True)
    return build_cache()


if __name__ == "__main__":
    sys.exit(main())
