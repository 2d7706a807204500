"""Image embeddings for failure clusters: the FID Inception (default), a user-supplied
TorchScript CLIP encoder, and the scene encoding; the report records which was used."""
import json

import numpy as np
import pytest
import torch
from PIL import Image

from isu_validate.analysis import build_report
from isu_validate.analysis.embeddings import CLIP_SIZE, make_embedder
from isu_validate.analysis.multi_report import ReportSettings
from isu_validate.realism.inception import weights_path
from isu_validate.space import load_space
from tests.test_report import make_run


def failing_run(tmp_path, n=3):
    return make_run(tmp_path / "r", [{"wrong": {"driver_gender": "NONE"}} for _ in range(n)])


def test_inception_embeddings_drive_the_clusters(tmp_path, monkeypatch):
    try:
        weights_path()
    except FileNotFoundError as exc:
        pytest.skip(f"no FID Inception weights: {exc}")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # compute, do not reuse features
    space = load_space("isu-paper")
    first, second = space.sample(np.random.default_rng(7), 2)
    # scenes pair tests 0+1 and 2+3; the images pair 0+2 (noise) and 1+3 (smooth ramps): only the
    # image embedding can give the second grouping
    run = make_run(tmp_path / "r", [{"scene": s, "wrong": {"driver_gender": "NONE"}}
                                    for s in (first, first, second, second)])
    rng = np.random.default_rng(0)
    ramp = np.linspace(0, 255, 64)[None, :, None] * np.ones((48, 1, 3))
    for i, path in enumerate(sorted((run / "images").glob("*.png"))):
        pixels = rng.integers(0, 256, (48, 64, 3)) if i % 2 == 0 else ramp + rng.normal(0, 3, ramp.shape)
        Image.fromarray(np.clip(pixels, 0, 255).astype(np.uint8)).save(path)
    out = build_report([run], tmp_path / "rep", ReportSettings(embedding="inception", k=2))
    report = json.loads((tmp_path / "rep" / "report.json").read_text())
    assert report["settings"]["embedding"] == "inception"
    assert "InceptionV3" in report["settings"]["embedding_detail"]
    cluster = [c["cluster"] for c in sorted(report["tables"]["clusters"], key=lambda c: c["test_id"])]
    assert cluster[0] == cluster[2] != cluster[1] == cluster[3]
    assert "k = 2 (requested 2)" in out.read_text()
    build_report([run], tmp_path / "rep-scene", ReportSettings(embedding="scene", k=2))
    by_scene = json.loads((tmp_path / "rep-scene" / "report.json").read_text())["tables"]["clusters"]
    cluster = [c["cluster"] for c in sorted(by_scene, key=lambda c: c["test_id"])]
    assert cluster[0] == cluster[1] != cluster[2] == cluster[3]


class MeanColour(torch.nn.Module):
    """Stands in for a CLIP image encoder: one feature per channel; refuses other input sizes."""
    def forward(self, x):
        if x.shape[1] != 3 or x.shape[2] != 224 or x.shape[3] != 224:
            raise ValueError("expected N x 3 x 224 x 224")
        return x.mean(dim=(2, 3))


@pytest.mark.filterwarnings("ignore:`torch.jit.script` is deprecated:FutureWarning")
def test_clip_option_loads_a_torchscript_encoder(tmp_path):
    assert CLIP_SIZE == 224
    path = tmp_path / "clip_visual.pt"
    torch.jit.script(MeanColour()).save(str(path))
    run = failing_run(tmp_path, n=4)
    embedder = make_embedder(f"clip:{path}")
    vectors = embedder.embed_images(sorted((run / "images").glob("*.png")))
    assert vectors.shape == (4, 3) and np.isfinite(vectors).all()
    assert len({tuple(np.round(v, 6)) for v in vectors}) == 4  # four different colours, four embeddings


def test_clip_file_that_is_not_torchscript_is_refused(tmp_path):
    path = tmp_path / "weights.bin"
    path.write_bytes(b"not a model")
    with pytest.raises(ValueError, match="is not a TorchScript module or exported program"):
        make_embedder(f"clip:{path}")


def test_scene_embedding_marks_inactive_features():
    space = load_space("isu-paper")
    scene = space.sample(np.random.default_rng(0), 1)[0]
    scene.update(luggage="NO", child_seat="NO", external_light="MEDIUM")
    vector = make_embedder("scene").embed_scenes(space, [space.canonical(scene)])[0]
    names = list(space.features)
    assert vector[names.index("luggage_colour")] == -1.0
    assert vector[names.index("external_light")] == 0.5   # MEDIUM of LOW, MEDIUM, HIGH


def test_clip_option_loads_an_exported_program(tmp_path):
    path = tmp_path / "clip_visual.pt2"
    batch = torch.export.Dim("batch", min=1, max=64)
    program = torch.export.export(MeanColour(), (torch.zeros(2, 3, 224, 224),), dynamic_shapes=({0: batch},))
    torch.export.save(program, str(path))
    run = failing_run(tmp_path, n=3)
    vectors = make_embedder(f"clip:{path}").embed_images(sorted((run / "images").glob("*.png")))
    assert vectors.shape == (3, 3) and np.isfinite(vectors).all()
