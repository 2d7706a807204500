"""The embedded reference ISU: a small, real, offline scene understanding system."""
from .model import ReferenceISU, default_model_dir

__all__ = ["ReferenceISU", "default_model_dir"]
