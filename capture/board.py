"""ChArUco boards: the ``charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT`` spec and corner detection.

Detection uses only OpenCV's new ArUco API (``CharucoDetector.detectBoard``); OpenCV
4.11-4.13 place every ChArUco corner about half a pixel off, hence the 4.14 pin.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import cv2
import numpy as np

from isu_validate.errors import InputError

SPEC_HELP = "charuco:COLSxROWS:SQUARE_M:MARKER_M:DICT, e.g. charuco:11x8:0.030:0.022:DICT_5X5_100"


@dataclass(frozen=True)
class BoardSpec:
    cols: int          # squares across
    rows: int          # squares down
    square_m: float
    marker_m: float
    dictionary: str    # an OpenCV predefined dictionary name, e.g. DICT_5X5_100

    @classmethod
    def parse(cls, spec: str) -> "BoardSpec":
        m = re.fullmatch(r"charuco:(\d+)x(\d+):([0-9.eE+-]+):([0-9.eE+-]+):(DICT_\w+)", spec.strip())
        if not m:
            raise InputError(f"cannot read board spec {spec!r}; expected {SPEC_HELP}")
        cols, rows, square, marker, dictionary = int(m[1]), int(m[2]), float(m[3]), float(m[4]), m[5]
        spec_obj = cls(cols, rows, square, marker, dictionary)
        spec_obj.validate()
        return spec_obj

    def validate(self) -> None:
        if self.cols < 2 or self.rows < 2:
            raise InputError(f"a ChArUco board needs at least 2x2 squares, got {self.cols}x{self.rows}")
        if not 0 < self.marker_m < self.square_m:
            raise InputError(f"marker size {self.marker_m} m must be positive and smaller than the square "
                             f"{self.square_m} m")
        if not hasattr(cv2.aruco, self.dictionary):
            raise InputError(f"unknown ArUco dictionary {self.dictionary!r}; use an OpenCV name such as DICT_5X5_100")
        n_markers = (self.cols * self.rows) // 2
        size = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary)).bytesList.shape[0]
        if n_markers > size:
            raise InputError(f"a {self.cols}x{self.rows} board needs {n_markers} markers but {self.dictionary} "
                             f"has {size}; use a larger dictionary")

    def __str__(self) -> str:
        return f"charuco:{self.cols}x{self.rows}:{self.square_m:g}:{self.marker_m:g}:{self.dictionary}"

    def cv_board(self) -> "cv2.aruco.CharucoBoard":
        dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))
        return cv2.aruco.CharucoBoard((self.cols, self.rows), self.square_m, self.marker_m, dictionary)

    def corners_m(self) -> np.ndarray:
        """The inner chessboard corners (N,3) in board metres, indexed by ChArUco id."""
        return np.asarray(self.cv_board().getChessboardCorners(), dtype=np.float64).reshape(-1, 3)

    @property
    def size_m(self) -> tuple[float, float]:
        return self.cols * self.square_m, self.rows * self.square_m


@dataclass
class Detection:
    """The board corners found in one image."""
    source: str                 # image path or a synthetic label
    image_size: tuple[int, int]  # (width, height)
    ids: np.ndarray             # (N,) ChArUco corner ids
    pixels: np.ndarray          # (N,2) sub-pixel corner positions
    board_points: np.ndarray    # (N,3) the same corners on the board, metres

    def __len__(self) -> int:
        return len(self.ids)


def detect(spec: BoardSpec, image: np.ndarray, source: str = "") -> Detection:
    """Corners of ``spec`` in a grey or BGR image (possibly none)."""
    if image is None or image.size == 0:
        raise InputError(f"{source or 'image'}: empty image")
    gray = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    if gray.dtype != np.uint8:
        gray = cv2.normalize(gray, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)
    board = spec.cv_board()
    charuco_params = cv2.aruco.CharucoParameters()
    charuco_params.tryRefineMarkers = True
    detector = cv2.aruco.CharucoDetector(board, charuco_params)
    corners, ids, _, _ = detector.detectBoard(gray)
    size = (gray.shape[1], gray.shape[0])
    if ids is None or len(ids) == 0:
        return Detection(source, size, np.zeros(0, int), np.zeros((0, 2)), np.zeros((0, 3)))
    ids = ids.reshape(-1).astype(int)
    return Detection(source, size, ids, corners.reshape(-1, 2).astype(np.float64), spec.corners_m()[ids])


def board_image(spec: BoardSpec, px_per_m: float, margin_px: int = 0) -> np.ndarray:
    """A printable (grey) image of the board at ``px_per_m`` pixels per metre."""
    w_m, h_m = spec.size_m
    size = (int(round(w_m * px_per_m)) + 2 * margin_px, int(round(h_m * px_per_m)) + 2 * margin_px)
    return spec.cv_board().generateImage(size, marginSize=margin_px, borderBits=1)
