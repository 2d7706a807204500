"""The camera's imaging model: auto-exposure, response and white balance, noise, colour correction.

One module per concept:

- ``model``: the model's parts and the camera-file tables they live in (the one reader/writer of them);
- ``apply``: the pure function the renderer's host side calls on a linear render (``metering`` meters);
- ``frames``: captured frames with sidecars; ``response_fit`` (Debevec via colour-hdri),
  ``exposure_fit``, ``noise_fit``; ``fit``: all of them from a capture session (``exposure fit``);
- ``chart``: the ColorChecker (reference, detection, sampling); ``colour_fit``: the correction and
  dE2000; ``colour_align``: ``exposure colour``; ``virtual_chart``: the chart's board, texture and pose
  for ``exposure chart`` (drawn by ``isu_validate/render/virtual_chart.py``);
- ``develop``: ``exposure apply`` on saved EXRs and runs; ``check``: ``exposure check``;
- ``synthetic``: cameras with known parameters (``bench exposure``).

Nothing here imports the renderer; the sRGB curve and the EXR format are leaves of their own
(``isu_validate/srgb.py``, ``isu_validate/exr.py``).
"""
from .model import AutoExposure, ColourCorrection, ImagingModel, ImagingModelError, Noise, Response

# the apply function lives in ``capture.camera_model.apply`` (not re-exported: it would hide that module)
__all__ = ["AutoExposure", "ColourCorrection", "ImagingModel", "ImagingModelError", "Noise", "Response"]
