"""The calibration solve: an OpenCV initial estimate refined by SciPy least squares.

Parameters are ``[intrinsics, (rvec, tvec) per frame]`` with the camera as the
reference frame and the boards moving, as in mrcal.  The refinement first runs with a
robust (Cauchy) loss so mis-detected corners cannot drag the solution, then rejects
corners whose residual is far beyond the estimated noise and re-solves with a plain
squared loss on the inliers, so that the final Jacobian gives an honest covariance.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.linalg import cho_factor, cho_solve
from threadpoolctl import threadpool_limits

from . import lens
from .board import Detection
from isu_validate.errors import UserError

MIN_CORNERS_PER_FRAME = 6


class CalibrationError(UserError, ValueError):
    """The data cannot be calibrated (too little of it, or no consistent solution)."""


@dataclass
class Solution:
    model: str
    image_size: tuple[int, int]
    intrinsics: np.ndarray              # [fx, fy, cx, cy, *distortion]
    rvecs: np.ndarray                   # (F,3) board-to-camera rotations
    tvecs: np.ndarray                   # (F,3) board-to-camera translations, metres
    detections: list[Detection]         # the frames used, same order as the poses
    inliers: list[np.ndarray]           # per frame, a bool per corner
    noise_px: float                     # per-axis observation noise estimated from the inlier residuals
    covariance: np.ndarray | None       # of all parameters; None when the data cannot determine them
    outlier_rounds: int = 0
    notes: list[str] = field(default_factory=list)

    @property
    def n_intrinsics(self) -> int:
        return len(self.intrinsics)

    def residuals(self) -> list[np.ndarray]:
        """Per frame, observed minus predicted pixels (N,2) for every corner, outliers included."""
        return [d.pixels - lens.project(self.model, self.intrinsics, d.board_points, r, t)
                for d, r, t in zip(self.detections, self.rvecs, self.tvecs)]

    def rms_px(self) -> float:
        res = np.concatenate([r[m] for r, m in zip(self.residuals(), self.inliers)])
        return float(np.sqrt(np.mean(np.sum(res ** 2, axis=1)))) if len(res) else float("nan")

    @property
    def n_corners(self) -> int:
        return int(sum(m.sum() for m in self.inliers))

    @property
    def n_outliers(self) -> int:
        return int(sum((~m).sum() for m in self.inliers))

    @property
    def intrinsics_covariance(self) -> np.ndarray | None:
        n = self.n_intrinsics
        return None if self.covariance is None else self.covariance[:n, :n]


# ---------------------------------------------------------------- initial estimate

def initial_estimate(model: str, detections: list[Detection], size: tuple[int, int]):
    """Intrinsics and per-frame poses close enough for the refinement to converge."""
    central = _central(detections, size) if model != "fisheye" else []
    try:
        if len(central) >= 3:
            # OpenCV's closed-form start assumes a distortion-free lens: on the corners near
            # the centre it finds the focal length (f = 294 px instead of 520 px was seen
            # from all corners of close, wide-angle views); poses then come from PnP.
            guess = _opencv_estimate(model, central, size)
            if guess is not None:
                poses = [pose_from_rays(model, guess[0], d) for d in detections]
                if all(p is not None for p in poses):
                    return guess[0], np.array([p[0] for p in poses]), np.array([p[1] for p in poses])
        guess = _opencv_estimate(model, detections, size)
        if guess is not None:
            return guess
    except cv2.error:
        pass  # OpenCV's own initialisation fails on degenerate views; fall through
    return _generic_estimate(model, detections, size)


def _central(detections, size, fraction: float = 0.6, min_corners: int = 8) -> list[Detection]:
    """Each view's corners within ``fraction`` of the half-diagonal from the image centre."""
    w, h = size
    limit = fraction * np.hypot(w, h) / 2
    out = []
    for d in detections:
        keep = np.linalg.norm(d.pixels - [(w - 1) / 2, (h - 1) / 2], axis=1) < limit
        if keep.sum() >= min_corners:
            out.append(Detection(d.source, d.image_size, d.ids[keep], d.pixels[keep], d.board_points[keep]))
    return out


def _opencv_estimate(model: str, detections, size):
    w, h = size
    if model == "fisheye":
        obj = [d.board_points.reshape(1, -1, 3) for d in detections]
        img = [d.pixels.reshape(1, -1, 2) for d in detections]
        flags = cv2.fisheye.CALIB_RECOMPUTE_EXTRINSIC | cv2.fisheye.CALIB_FIX_SKEW
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-9)
        _, K, D, rvecs, tvecs = cv2.fisheye.calibrate(obj, img, size, None, None, flags=flags, criteria=crit)
        intr = np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2], *np.ravel(D)[:4]])
    else:
        obj = [d.board_points.astype(np.float32) for d in detections]
        img = [d.pixels.astype(np.float32) for d in detections]
        # The initial solve fits only k1 k2 p1 p2; the rational terms start at zero and
        # are left to the refinement, which is far less prone to diverging with them.
        flags = cv2.CALIB_FIX_K3
        if model == "pinhole":
            flags |= cv2.CALIB_FIX_K1 | cv2.CALIB_FIX_K2 | cv2.CALIB_ZERO_TANGENT_DIST
        _, K, D, rvecs, tvecs = cv2.calibrateCamera(obj, img, size, None, None, flags=flags)
        D = np.ravel(D)
        dist = [] if model == "pinhole" else [*D[:5], 0.0, 0.0, 0.0]
        intr = np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2], *dist])
    rvecs = np.array([np.ravel(r) for r in rvecs])
    tvecs = np.array([np.ravel(t) for t in tvecs])
    plausible = (np.all(np.isfinite(intr)) and 0 < intr[0] < 50 * w and 0 < intr[1] < 50 * w
                 and -w < intr[2] < 2 * w and -h < intr[3] < 2 * h and np.all(tvecs[:, 2] > 0))
    return (intr, rvecs, tvecs) if plausible else None


def _generic_estimate(model: str, detections, size):
    """Try a few focal lengths with a centred principal point; keep the one that fits best."""
    w, h = size
    candidates = [w / 2.0, float(w), 2.0 * w]
    if model == "fisheye":
        candidates.insert(0, h / np.pi)  # a 180-degree image circle across the image height
    try:
        K0 = cv2.initCameraMatrix2D([d.board_points.astype(np.float32) for d in detections],
                                    [d.pixels.astype(np.float32) for d in detections], size)
        if np.isfinite(K0[0, 0]) and 0 < K0[0, 0] < 50 * w:
            candidates.insert(0, float(K0[0, 0]))
    except cv2.error:
        pass
    best, best_cost = None, np.inf
    for f in candidates:
        intr = np.array([f, f, (w - 1) / 2, (h - 1) / 2] + [0.0] * lens.N_DISTORTION[model])
        poses = [pose_from_rays(model, intr, d) for d in detections]
        if any(p is None for p in poses):
            continue
        rvecs, tvecs = np.array([p[0] for p in poses]), np.array([p[1] for p in poses])
        masks = [np.ones(len(d), bool) for d in detections]
        x0 = np.concatenate([intr, np.column_stack([rvecs, tvecs]).ravel()])
        # A short fit with only focal length, centre and k1 k2 free ranks the candidates;
        # the full solve that follows does the rest.
        frozen = list(range(6, len(intr))) if model == "opencv8" else []
        x = _refine(model, detections, masks, *_split(x0, model, len(detections)), max_iter=25, frozen=frozen)
        cost = np.sum(_residual_vector(model, detections, masks, x) ** 2) + np.sum(_prior_residuals(model, x) ** 2)
        if cost < best_cost:
            best, best_cost = x, cost
    if best is None:
        raise CalibrationError("could not find a starting point for the solve: no board pose could be "
                               "estimated; check the board spec matches the printed board")
    return _split(best, model, len(detections))


def pose_from_rays(model: str, intrinsics, det: Detection):
    """Board pose from one view with known intrinsics (any lens model): PnP on unprojected rays."""
    rays = lens.unproject(model, intrinsics, det.pixels)
    ok = np.all(np.isfinite(rays), axis=1) & (rays[:, 2] > 0.05)
    if ok.sum() < 4:
        return None
    norm = rays[ok, :2] / rays[ok, 2:3]
    found, rvec, tvec = cv2.solvePnP(det.board_points[ok], norm, np.eye(3), None, flags=cv2.SOLVEPNP_IPPE)
    if not found:
        return None
    return np.ravel(rvec), np.ravel(tvec)


# ---------------------------------------------------------------- refinement

def _split(x, model, n_frames):
    ni = lens.n_intrinsics(model)
    poses = x[ni:].reshape(n_frames, 6)
    return x[:ni].copy(), poses[:, :3].copy(), poses[:, 3:].copy()


# mrcal-style regularisation: a weak zero-mean prior on the radial/rational distortion
# terms.  OpenCV's rational model is degenerate on its own (numerator k1-k3 trade
# against denominator k4-k6: condition numbers of 1e12-1e17 were measured on rendered
# boards); one "pixel" of cost per unit of coefficient is negligible next to thousands
# of corner residuals, yet it pins the directions the data cannot see.
PRIOR_SIGMA = 1.0
_PRIOR_INDICES = {"pinhole": [], "opencv8": [4, 5, 8, 9, 10, 11], "fisheye": [4, 5, 6, 7]}


def _prior_residuals(model, x) -> np.ndarray:
    return x[_PRIOR_INDICES[model]] / PRIOR_SIGMA


def _add_prior(model, x, A, g) -> None:
    idx = _PRIOR_INDICES[model]
    A[idx, idx] += 1.0 / PRIOR_SIGMA ** 2
    g[idx] += x[idx] / PRIOR_SIGMA ** 2


def _residual_vector(model, detections, masks, x):
    intr, rvecs, tvecs = _split(x, model, len(detections))
    parts = [(lens.project(model, intr, d.board_points[m], r, t) - d.pixels[m]).ravel()
             for d, m, r, t in zip(detections, masks, rvecs, tvecs)]
    return np.concatenate(parts)


def _normal_equations(model, detections, masks, x, weights=None):
    """J^T W J and J^T W r, assembled frame by frame.

    Each frame's residuals depend only on the intrinsics and that frame's pose, so the
    normal matrix is built from small blocks (never the full 2N x P Jacobian): milliseconds
    instead of the 0.1-0.6 s a dense product or SVD takes for 40 frames on this machine.
    """
    intr, rvecs, tvecs = _split(x, model, len(detections))
    ni = len(intr)
    A = np.zeros((len(x), len(x)))
    g = np.zeros(len(x))
    for f, (d, m, r, t) in enumerate(zip(detections, masks, rvecs, tvecs)):
        px, j_intr, j_pose = lens.project(model, intr, d.board_points[m], r, t, jacobian=True)
        n = 2 * int(m.sum())
        Ji, Jp, res = j_intr.reshape(n, ni), j_pose.reshape(n, 6), (px - d.pixels[m]).ravel()
        if weights is not None:  # one weight per corner, applied to its x and y residual
            w = np.repeat(weights[f][m], 2)
            Ji, Jp, res = Ji * w[:, None], Jp * w[:, None], res * w  # w holds sqrt(weight)
        o = ni + 6 * f
        A[:ni, :ni] += Ji.T @ Ji
        A[:ni, o:o + 6] = Ji.T @ Jp
        A[o:o + 6, :ni] = A[:ni, o:o + 6].T
        A[o:o + 6, o:o + 6] = Jp.T @ Jp
        g[:ni] += Ji.T @ res
        g[o:o + 6] = Jp.T @ res
    _add_prior(model, x, A, g)
    return A, g


def _refine(model, detections, masks, intr, rvecs, tvecs, weights=None, max_iter=200, frozen=()):
    """Least squares from the given start; ``weights`` (per frame, per corner) scale each corner's squared residual."""
    x0 = np.concatenate([intr, np.column_stack([rvecs, tvecs]).ravel()])
    sw = None if weights is None else [np.sqrt(w) for w in weights]
    flat_sw = None if sw is None else np.concatenate([np.repeat(w[m], 2) for w, m in zip(sw, masks)])

    def cost(x):
        r = _residual_vector(model, detections, masks, x)
        r = r if flat_sw is None else r * flat_sw
        p = _prior_residuals(model, x)
        return float(r @ r + p @ p)

    def normal(x):
        A, g = _normal_equations(model, detections, masks, x, sw)
        if len(frozen):  # a frozen parameter gets an identity row and a zero gradient: its step is 0
            A[frozen, :] = 0.0
            A[:, frozen] = 0.0
            A[frozen, frozen] = 1.0
            g[frozen] = 0.0
        return A, g

    return levenberg_marquardt(cost, normal, x0, max_iter)


def levenberg_marquardt(cost, normal_equations, x0, max_iter: int = 200, rtol: float = 1e-7) -> np.ndarray:
    """Levenberg-Marquardt on the normal equations, with Marquardt's diagonal scaling.

    Why not scipy.optimize.least_squares: on a 40-frame calibration (5400 x 252 Jacobian)
    its trust-region solver spends 0.6 s per step in an SVD and MINPACK's unblocked QR
    is no faster: 30-70 s per solve on this 2-core machine.  The block-built normal
    equations solve in milliseconds; their conditioning is checked in _covariance.
    """
    x = np.asarray(x0, dtype=np.float64).copy()
    c = cost(x)
    lam = 1e-3
    for _ in range(max_iter):
        A, g = normal_equations(x)
        diag = np.maximum(np.diag(A), 1e-12 * max(np.diag(A).max(), 1e-12))
        while True:
            try:
                step = -cho_solve(cho_factor(A + lam * np.diag(diag)), g)
                c_new = cost(x + step)
            except np.linalg.LinAlgError:
                c_new = np.inf
            if np.isfinite(c_new) and c_new <= c:
                break
            lam *= 10.0
            if lam > 1e10:
                return x  # no step reduces the cost: at a minimum to working precision
        x = x + step
        converged = c - c_new <= rtol * max(c, 1e-300)
        c = c_new
        lam = max(lam / 10.0, 1e-12)
        if converged:
            break
    return x


# Parameters held at zero while the solve finds its basin: from a rough start, OpenCV's
# rational terms k4-k6 let LM crawl along their degenerate valley (200 iterations and a
# 10 px RMS local minimum were seen on close, partly visible boards) instead of fixing
# focal length and poses first.
STAGED_FROZEN = {"opencv8": [9, 10, 11]}


def _robust_start(model, frames, masks, x, scale_px: float, rounds: int = 4):
    """Iteratively reweighted least squares with the Cauchy loss rho(s) = c^2 log(1 + s/c^2).

    Its weight 1 / (1 + r^2/c^2) shrinks gross mis-detections to nearly nothing, so they
    stand out clearly for the rejection that follows instead of bending the solution.
    """
    for i in range(rounds):
        intr, rvecs, tvecs = _split(x, model, len(frames))
        weights = []
        for d, r, t in zip(frames, rvecs, tvecs):
            err = np.linalg.norm(lens.project(model, intr, d.board_points, r, t) - d.pixels, axis=1)
            weights.append(1.0 / (1.0 + (err / scale_px) ** 2))
        frozen = STAGED_FROZEN.get(model, []) if i < rounds // 2 else []
        x = _refine(model, frames, masks, intr, rvecs, tvecs, weights=weights, max_iter=50, frozen=frozen)
    return x


def robust_sigma(residuals: np.ndarray) -> float:
    """Per-axis noise from (N,2) residuals, by the median absolute deviation (outliers barely move it)."""
    if len(residuals) == 0:
        return float("nan")
    return float(1.4826 * np.median(np.abs(residuals - np.median(residuals, axis=0))))


def solve(model: str, detections: list[Detection], size: tuple[int, int], **options) -> Solution:
    """Calibrate ``model`` from board detections that all share one image size.

    Options: ``outlier_sigma`` (reject corners beyond this many noise sigmas, default 4),
    ``noise_floor_px`` (never assume less noise than this when rejecting, 0.05),
    ``robust_scale_px`` (the Cauchy loss scale, 1.0), ``start`` (intrinsics, rvecs, tvecs).
    """
    # The matrices here are a few hundred wide: multi-threaded BLAS only adds
    # synchronisation, 4x slower on a loaded 2-core machine (measured).
    with threadpool_limits(1, user_api="blas"):
        return _solve(model, detections, size, **options)


# More rejected corners than this means the solve found a wrong basin, not bad corners.
SUSPECT_OUTLIER_FRACTION = 0.1


def _solve(model: str, detections: list[Detection], size: tuple[int, int], *, start=None, **options) -> Solution:
    lens.check_model(model)
    frames = [d for d in detections if len(d) >= MIN_CORNERS_PER_FRAME]
    if not frames:
        raise CalibrationError(f"no image has at least {MIN_CORNERS_PER_FRAME} board corners; "
                               "check the board spec and that the board is in view and in focus")
    if start is not None:
        return _solve_from(model, frames, size, start, **options)
    sol = _solve_from(model, frames, size, initial_estimate(model, frames, size), **options)
    if sol.n_outliers > SUSPECT_OUTLIER_FRACTION * (sol.n_corners + sol.n_outliers):
        # OpenCV's initialisation can land in a wrong basin (f = 294 px for a 520 px lens was
        # seen with close, partly visible boards): try the generic starts and keep the better.
        try:
            alt = _solve_from(model, frames, size, _generic_estimate(model, frames, size), **options)
        except CalibrationError:
            return sol
        if (alt.n_outliers, alt.rms_px()) < (sol.n_outliers, sol.rms_px()):
            alt.notes.append("OpenCV's initial estimate led to a worse solution; a generic start was used")
            return alt
    return sol


def _solve_from(model, frames, size, start, *, outlier_sigma: float = 4.0, noise_floor_px: float = 0.05,
                robust_scale_px: float = 1.0, max_rounds: int = 6) -> Solution:
    intr, rvecs, tvecs = start
    masks = [np.ones(len(d), bool) for d in frames]
    x = _robust_start(model, frames, masks, np.concatenate([intr, np.column_stack([rvecs, tvecs]).ravel()]),
                      scale_px=robust_scale_px)
    rounds = 0
    for rounds in range(1, max_rounds + 1):  # noqa: B007 (the rounds taken are reported)
        sol_res = [d.pixels - lens.project(model, x[:len(intr)], d.board_points, *p)
                   for d, p in zip(frames, _poses(x, model, len(frames)))]
        inlier_res = np.concatenate([r[m] for r, m in zip(sol_res, masks)])
        threshold = outlier_sigma * max(robust_sigma(inlier_res), noise_floor_px)
        new_masks = [np.linalg.norm(r, axis=1) <= threshold for r in sol_res]
        changed = any((a != b).any() for a, b in zip(new_masks, masks))
        masks = new_masks
        x = _refine(model, frames, masks, *_split(x, model, len(frames)))
        if not changed:
            break
    frames, masks, x = _drop_thin_frames(model, frames, masks, x)
    intr, rvecs, tvecs = _split(x, model, len(frames))
    noise, cov, notes = _covariance(model, frames, masks, x)
    return Solution(model, size, intr, rvecs, tvecs, frames, masks, noise, cov, rounds, notes)


def _poses(x, model, n):
    _, r, t = _split(x, model, n)
    return list(zip(r, t))


def _drop_thin_frames(model, frames, masks, x):
    """Frames left with too few inliers determine no pose; leave them out and re-solve."""
    keep = [i for i, m in enumerate(masks) if m.sum() >= MIN_CORNERS_PER_FRAME]
    if len(keep) == len(frames):
        return frames, masks, x
    if not keep:
        raise CalibrationError("every frame lost its corners as outliers: the board spec may not match the board")
    intr, rvecs, tvecs = _split(x, model, len(frames))
    frames = [frames[i] for i in keep]
    masks = [masks[i] for i in keep]
    return frames, masks, _refine(model, frames, masks, intr, rvecs[keep], tvecs[keep])


def _covariance(model, frames, masks, x):
    """Observation noise and the parameter covariance sigma^2 (J^T J + prior)^-1 at the solution."""
    r = _residual_vector(model, frames, masks, x)
    JtJ, _ = _normal_equations(model, frames, masks, x)
    dof = len(r) - len(x)
    notes = []
    if dof <= 0:
        return float("nan"), None, [f"{len(r)} residuals cannot determine {len(x)} parameters"]
    noise = float(np.sqrt(np.sum(r ** 2) / dof))
    # Scale to unit diagonal first: focal lengths (~500) and rotations (~1) differ by
    # orders of magnitude, and only the scaled matrix's conditioning says anything.
    d = np.sqrt(np.diag(JtJ))
    if np.any(d == 0):
        return noise, None, ["some parameters have no effect on any observation"]
    scaled = JtJ / np.outer(d, d)
    if np.linalg.cond(scaled) > 1e14:  # the rational model alone reaches ~1e12 (k1-k3 vs k4-k6)
        return noise, None, ["the normal equations are singular: the views cannot determine all parameters"]
    cov = np.linalg.inv(scaled) / np.outer(d, d) * noise ** 2
    return noise, cov, notes
