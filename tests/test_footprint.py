"""The unoccluded-footprint rasteriser (no Blender): pixel-centre coverage, unions, the near plane,
degenerate and huge triangles, closed-mesh culling, and the packed masks the worker hands back."""
from __future__ import annotations

import numpy as np
import pytest

from capture.camera import load_camera
from isu_validate.render.footprint import (NEAR_M, clip_near, facing_camera, fill_parts, footprints,
                                           is_closed, orientation, pack, project, unpack_counts)


def fill_triangles(triangles_px, width, height):
    """One part's mask: the rasteriser's semantics seen through ``fill_parts``."""
    return fill_parts([triangles_px], width, height)[0]


SQUARE = np.array([[[10, 10], [20, 10], [20, 20]], [[10, 10], [20, 20], [10, 20]]], float)


def _cube():
    """A unit cube with outward-wound triangles (12), vertices at +-0.5."""
    v = np.array([[x, y, z] for x in (-.5, .5) for y in (-.5, .5) for z in (-.5, .5)])
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = []
    for a, b, c, d in quads:
        faces += [(a, b, c), (a, c, d)]
    faces = np.array(faces)
    if orientation(v, faces) < 0:   # make the winding outward whatever the quad order gave
        faces = faces[:, ::-1]
    return v, faces


def test_pixel_centres_inside_edges_included():
    assert fill_triangles(SQUARE, 64, 48).sum() == 11 * 11     # centres 10..20 on both axes
    assert fill_triangles(SQUARE + 0.5, 64, 48).sum() == 10 * 10


def test_overlapping_triangles_make_a_union_not_an_even_odd_fill():
    # cv2.fillPoly with several contours cancels overlaps (even-odd); a footprint must not
    a = np.array([[[10, 10], [60, 10], [10, 60]]], float)
    b = np.array([[[20, 20], [70, 20], [20, 70]]], float)
    both = fill_triangles(np.concatenate([a, b]), 100, 100)
    assert np.array_equal(both, fill_triangles(a, 100, 100) | fill_triangles(b, 100, 100))
    assert both[25, 25]


def test_degenerate_offscreen_nan_and_huge_triangles():
    line = np.array([[[5, 5], [30, 30], [60, 60]]], float)        # zero area
    away = np.array([[[-50, -50], [-40, -50], [-40, -40]]], float)
    nan = np.array([[[np.nan, 1], [2, 3], [4, 5]]])
    assert fill_triangles(line, 64, 64).sum() <= 60                # only centres exactly on the line
    assert not fill_triangles(away, 64, 64).any() and not fill_triangles(nan, 64, 64).any()
    huge = np.array([[[-1e6, -1e6], [1e7, 0], [0, 1e7]]], float)
    assert fill_triangles(huge, 320, 240).all()
    assert fill_parts([], 8, 6).shape == (0, 6, 8)


def test_parts_are_filled_apart():
    masks = fill_parts([SQUARE, SQUARE + 30, np.zeros((0, 3, 2))], 64, 64)
    assert masks.shape == (3, 64, 64) and [int(m.sum()) for m in masks] == [121, 121, 0]
    assert not (masks[0] & masks[1]).any()


def test_near_plane_cuts_triangles_behind_the_camera():
    behind = np.array([[[0, 0, -1], [1, 0, -1], [0, 1, -1]]], float)
    assert len(clip_near(behind)) == 0
    # a triangle from 1 m in front to 1 m behind: what is left lies in front of the near plane
    crossing = np.array([[[-0.2, 0.0, 1.0], [0.2, 0.0, 1.0], [0.0, 0.1, -1.0]]])
    kept = clip_near(crossing)
    assert len(kept) == 2 and (kept[..., 2] >= NEAR_M - 1e-12).all()
    area = sum(0.5 * np.linalg.norm(np.cross(t[1] - t[0], t[2] - t[0])) for t in kept)
    whole = 0.5 * np.linalg.norm(np.cross(crossing[0, 1] - crossing[0, 0], crossing[0, 2] - crossing[0, 0]))
    cut = (1 + NEAR_M) / 2                  # share of the height from the tip to the near plane
    assert area == pytest.approx(whole * (1 - cut ** 2), rel=1e-9)   # the tip cut off is a similar triangle


def test_projection_matches_the_camera_rig():
    rig = load_camera()
    points = np.array([[-0.5, 0.3, 0.6], [-0.9, -0.2, 0.5], [0.0, 0.37, 0.9]])
    cam = rig.to_camera(points)
    uv = project(cam.reshape(1, 3, 3), rig.fx, rig.cx, rig.cy)[0]
    assert np.allclose(uv, rig.project(points), atol=1e-9)


def test_closed_mesh_orientation_and_culling_keep_the_silhouette():
    v, faces = _cube()
    assert orientation(v, faces) == 1 and orientation(v, faces[:, ::-1]) == -1
    assert orientation(v, faces[1:]) == 0                               # a hole: open
    assert orientation(v, np.concatenate([faces[:1, ::-1], faces[1:]])) == 0   # inconsistent winding
    # the topology check, cached across frames by the worker, decides alone once given
    assert is_closed(faces) and not is_closed(faces[1:]) and not is_closed(faces[:0])
    assert orientation(v, faces, closed=False) == 0 and orientation(-v, faces, closed=True) == -1
    R = (np.array([[0.8, 0.0, 0.6], [0.0, 1.0, 0.0], [-0.6, 0.0, 0.8]])
         @ np.array([[1, 0, 0], [0, 0.8, -0.6], [0, 0.6, 0.8]]))
    tris = (v @ (0.3 * R).T + [0.05, -0.02, 1.2])[faces]               # rotated, scaled, 1.2 m away
    front = facing_camera(tris, 1)
    assert 0 < front.sum() < len(tris)
    every = footprints([tris], 300, 160, 120, 320, 240)[0]
    assert every.sum() > 1000 and np.array_equal(footprints([tris[front]], 300, 160, 120, 320, 240)[0], every)


def test_packed_masks_count_back_beyond_sixteen_parts():
    rng = np.random.default_rng(0)
    masks = rng.random((19, 12, 16)) < 0.3
    planes = pack(masks)
    assert planes.shape == (2, 12, 16) and planes.dtype == np.uint16
    assert unpack_counts(planes, 19) == [int(m.sum()) for m in masks]
