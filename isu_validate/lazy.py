"""Packages whose public names load on first use (PEP 562), so that importing them stays cheap: the
command line reads a package's light names for ``--help`` without loading torch, pymoo or Blender."""
from __future__ import annotations

import importlib
import sys


def lazy_names(package: str, names: dict[str, str]):
    """``__getattr__`` and ``__dir__`` for ``package``: ``names`` maps each public name to the module
    (absolute, or relative to ``package`` with a leading dot) that defines it under the same name.

    Usage, at the end of a package's ``__init__.py``::

        __getattr__, __dir__ = lazy_names(__name__, {"run_search": ".loop"})
    """
    def __getattr__(name: str):
        module = names.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, package), name)
        setattr(sys.modules[package], name, value)   # the next lookup finds it without this hook
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(names))

    return __getattr__, __dir__
