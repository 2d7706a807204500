"""`stylize --pairs` with the fast net trained once per style set: cache, skipping, interrupts, bad inputs."""
import json
import shutil

import numpy as np
import pytest
import torch
from PIL import Image, ImageDraw

from isu_validate.cli import main
from isu_validate.commands import stylize
from style_transfer import fast
from style_transfer.model_cache import fast_model_for, model_key
from style_transfer.style_set import mean_grams, style_paths

pytestmark = pytest.mark.usefixtures("few_torch_threads")

# a tiny net and a few steps: the plumbing is tested, not the look (bench nst measures that)
TINY = ["--steps", "3", "--crop", "24", "--width", "8", "--blocks", "1", "--batch-size", "1", "--style-size", "64",
        "--threads", "2", "--fast-size", "0"]


def _pair(root, name, i, frames=1):
    d = root / name
    (d / "real").mkdir(parents=True)
    img = Image.new("RGB", (64, 48), (90, 90, 110))
    ImageDraw.Draw(img).rectangle([5 + 4 * i, 8, 30, 40], fill=(200, 60, 50))
    img.save(d / "sim.png")
    rng = np.random.default_rng(i)
    for f in range(frames):
        noisy = np.asarray(img, np.float32) * 0.8 + rng.normal(0, 12, (48, 64, 3)) + 25
        Image.fromarray(np.clip(noisy, 0, 255).astype(np.uint8)).save(d / "real" / f"frame_{f:04d}.png")


@pytest.fixture()
def pairs(tmp_path):
    root = tmp_path / "pairs"
    for i in range(3):
        _pair(root, f"S0{i + 1}", i)
    return root


def _stylize(pairs, cache, *extra):
    return main(["stylize", "--pairs", str(pairs), "--model-cache", str(cache), "--style-distance", "0", *TINY, *extra])


def test_fast_is_the_pairs_default_trained_once_per_style_set_and_reruns_skip(pairs, tmp_path, capsys):
    cache = tmp_path / "cache"
    assert _stylize(pairs, cache) == 0
    err = capsys.readouterr().err
    assert "training the fast net: step 3/3" in err
    report = json.loads((pairs / "nst.json").read_text())
    settings = report["settings"]
    assert report["complete"] and report["count"] == 3 and settings["method"] == "fast"
    assert settings["model_from_cache"] is False and settings["content_images"] == 3
    assert len(settings["styles"]) == 3  # every pair's real frame: the camera's shared look
    assert len(list(cache.glob("*.pt"))) == 1 and not list(cache.glob("*.ckpt"))
    for s in ("S01", "S02", "S03"):
        with Image.open(pairs / s / "nst.png") as img:
            assert img.size == (64, 48)
    # the same command again: every pair is kept, nothing is trained or styled
    stamps = {s: (pairs / s / "nst.png").stat().st_mtime_ns for s in ("S01", "S02", "S03")}
    assert _stylize(pairs, cache) == 0
    err = capsys.readouterr().err
    assert "training" not in err and err.count("kept") == 3
    again = json.loads((pairs / "nst.json").read_text())
    assert all(r["resumed"] for r in again["images"]) and again["settings"]["model_from_cache"] is False
    assert stamps == {s: (pairs / s / "nst.png").stat().st_mtime_ns for s in stamps}
    # a changed render is styled again, with the cached net (no training)
    (pairs / "S02" / "sim.png").write_bytes((pairs / "S01" / "sim.png").read_bytes())
    assert _stylize(pairs, cache) == 0
    err = capsys.readouterr().err
    assert "training" not in err and "from the cache" in err and err.count("kept") == 2
    assert json.loads((pairs / "nst.json").read_text())["settings"]["model_from_cache"] is True


def test_other_settings_restyle_and_a_given_style_is_its_own_set(pairs, tmp_path, capsys):
    cache = tmp_path / "cache"
    assert _stylize(pairs, cache) == 0
    style = pairs / "S01" / "real" / "frame_0000.png"
    assert _stylize(pairs, cache, "--style", str(style)) == 0
    assert "kept" not in capsys.readouterr().err
    report = json.loads((pairs / "nst.json").read_text())
    assert report["settings"]["styles"] == [str(style)] and len(list(cache.glob("*.pt"))) == 2


def test_an_interrupted_run_keeps_finished_pairs(pairs, tmp_path, monkeypatch, capsys):
    cache, calls = tmp_path / "cache", []
    real = fast.stylize_fast

    def second_one_interrupts(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*args, **kwargs)
    monkeypatch.setattr(fast, "stylize_fast", second_one_interrupts)
    assert _stylize(pairs, cache) == 130
    assert "the same command again goes on from there" in capsys.readouterr().err
    partial = json.loads((pairs / "nst.json").read_text())
    assert partial["complete"] is False and [r["output"] for r in partial["images"]] == [str(pairs / "S01" / "nst.png")]
    assert not (pairs / "S02" / "nst.png").exists()
    monkeypatch.setattr(fast, "stylize_fast", real)
    assert _stylize(pairs, cache) == 0
    err = capsys.readouterr().err
    assert err.count("kept") == 1 and "from the cache" in err
    report = json.loads((pairs / "nst.json").read_text())
    assert report["complete"] and report["count"] == 3 and [r.get("resumed", False) for r in report["images"]] == [
        True, False, False]


def test_style_distance_is_measured_on_images_spread_over_the_set(pairs, tmp_path, monkeypatch):
    monkeypatch.setattr(stylize, "PAIR_STYLES", 2)  # the default style set: first frames, spread and capped
    assert main(["stylize", "--pairs", str(pairs), "--model-cache", str(tmp_path / "c"), *TINY,
                 "--style-distance", "2"]) == 0
    report = json.loads((pairs / "nst.json").read_text())
    assert report["settings"]["styles"] == [str(pairs / s / "real" / "frame_0000.png") for s in ("S01", "S03")]
    first, middle, last = report["images"]
    assert "style_distance" not in middle
    for r in (first, last):
        assert r["render_style_distance"] > 0 and r["style_distance"] >= 0
        assert r["style_gap_closed"] == pytest.approx(1 - r["style_distance"] / r["render_style_distance"])
    assert report["style_distance_mean"] == pytest.approx((first["style_distance"] + last["style_distance"]) / 2)


def test_bad_style_inputs_give_one_line(pairs, tmp_path, capsys):
    cache = tmp_path / "cache"
    broken = pairs / "S02" / "real" / "frame_0000.png"
    broken.write_bytes(b"\x89PNG\r\n\x1a\n" + b"cut short")
    assert _stylize(pairs, cache) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and f"cannot read style image {broken}" in err
    assert _stylize(pairs, cache, "--style", str(tmp_path / "nowhere.png")) == 2
    assert f"style image {tmp_path / 'nowhere.png'} does not exist" in capsys.readouterr().err
    for s in ("S01", "S02", "S03"):
        shutil.rmtree(pairs / s / "real")
    assert _stylize(pairs, cache) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "has no real frames to take the style from" in err


def test_a_pair_without_real_frames_is_named_and_still_styled(pairs, tmp_path, capsys):
    shutil.rmtree(pairs / "S03" / "real")
    assert _stylize(pairs, tmp_path / "cache") == 0
    assert "1 sample(s) have no real frames (S03)" in capsys.readouterr().err
    assert (pairs / "S03" / "nst.png").is_file()
    assert len(json.loads((pairs / "nst.json").read_text())["settings"]["styles"]) == 2


def test_gatys_stays_available_for_pairs(pairs, tmp_path):
    assert main(["stylize", "--pairs", str(pairs), "--method", "gatys", "--size", "32", "--steps", "1",
                 "--style-distance", "0", "--threads", "2"]) == 0
    settings = json.loads((pairs / "nst.json").read_text())["settings"]
    assert settings["method"] == "gatys" and len(settings["styles"]) == 3


def test_the_library_trains_or_loads_by_the_photos_content(pairs, tmp_path):
    """`fast_model_for`: the call the dataset builder makes; names and order of the photos do not matter."""
    cfg = fast.FastTrainConfig(steps=2, batch_size=1, crop=24, style_size=48, style_layers=("relu1_1", "relu2_1"),
                               net=fast.FastNetConfig(width=8, blocks=1))
    frames = sorted(pairs.glob("S*/real/*.png"))
    renders = sorted(pairs.glob("S*/sim.png"))
    first = fast_model_for(frames, renders, cfg, tmp_path / "cache")
    assert first.trained and first.meta["steps_done"] == 2 and first.meta["content_images"] == 3
    renamed = tmp_path / "elsewhere"
    renamed.mkdir()
    for i, f in enumerate(reversed(frames)):
        shutil.copy(f, renamed / f"photo{i}.png")
    second = fast_model_for([renamed], renders[:1], cfg, tmp_path / "cache")
    assert not second.trained and second.path == first.path and second.train_seconds == 0
    x = torch.rand(1, 3, 32, 40, generator=torch.Generator().manual_seed(0))
    assert torch.equal(fast.stylize_fast(first.net, x), fast.stylize_fast(second.net, x))
    assert model_key(style_paths(frames), cfg) != model_key(style_paths(frames[:1]), cfg)
    first.path.write_bytes(b"damaged")  # a damaged entry is retrained, not an error
    assert fast_model_for(frames, renders, cfg, tmp_path / "cache").trained


def test_a_style_set_aims_at_the_mean_gram():
    from style_transfer.vgg import VGG19
    vgg = VGG19()
    a, b = torch.rand(1, 3, 24, 24), torch.rand(1, 3, 24, 24) * 0.5
    both = mean_grams(vgg, [a, b], ["relu1_1"])["relu1_1"]
    one = [mean_grams(vgg, [x], ["relu1_1"])["relu1_1"] for x in (a, b)]
    assert torch.allclose(both, (one[0] + one[1]) / 2)
