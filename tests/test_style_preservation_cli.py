"""Semantic preservation measures, and the stylize / realism commands on a tiny pairs directory."""
import json
import sys

import numpy as np
import pytest
from PIL import Image, ImageDraw

from isu_validate.cli import main
from style_transfer.preservation import answer_flips, edge_agreement, ssim_luma, structure_score


pytestmark = pytest.mark.usefixtures("few_torch_threads")


def test_identical_images_preserve_everything():
    rng = np.random.default_rng(0)
    luma = rng.random((24, 30))
    assert ssim_luma(luma, luma) == pytest.approx(1.0)
    assert edge_agreement(luma, luma) == pytest.approx(1.0)


def test_inversion_keeps_edges_but_not_ssim():
    luma = np.zeros((24, 30))
    luma[6:18, 8:20] = 1.0
    assert edge_agreement(luma, 1.0 - luma) == pytest.approx(1.0)
    assert ssim_luma(luma, 1.0 - luma) < 0.0


def test_flat_frames_do_not_produce_nan():
    flat, black = np.full((20, 20), 0.5), np.zeros((20, 20))
    textured = np.indices((20, 20)).sum(axis=0) % 2.0
    assert edge_agreement(flat, black) == 1.0
    assert edge_agreement(flat, textured) == 0.0
    assert np.isfinite(ssim_luma(black, flat))
    with pytest.raises(ValueError, match="equal sizes"):
        ssim_luma(flat, np.zeros((10, 10)))


def test_structure_score_compares_at_the_render_size(tmp_path):
    img = Image.new("RGB", (64, 48), (60, 60, 60))
    ImageDraw.Draw(img).rectangle([10, 10, 40, 30], fill=(230, 230, 230))
    img.save(tmp_path / "render.png")
    img.resize((32, 24), Image.Resampling.LANCZOS).save(tmp_path / "small.png")
    score = structure_score(tmp_path / "render.png", tmp_path / "small.png")
    assert score.ssim_luma > 0.8 and score.edge_agreement > 0.8


def test_answer_flips_count_changes_and_keep_errors_apart():
    answers = {"r1": {"a": "YES", "b": "RED"}, "s1": {"a": "NO", "b": "RED"},
               "r2": {"a": "YES"}, "s2": None}
    report = answer_flips([("ctx", "r1", "s1"), ("ctx", "r2", "s2")], lambda ctx, image: answers[image])
    assert (report.compared, report.flipped, report.errors) == (2, 1, 1)
    assert report.flip_rate == 0.5 and report.per_feature == {"a": [1, 1], "b": [1, 0]}


@pytest.fixture()
def pairs(tmp_path):
    from isu_validate.space.loader import load_space
    scenes = load_space().sample(np.random.default_rng(0), 2)
    rng = np.random.default_rng(1)
    root = tmp_path / "pairs"
    for i, scene in enumerate(scenes):
        d = root / f"s{i}"
        (d / "real").mkdir(parents=True)
        (d / "scene.json").write_text(json.dumps(scene))
        img = Image.new("RGB", (40, 32), (90, 90, 110))
        ImageDraw.Draw(img).rectangle([5 + 3 * i, 8, 22, 28], fill=(200, 60, 50))
        img.save(d / "sim.png")
        noisy = np.asarray(img, np.float32) * 0.8 + rng.normal(0, 12, (32, 40, 3)) + 25
        Image.fromarray(np.clip(noisy, 0, 255).astype(np.uint8)).save(d / "real" / "cam0.png")
        (d / "real" / "cam0.json").write_text("{}")
    return root


FLIPPING_SUT = """
import json, sys
req = json.load(sys.stdin)
last = req["image"].endswith("nst.png")  # answers differently on stylised images
print(json.dumps({"answers": {q["key"]: q["options"][-1 if last else 0] for q in req["questions"]}}))
"""


def test_stylize_pairs_writes_nst_counts_flips_and_feeds_realism(pairs, tmp_path, capsys):
    sut = tmp_path / "sut.py"
    sut.write_text(FLIPPING_SUT)
    style = pairs / "s0" / "real" / "cam0.png"
    code = main(["stylize", "--style", str(style), "--pairs", str(pairs), "--method", "gatys", "--size", "32",
                 "--steps", "1", "--sut", f"command:{sys.executable} {sut}", "--threads", "2", "--style-distance", "0"])
    assert code == 0
    for sample in ("s0", "s1"):
        with Image.open(pairs / sample / "nst.png") as nst:
            assert nst.size == (40, 32)  # written back at the render's size
    report = json.loads((pairs / "nst.json").read_text())
    scores = [structure_score(pairs / sample / "sim.png", pairs / sample / "nst.png") for sample in ("s0", "s1")]
    assert report["count"] == 2
    assert report["ssim_luma_mean"] == pytest.approx((scores[0].ssim_luma + scores[1].ssim_luma) / 2)
    assert [r["edge_agreement"] for r in report["images"]] == pytest.approx([s.edge_agreement for s in scores])
    assert report["settings"]["steps"] == 1 and report["settings"]["style_weight"] == 10.0
    flips = report["answer_flips"]
    assert flips["samples"] == 2 and flips["compared"] > 0 and flips["flipped"] > 0 and flips["sut_errors"] == 0
    # an interrupted run resumes: existing outputs are kept, not recomputed
    before = (pairs / "s0" / "nst.png").stat().st_mtime_ns
    assert main(["stylize", "--style", str(style), "--pairs", str(pairs), "--method", "gatys", "--size", "32",
                 "--resume", "--style-distance", "0"]) == 0
    assert (pairs / "s0" / "nst.png").stat().st_mtime_ns == before
    assert all(r.get("resumed") for r in json.loads((pairs / "nst.json").read_text())["images"])
    capsys.readouterr()
    assert main(["realism", "--pairs", str(pairs), "--json", "--bootstrap", "10", "--kid-subsets", "5",
                 "--cache-dir", str(tmp_path / "cache"), "--threads", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {f"{pairs}:sim vs {pairs}:real", f"{pairs}:nst vs {pairs}:real", f"{pairs}:sim vs {pairs}:nst"}
    assert all(np.isfinite(r["fid"]) and r["n_a"] == 2 for r in out.values())


def test_stylize_errors_name_the_fix(pairs, tmp_path, capsys):
    render = str(pairs / "s0" / "sim.png")
    assert main(["stylize", render, "--out", str(tmp_path / "out")]) == 2
    assert "the gatys method needs --style" in capsys.readouterr().err
    assert main(["stylize", render, "--out", str(tmp_path / "out"), "--method", "fast"]) == 2
    assert "the fast method needs --style" in capsys.readouterr().err
    assert main(["stylize", "train", "--style", str(pairs / "s0" / "sim.png")]) == 2
    assert "usage: isu-validate stylize train" in capsys.readouterr().err


def test_train_then_stylise_with_the_fast_model(pairs, tmp_path, capsys):
    model, out = tmp_path / "fast.pt", tmp_path / "out"
    style = pairs / "s0" / "real" / "cam0.png"
    assert main(["stylize", "train", "--style", str(style), "--content", str(pairs / "s0"), "--out", str(model),
                 "--steps", "2", "--crop", "24", "--width", "8", "--blocks", "1", "--batch-size", "1",
                 "--device", "cpu"]) == 0
    assert json.loads(capsys.readouterr().out)["steps"] == 2
    assert main(["stylize", str(pairs / "s1" / "sim.png"), "--method", "fast", "--model", str(model),
                 "--style", str(style), "--out", str(out)]) == 0
    with Image.open(out / "sim.png") as img:
        assert img.size == (40, 32)
    report = json.loads((out / "stylize.json").read_text())
    assert report["settings"]["steps_done"] == 2 and report["settings"]["trained_on"] == "cpu"
    assert main(["stylize", str(pairs / "s1" / "sim.png"), "--method", "fast", "--model", str(model),
                 "--style", str(pairs / "s1" / "sim.png"), "--out", str(out)]) == 2
    assert "trained for style" in capsys.readouterr().err


def test_stylize_skips_a_corrupt_image_with_a_message_and_keeps_the_others(tmp_path, capsys):
    renders = tmp_path / "renders"
    renders.mkdir()
    for name, colour in (("a", (200, 40, 40)), ("c", (40, 40, 200))):
        img = Image.new("RGB", (40, 32), colour)
        ImageDraw.Draw(img).rectangle([8, 8, 30, 24], fill=(240, 240, 240))
        img.save(renders / f"{name}.png")
    (renders / "b.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"not really a png")  # e.g. an interrupted copy
    out = tmp_path / "nst"
    assert main(["stylize", "--style", str(renders / "a.png"), str(renders), "--size", "32", "--steps", "1",
                 "--out", str(out), "--threads", "2"]) == 0
    err = capsys.readouterr().err
    assert f"skipped {renders / 'b.png'}: cannot read it as an image" in err
    assert sorted(p.name for p in out.glob("*.png")) == ["a.png", "c.png"]
    report = json.loads((out / "stylize.json").read_text())
    assert report["count"] == 2 and [s["source"] for s in report["skipped"]] == [str(renders / "b.png")]


def test_stylize_falls_back_from_an_absent_gpu_and_names_the_device(tmp_path, capsys, monkeypatch):
    import torch
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    img = Image.new("RGB", (40, 32), (200, 40, 40))
    ImageDraw.Draw(img).rectangle([8, 8, 30, 24], fill=(240, 240, 240))
    img.save(tmp_path / "a.png")
    out = tmp_path / "nst"
    assert main(["stylize", "--style", str(tmp_path / "a.png"), str(tmp_path / "a.png"), "--size", "32",
                 "--steps", "1", "--out", str(out), "--device", "cuda"]) == 0
    err = capsys.readouterr().err
    assert err.count("warning: device cuda is not available (torch sees no CUDA device") == 1
    report = json.loads((out / "stylize.json").read_text())
    assert report["device"].startswith("cpu (asked cuda: torch sees no CUDA device")
    assert main(["stylize", "--style", str(tmp_path / "a.png"), str(tmp_path / "a.png"), "--size", "32",
                 "--steps", "1", "--out", str(out), "--device", "cpu"]) == 0
    again = json.loads((out / "stylize.json").read_text())
    assert again["device"] == "cpu" and again["images"][0]["resumed"]   # a device change keeps the images
