"""Cameras for the sim-to-real half of isu-validate: capture frames, calibrate, register.

One module per concept:

- ``sources/``: the frame-source interface and its V4L2, DepthAI and replay implementations
  (``open_source(spec)``); ``discovery``: ``capture list``; ``session``: ``capture shoot``.
- ``board``: ChArUco board specs and detection (OpenCV 4.14's new ArUco API).
- ``lens``: pinhole / opencv8 / fisheye projection and unprojection, with Jacobians.
- ``solve``: OpenCV initial estimate, robust least-squares refinement, outlier rejection, covariance.
- ``uncertainty``: projection uncertainty propagated from the observation noise (mrcal's method).
- ``projection_diff``: differencing two calibrations (cross-validation, ``calibrate diff``).
- ``checks``: warnings when the data cannot support the model.
- ``calibrate``: images to camera file; ``report``: the HTML report; ``camera_file``: the
  camera file contract (TOML, JSON, mrcal ``.cameramodel``); ``registration``: the camera's
  pose in the cabin from ArUco markers.
- ``synthetic``: data with a known truth (tests, ``bench calib``); ``bench``: ``bench calib``.
- ``camera_model/``: the camera's imaging model (auto-exposure, response, noise, colour) kept in the
  camera file: fitted from captures, applied to renders (``isu-validate exposure``, ``bench exposure``).
"""
