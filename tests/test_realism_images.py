"""Image reading, anti-aliased resizing and image-set resolution for the realism metrics."""
import numpy as np
import pytest
from PIL import Image

from isu_validate.errors import InputError
from isu_validate.realism.images import ImageError, list_images, read_rgb
from isu_validate.realism.resize import resize_rgb
from isu_validate.realism.sets import resolve_set


def save(path, array, mode=None):
    img = Image.fromarray(array) if mode is None else Image.fromarray(array).convert(mode)
    img.save(path)
    return path


@pytest.mark.parametrize("mode", ["L", "RGBA", "P", "LA", "1"])
def test_any_mode_becomes_rgb_float(tmp_path, mode):
    rgb = np.random.default_rng(0).integers(0, 256, (10, 14, 3), dtype=np.uint8)
    path = save(tmp_path / "x.png", rgb, mode)
    out = read_rgb(path)
    assert out.shape == (10, 14, 3) and out.dtype == np.float32
    with Image.open(path) as img:  # alpha dropped, palette looked up, grey copied to R, G and B
        assert np.array_equal(out, np.asarray(img.convert("RGB"), np.float32))
    if mode in ("L", "LA", "1"):
        assert np.array_equal(out[..., 0], out[..., 2])


def test_sixteen_bit_grey_scales_to_0_255(tmp_path):
    grey = np.array([[0, 32768, 65535]], dtype=np.uint16)
    path = tmp_path / "g16.png"
    Image.fromarray(grey).save(path)
    out = read_rgb(path)
    assert out[0, :, 0] == pytest.approx([0, 127.5, 255], abs=0.01)


def test_corrupt_image_names_the_file_and_the_fix(tmp_path):
    bad = tmp_path / "broken.png"
    good = save(tmp_path / "ok.png", np.zeros((8, 8, 3), np.uint8))
    bad.write_bytes(good.read_bytes()[:40])
    with pytest.raises(ImageError, match=r"broken\.png.*re-export"):
        read_rgb(bad)


def test_empty_folder_is_a_clear_error(tmp_path):
    (tmp_path / "notes.txt").write_text("no images here")
    with pytest.raises(ImageError, match="holds no images"):
        list_images(tmp_path)


def test_a_render_folder_counts_frames_only_not_the_contact_sheet_or_channel_images(tmp_path):
    """`render --random N` writes a contact sheet (and, with --channels, seg/depth images) beside its frames."""
    rng = np.random.default_rng(2)
    for name in ("scene-0000.png", "scene-0001.png", "contact_sheet.png", "scene-0000.seg.png",
                 "scene-0000.semantic.png", "scene-0000.depth.png"):
        save(tmp_path / name, rng.integers(0, 256, (12, 16, 3), dtype=np.uint8))
    (tmp_path / "scene-0000.label.json").write_text("{}")
    image_set = resolve_set(str(tmp_path))
    assert [p.name for p in image_set.paths] == ["scene-0000.png", "scene-0001.png"]
    assert sorted(p.name for p in image_set.left_out) == sorted(["contact_sheet.png", "scene-0000.depth.png",
                                                                  "scene-0000.semantic.png", "scene-0000.seg.png"])


def test_resize_is_anti_aliased():
    # a one-pixel checkerboard must average to grey; an aliasing filter returns stripes
    checker = (np.indices((598, 598)).sum(axis=0) % 2 * 255.0)[..., None].repeat(3, axis=2)
    out = resize_rgb(checker, 299)
    assert out.shape == (299, 299, 3)
    assert np.abs(out[5:-5, 5:-5] - 127.5).max() < 2.0


def test_resize_keeps_constant_frames_exact_and_in_range():
    for value in (0.0, 255.0):
        out = resize_rgb(np.full((37, 91, 3), value, np.float32), 299)
        assert np.array_equal(out, np.full((299, 299, 3), value, np.float32))


def make_pairs(root, samples=3, nst=True):
    rng = np.random.default_rng(1)
    for i in range(samples):
        d = root / f"s{i}"
        (d / "real").mkdir(parents=True)
        save(d / "sim.png", rng.integers(0, 256, (12, 16, 3), dtype=np.uint8))
        save(d / "real" / "cam0.png", rng.integers(0, 256, (12, 16, 3), dtype=np.uint8))
        (d / "real" / "cam0.json").write_text("{}")
        if nst:
            save(d / "nst.png", rng.integers(0, 256, (12, 16, 3), dtype=np.uint8))
    return root


def test_pairs_roles_resolve_in_sample_order(tmp_path):
    pairs = make_pairs(tmp_path / "pairs")
    assert [p.parent.name for p in resolve_set(f"{pairs}:sim").paths] == ["s0", "s1", "s2"]
    assert all(p.name == "cam0.png" for p in resolve_set(f"{pairs}:real").paths)
    assert len(resolve_set(f"{pairs}:nst").paths) == 3


def test_pairs_without_role_or_without_nst_explain_themselves(tmp_path):
    pairs = make_pairs(tmp_path / "pairs", nst=False)
    with pytest.raises(ImageError, match="name the role"):
        resolve_set(str(pairs))
    with pytest.raises(ImageError, match="no nst images.*stylize"):
        resolve_set(f"{pairs}:nst")
    with pytest.raises(ValueError, match="unknown pairs role"):
        resolve_set(f"{pairs}:fake")


def test_missing_inception_weights_name_the_fix(tmp_path, monkeypatch):
    from isu_validate.realism import inception
    monkeypatch.setenv(inception.WEIGHTS_ENV, str(tmp_path / "nope.pt"))
    with pytest.raises(FileNotFoundError, match="ISU_FID_WEIGHTS"):
        inception.weights_path()
    monkeypatch.delenv(inception.WEIGHTS_ENV)
    assert inception.weights_path().name == "default_1.pt"


def test_a_labelled_real_set_in_class_folders_is_read_whole(tmp_path):
    """State Farm's layout (c0/ .. c9/, no image at the top): KID must count the photos `transfer` scores."""
    rng = np.random.default_rng(3)
    for cls, n in (("c0", 2), ("c1", 3)):
        (tmp_path / cls).mkdir()
        for i in range(n):
            save(tmp_path / cls / f"img_{i}.jpg", rng.integers(0, 256, (12, 16, 3), dtype=np.uint8))
    (tmp_path / "driver_imgs_list.csv").write_text("subject,classname,img\n")
    image_set = resolve_set(str(tmp_path))
    assert [p.relative_to(tmp_path).as_posix() for p in image_set.paths] == [
        "c0/img_0.jpg", "c0/img_1.jpg", "c1/img_0.jpg", "c1/img_1.jpg", "c1/img_2.jpg"]
    (tmp_path / "empty").mkdir()
    with pytest.raises(ImageError, match="holds no images.*real photo set"):
        list_images(tmp_path / "empty")
    yolo = tmp_path / "yolo"                  # a set recognised by its data.yaml, but without its photos
    (yolo / "images").mkdir(parents=True)
    (yolo / "data.yaml").write_text("names: [phone]\n")
    with pytest.raises(InputError, match="yolo layout"):   # its own words, not "holds no images"
        list_images(yolo)
