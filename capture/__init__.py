"""Cameras for the sim-to-real half of isu-validate: capture frames, calibrate, register.

Nothing here imports the renderer (``isu_validate.render``): the renderer imports the camera from here,
and what needs a render (the stand-in source, ``exposure chart``) is handed one by its command.

One module per concept:

- ``sources/``: the frame-source interface and its V4L2, DepthAI, replay and stand-in implementations
  (``open_source(spec)``); ``discovery``: ``capture list``; ``session``: ``capture shoot``.
- ``sidecar``: the one reader of a frame's sidecar, and of whether the frame is a stand-in render
  (``provenance``: how many frames taken for reality are stand-ins; ``banner``: the line that says so).
- ``board``: ChArUco board specs and detection (OpenCV 4.14's new ArUco API).
- ``camera``: the camera (``Camera``) and the one reader/writer of the camera file, the contract
  that calibration writes and the renderer renders through (TOML, JSON); ``mrcal_file``: mrcal's
  ``.cameramodel`` export.
- ``lens``: pinhole / opencv8 / fisheye projection and unprojection, with Jacobians (the one place
  that calls OpenCV's projection); ``lens_models``: the one list of lens models (light: no OpenCV).
- ``solve``: OpenCV initial estimate, robust least-squares refinement, outlier rejection, covariance.
- ``uncertainty``: projection uncertainty propagated from the observation noise (mrcal's method).
- ``projection_diff``: differencing two calibrations (cross-validation, ``calibrate diff``).
- ``checks``: warnings when the data cannot support the model.
- ``calibrate``: images to camera file; ``report``: the HTML report; ``registration``: the camera's
  pose in the cabin from ArUco markers.
- ``synthetic``: data with a known truth (tests, ``bench calib``).
- ``camera_model/``: the camera's imaging model (auto-exposure, response, noise, colour) kept in the
  camera file: fitted from captures, applied to renders (``isu-validate exposure``, ``bench exposure``).
"""
