"""``reference``: the embedded offline reference ISU (``isu_validate.reference``).

Imported lazily: it loads torch and the backbone, which other SUTs never need.
"""
from __future__ import annotations

from typing import Any


def open_reference(target: str, **kwargs: Any):
    from ...reference.adapter import ReferenceAdapter

    return ReferenceAdapter(target, **kwargs)
