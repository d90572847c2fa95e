"""Renders through Python against the CLI, bit for bit, and exact merging of sample
ranges."""

import numpy as np

import lanterna
from conftest import SCENE, H, W


def cli_render(cli, tmp_path, *args):
    out = tmp_path / "cli.exr"
    p = cli("render", str(SCENE), "--width", str(W), "--height", str(H), "--no-png",
            "--quiet", "-o", str(out), *args)
    assert p.returncode == 0, p.stderr
    return lanterna.read_exr(out)


def edited_scene(tmp_path, edit):
    """cornell-lights' JSON passed through ``edit`` (which changes it in place), written
    beside a copy of its buffer; returns the new file's path."""
    import json
    import shutil

    gltf = json.loads(SCENE.read_text())
    edit(gltf)
    shutil.copy(SCENE.with_suffix(".bin"), tmp_path / "cornell-lights.bin")
    path = tmp_path / "edited.gltf"
    path.write_text(json.dumps(gltf))
    return path


def render_pt(path, **load):
    """A 4-spp ``pt`` render of the scene at ``path`` loaded with ``load``'s options."""
    return lanterna.Renderer(lanterna.load_scene(path, **load), W, H, method="pt", seed=1).render(spp=4)


def test_render_equals_cli_bit_for_bit(scene, ris, cli, tmp_path):
    img = ris.render(spp=6, sample_offset=5)
    ref = cli_render(cli, tmp_path, "--method", "ris", "--seed", "3", "--max-depth", "3",
                     "--spp", "6", "--sample-offset", "5")
    assert img.dtype == np.float32 and img.shape == (H, W, 3)
    assert img.sums is not None and img.sums.dtype == np.uint64
    np.testing.assert_array_equal(img.sums, ref.sums)
    np.testing.assert_array_equal(np.asarray(img), np.asarray(ref))
    for key in ("spp", "sample_offset", "method", "seed", "max_depth", "scene_hash",
                "source", "ris_candidates", "strategy", "rr_depth"):
        assert img.meta[key] == ref.meta[key], key
    assert img.meta["spp"] == 6 and img.meta["sample_offset"] == 5
    assert img.meta["rays"] == (img.meta["camera_rays"] + img.meta["bounce_rays"] + img.meta["shadow_rays"]
                                + img.meta["probe_rays"])
    # One camera ray per sample, and one more in pixels with small emitters in view.
    assert img.meta["camera_rays"] >= 6 * W * H
    plain = lanterna.Renderer(scene, W, H, method="ris", max_depth=3, seed=3, pixel_emitters=False)
    assert plain.render(spp=6, sample_offset=5).meta["camera_rays"] == 6 * W * H
    assert img.meta["gpu_seconds"] > 0 and img.meta["render_seconds"] > 0


def test_disjoint_sample_offsets_merge_to_the_one_shot_render(ris):
    a = ris.render(spp=3, sample_offset=0)
    b = ris.render(spp=5, sample_offset=3)
    one = ris.render(spp=8)
    np.testing.assert_array_equal(a.sums + b.sums, one.sums)
    merged = lanterna.merge([a, b])
    np.testing.assert_array_equal(merged.sums, one.sums)
    np.testing.assert_array_equal(np.asarray(merged), np.asarray(one))
    assert merged.meta["spp"] == 8 and merged.meta["sample_offset"] == 0


def test_aovs_match_the_cli(pt, cli, tmp_path):
    img = pt.render(spp=2, aovs=["albedo", "depth", "sample-count"])
    ref = cli_render(cli, tmp_path, "--spp", "2", "--aov", "albedo,depth,sample-count")
    assert set(img.aovs) == {"albedo", "depth", "sample-count"}
    assert img.aovs["albedo"].shape == (H, W, 3) and img.aovs["depth"].shape == (H, W)
    assert img.aov_channels["albedo"] == ("R", "G", "B")
    np.testing.assert_array_equal(img.aovs["sample-count"], 2.0)
    for name in img.aovs:
        np.testing.assert_array_equal(img.aovs[name], ref.aovs[name])
    # The film does not depend on whether AOVs are accumulated.
    np.testing.assert_array_equal(img.sums, ref.sums)
    plain = cli_render(cli, tmp_path, "--spp", "2")
    np.testing.assert_array_equal(img.sums, plain.sums)


def test_time_budget_and_progress(pt):
    calls = []
    img = pt.render(seconds=0.5, progress=lambda done, t: calls.append((done, t)))
    assert img.meta["spp"] >= 1
    assert calls and calls[-1][0] == img.meta["spp"]
    assert [c[0] for c in calls] == sorted(c[0] for c in calls)


def test_progress_callback_errors_propagate(pt):
    def stop(done, t):
        raise RuntimeError("stop here")

    try:
        pt.render(spp=4, progress=stop)
    except RuntimeError as e:
        assert "stop here" in str(e)
    else:
        raise AssertionError("the callback's exception was swallowed")
    assert pt.render(spp=1).meta["spp"] == 1


def test_gil_is_released_while_rendering(pt):
    import threading

    done = threading.Event()
    t = threading.Thread(target=lambda: (pt.render(spp=64), done.set()))
    t.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        done.wait(0.001)
    t.join()
    # With the GIL held for the whole render the loop would not run at all.
    assert ticks > 20


def test_image_shows_itself_as_png(pt):
    img = pt.render(spp=1)
    png = img._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert "32×24" in repr(img)
    assert img[:, :, 0]._repr_png_() is None


def test_clip_planes_follow_the_file_unless_turned_off(tmp_path):
    """The file camera's znear/zfar clip camera rays (``--no-clip-planes`` as
    ``clip_planes=False``): a far plane in front of cornell-lights' back wall leaves the
    wall's pixels black, and turning the planes off shows it."""
    path = edited_scene(tmp_path, lambda g: g["cameras"][0]["perspective"].update(znear=3.3, zfar=4.6))
    wall = {}
    for clip in (True, False):
        wall[clip] = np.asarray(render_pt(path, clip_planes=clip))[H // 4, W // 2]
    assert np.all(wall[True] == 0.0), wall
    assert np.all(wall[False] > 0.05), wall


def test_animation_time_poses_the_scene(tmp_path):
    """``animation_time=`` (``--animation-time``) poses the file's animations: the
    blockers of cornell-lights, lifted 0.3 by a one-second animation, cast their shadow
    elsewhere at time 1 than at time 0, and the file's static pose is time 0's; an
    unknown animation and a time that is not a number are ValueErrors."""
    import base64
    import struct

    import pytest

    def animate(gltf):
        data = struct.pack("<8f", 0, 1, 0, 0, 0, 0, 0.3, 0)
        gltf["buffers"].append({"byteLength": len(data),
                                "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()})
        buffer = len(gltf["buffers"]) - 1
        gltf["bufferViews"] += [{"buffer": buffer, "byteOffset": 0, "byteLength": 8},
                                {"buffer": buffer, "byteOffset": 8, "byteLength": 24}]
        views = len(gltf["bufferViews"])
        gltf["accessors"] += [{"bufferView": views - 2, "componentType": 5126, "count": 2, "type": "SCALAR",
                               "min": [0], "max": [1]},
                              {"bufferView": views - 1, "componentType": 5126, "count": 2, "type": "VEC3"}]
        accessors = len(gltf["accessors"])
        blockers = next(i for i, n in enumerate(gltf["nodes"]) if n.get("name") == "blockers")
        gltf["animations"] = [{"name": "lift", "samplers": [{"input": accessors - 2, "output": accessors - 1}],
                               "channels": [{"sampler": 0, "target": {"node": blockers, "path": "translation"}}]}]

    path = edited_scene(tmp_path, animate)
    still, start = render_pt(path), render_pt(path, animation_time=0.0)
    lifted = render_pt(path, animation_time=1.0, animation="lift")
    # The pose is recorded in the metadata, and makes a scene of its own.
    assert lifted.meta["animation_time"] == 1 and lifted.meta["animation"] == "lift"
    assert "animation_time" not in still.meta
    assert lifted.meta["scene_hash"] != still.meta["scene_hash"]
    still, start, lifted = (np.asarray(i) for i in (still, start, lifted))
    np.testing.assert_array_equal(still, start)
    assert np.abs(lifted - start).mean() > 0.01 * start.mean()
    assert lanterna.load_scene(path).info()["animations"][0]["name"] == "0 (`lift`)"
    with pytest.raises(ValueError, match="no animation matches `walk`"):
        lanterna.load_scene(path, animation="walk")
    with pytest.raises(ValueError, match="not a finite number"):
        lanterna.load_scene(path, animation_time=float("nan"))


def test_material_variant_is_chosen_by_name_or_index(tmp_path):
    """``variant=`` (``--variant``) renders a KHR_materials_variants variant: the
    blockers of cornell-lights in a blue variant render differently from the file's own
    white, by name and by index alike; an unknown variant is a ValueError naming the
    variants."""
    import pytest

    def add_variants(gltf):
        blue = len(gltf["materials"])
        gltf["materials"].append({"name": "blue", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.2, 0.8, 1]}})
        gltf["extensionsUsed"] = ["KHR_materials_variants"]
        gltf["extensions"] = {"KHR_materials_variants": {"variants": [{"name": "white"}, {"name": "blue"}]}}
        blockers = next(m for m in gltf["meshes"] if m.get("name") == "blockers")
        blockers["primitives"][0]["extensions"] = {
            "KHR_materials_variants": {"mappings": [{"material": blue, "variants": [1]}]}}

    path = edited_scene(tmp_path, add_variants)
    own, white = render_pt(path), render_pt(path, variant="white")
    by_name, by_index = render_pt(path, variant="blue"), render_pt(path, variant=1)
    assert by_index.meta["variant"] == "blue" and "variant" not in own.meta
    own, white, by_name, by_index = (np.asarray(i) for i in (own, white, by_name, by_index))
    np.testing.assert_array_equal(own, white)
    np.testing.assert_array_equal(by_name, by_index)
    assert np.abs(by_name - own).mean() > 0.01 * own.mean()
    assert lanterna.load_scene(path).info()["material_variants"] == ["white", "blue"]
    with pytest.raises(ValueError, match="no material variant matches `red`"):
        lanterna.load_scene(path, variant="red")
