"""Which files are images: the one list of suffixes every image reader of isu-validate accepts.

Image sets, pairs, stylize inputs, calibration views and camera-model frames take these suffixes
(compared lower-case); the list is a contract (docs/ARCHITECTURE.md, "Image sets"). A leaf: imports
nothing of the project.
"""

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")
