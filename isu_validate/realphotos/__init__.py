"""Labelled real photographs: the layouts people keep them in, and what their labels say in the scene space.

A real photo set is read in one place (``layouts``): class folders, YOLO (``data.yaml`` + ``images/`` +
``labels/``), COCO JSON, or a CSV of image and label. A label map (``label_map``, TOML) says what each
real label means as answers to the scene space's questions; ``labelled`` puts the two together. Nothing
here trains on the photos: they are read to measure (``isu-validate transfer``, ``recognise --real``).
"""
from .label_map import LabelMap, load_label_map
from .labelled import LabelledPhoto, LabelledSet, label_photos
from .layouts import Box, Photo, PhotoSet, read_photo_set

__all__ = ["Box", "LabelMap", "LabelledPhoto", "LabelledSet", "Photo", "PhotoSet", "label_photos",
           "load_label_map", "read_photo_set"]
