"""The real Inception network: black and saturated frames, identical sets, the cache, the command."""
import json

import numpy as np
import pytest
from PIL import Image

from isu_validate.cli import main
from isu_validate.realism import FeatureExtractor, fid, kid


pytestmark = pytest.mark.usefixtures("few_torch_threads")


@pytest.fixture(scope="module")
def images(tmp_path_factory):
    root = tmp_path_factory.mktemp("realism")
    rng = np.random.default_rng(0)
    folders = {name: root / name for name in ("noise", "gradient", "black", "white")}
    for folder in folders.values():
        folder.mkdir()
    for i in range(3):
        Image.fromarray(rng.integers(0, 256, (24, 32, 3), dtype=np.uint8)).save(folders["noise"] / f"{i}.png")
        ramp = np.clip(np.linspace(0, 255, 32)[None, :, None] + rng.normal(0, 10, (24, 32, 3)), 0, 255)
        Image.fromarray(ramp.astype(np.uint8)).save(folders["gradient"] / f"{i}.png")
    for i in range(2):  # n = 2, the smallest set FID accepts
        Image.fromarray(np.zeros((20, 20, 3), np.uint8)).save(folders["black"] / f"{i}.png")
        Image.fromarray(np.full((20, 30), 255, np.uint8), "L").save(folders["white"] / f"{i}.png")
    return folders


@pytest.fixture(scope="module")
def extractor(tmp_path_factory):
    return FeatureExtractor(cache=tmp_path_factory.mktemp("cache"), batch_size=4)


def paths(folder):
    return sorted(folder.glob("*.png"))


def test_black_and_saturated_frames_give_finite_distinct_features(extractor, images):
    black, white = extractor.features(paths(images["black"])), extractor.features(paths(images["white"]))
    assert black.shape == (2, 2048) and np.isfinite(black).all() and np.isfinite(white).all()
    value = fid(black, white)  # both covariances are zero: the singular extreme, FID = squared mean distance
    assert np.allclose(black, black[0]) and np.allclose(white, white[0])
    assert value == pytest.approx(float(((black[0] - white[0]) ** 2).sum()), rel=1e-9) and value > 1.0
    assert fid(black, black) == pytest.approx(0.0, abs=1e-9)


def test_identical_sets_zero_and_different_sets_positive(extractor, images):
    noise, gradient = extractor.features(paths(images["noise"])), extractor.features(paths(images["gradient"]))
    assert fid(noise, noise) == pytest.approx(0.0, abs=1e-8)
    assert fid(noise, gradient) > 10.0
    assert kid(noise, gradient).mean > kid(noise, noise).mean


def test_cache_serves_repeats_and_copies_and_recovers_from_damage(extractor, images, tmp_path):
    first = extractor.features(paths(images["noise"]))
    hits = extractor.cache.hits
    copy = tmp_path / "renamed.png"
    copy.write_bytes(paths(images["noise"])[0].read_bytes())
    again = extractor.features([*paths(images["noise"]), copy])
    assert extractor.cache.hits - hits == 4
    assert np.array_equal(again[:3], first) and np.array_equal(again[3], first[0])
    for entry in extractor.cache.folder.rglob("*.npy"):
        entry.write_bytes(b"damaged")
    assert np.allclose(extractor.features(paths(images["noise"])), first, atol=1e-4)
    assert extractor.cache.hits - hits == 4  # the damaged entries were misses, recomputed


def test_resolution_barely_moves_features(extractor, tmp_path):
    rng = np.random.default_rng(3)
    base = np.clip(rng.normal(128, 60, (8, 8, 3)), 0, 255).astype(np.uint8)
    small = Image.fromarray(base).resize((120, 90), Image.Resampling.BICUBIC)
    large = Image.fromarray(base).resize((640, 480), Image.Resampling.BICUBIC)
    a, b = extractor.features_of_arrays([np.asarray(small, np.float32), np.asarray(large, np.float32)])
    assert np.dot(a, b) / np.linalg.norm(a) / np.linalg.norm(b) > 0.98


def test_command_json_and_errors(images, extractor, tmp_path, capsys):
    cache = str(extractor.cache.folder.parent)  # features extracted above: the command reuses them
    args = ["realism", str(images["noise"]), str(images["gradient"]), "--json", "--cache-dir", cache,
            "--bootstrap", "20", "--kid-subsets", "10", "--threads", "2"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    expected = fid(extractor.features(paths(images["noise"])), extractor.features(paths(images["gradient"])))
    assert out["n_a"] == 3 and out["fid"] == pytest.approx(expected, rel=1e-9) and len(out["fid_ci"]) == 2
    assert out["settings"]["resize_filter"] == "bicubic" and out["settings"]["kid_subset_size"] == 3
    assert main([*args, "--kid-subset-size", "4"]) == 2
    assert "exceeds the smaller set (3 images)" in capsys.readouterr().err
    assert main(["realism", str(images["noise"]), str(tmp_path)]) == 2
    assert "holds no images" in capsys.readouterr().err
