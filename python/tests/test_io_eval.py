"""EXR round trips with metadata, metrics, comparison, guiding."""

import numpy as np
import pytest

import lanterna
from conftest import H, W


def test_exr_round_trip_keeps_metadata_sums_and_aovs(pt, tmp_path):
    img = pt.render(spp=2, aovs=["normal", "depth"])
    img.meta["note"] = "hello"
    img.meta["ratio"] = 0.1
    img.meta["flag"] = True
    lanterna.write_exr(tmp_path / "a.exr", img)
    back = lanterna.read_exr(tmp_path / "a.exr")
    np.testing.assert_array_equal(np.asarray(back), np.asarray(img))
    np.testing.assert_array_equal(back.sums, img.sums)
    for name in img.aovs:
        np.testing.assert_array_equal(back.aovs[name], img.aovs[name])
    assert back.aov_channels == img.aov_channels
    assert back.meta == img.meta


def test_plain_arrays_are_images(tmp_path):
    a = np.random.default_rng(1).random((5, 7, 3))
    lanterna.write_exr(tmp_path / "b.exr", a, meta={"spp": 3})
    back = lanterna.read_exr(tmp_path / "b.exr")
    np.testing.assert_array_equal(np.asarray(back), a.astype(np.float32))
    assert back.sums is None and back.meta["spp"] == 3
    with pytest.raises(ValueError):
        lanterna.write_exr(tmp_path / "c.exr", np.zeros((5, 7)))


def test_metrics(pt):
    a = pt.render(spp=1)
    b = pt.render(spp=4, sample_offset=1)
    x, r = np.asarray(a, np.float64), np.asarray(b, np.float64)
    assert lanterna.mae(a, a) == 0.0
    assert lanterna.mae(a, b) == pytest.approx(np.mean(np.abs(x - r)), rel=1e-12)
    assert lanterna.relmse(a, b) == pytest.approx(np.mean((x - r) ** 2 / (r * r + 0.01)), rel=1e-12)
    with pytest.raises(ValueError, match="non-finite"):
        lanterna.mae(np.full((H, W, 3), np.nan), b)
    with pytest.raises(ValueError, match="is 2x2 but the reference"):
        lanterna.mae(np.zeros((2, 2, 3)), b)


def test_merge_refuses_overlaps(ris):
    a = ris.render(spp=2)
    with pytest.raises(ValueError, match="overlap"):
        lanterna.merge([a, ris.render(spp=2, sample_offset=1)])


def test_compare_returns_the_report(ris, pt, tmp_path):
    reference = pt.render(spp=16, sample_offset=100)
    reference.meta["max_depth"] = 3
    report = lanterna.compare(ris, reference, methods=["pt", "ris"], spp=[1, 2], out_dir=tmp_path)
    assert (tmp_path / "report.json").exists() and (tmp_path / "index.html").exists()
    records = report["records"]
    assert sorted((r["method"], r["spp"]) for r in records) == [("pt", 1), ("pt", 2), ("ris", 1), ("ris", 2)]
    assert all(r["mae"] > 0 for r in records)
    assert ris.method == "ris"  # the renderer keeps its own method
    with pytest.raises(ValueError, match="max depth 4, but --max-depth is 3"):
        lanterna.compare(ris, pt.render(spp=1), methods=["pt"], spp=[1])


def test_guiding_train_save_load_and_leaf(scene, tmp_path):
    g = lanterna.Renderer(scene, W, H, method="guided")
    info = g.train(spp=7)
    assert [it["spp"] for it in info["iterations"]] == [1, 2, 4] and info["spp"] == 7
    assert g.has_guiding
    img = g.render(spp=4)
    assert img.meta["spp"] == 4  # the whole budget renders with the trained tree
    g.save_guiding(tmp_path / "tree.sdt")
    loaded = lanterna.Renderer(scene, W, H, method="guided", load_guiding=tmp_path / "tree.sdt")
    assert loaded.has_guiding and loaded.render(spp=2).meta["spp"] == 2
    leaf = g.guiding_leaf(16, 12, size=32)
    assert leaf["density"].shape == (32, 32) and leaf["image"].shape == (32, 32, 3)
    # A density over the unit square averages to one.
    assert leaf["density"].mean() == pytest.approx(1.0, rel=0.05)
    assert len(leaf["position"]) == 3 and leaf["nodes"] >= 1
    with pytest.raises(FileNotFoundError):
        lanterna.Renderer(scene, W, H, method="guided", load_guiding=tmp_path / "none.sdt")
