"""Benchmarks: one module per ``isu-validate bench NAME``, named after it, each printing speed against
error. ``render`` (presets), ``faces`` (the driver's expression per preset), ``calib`` (calibration),
``search`` (search overhead), ``effectiveness`` (failure rates against random search; a package: the
harness, emulated SUTs, the known-risk bound), ``evaluate`` (judge cost), ``fid`` (FID/KID numerics),
``nst`` (style transfer), ``exposure`` (imaging-model fits). Benchmarks sit above the domain packages:
they import them, nothing below imports a benchmark."""
