"""Bad arguments and missing files raise the Python exception that fits, with the
message the CLI prints after `error: `."""

import pytest

import lanterna
from conftest import SCENE


def cli_error(cli, *args):
    p = cli("render", str(SCENE), "--width", "8", "--height", "6", "--no-png", "--quiet",
            "-o", "/dev/null", *args)
    assert p.returncode != 0
    return p.stderr


@pytest.mark.parametrize(
    "kwargs, flags",
    [
        ({"method": "fast"}, ["--method", "fast"]),
        ({"max_depth": 0}, ["--max-depth", "0"]),
        ({"ris_candidates": 0, "method": "ris"}, ["--ris-candidates", "0", "--method", "ris"]),
        ({"bsdf_fraction": 1.5, "method": "guided"}, ["--bsdf-fraction", "1.5", "--method", "guided"]),
        ({"light_mix": 1.0, "method": "guided"}, ["--light-mix", "1", "--method", "guided"]),
        ({"light_reuse": "world", "method": "pt"}, ["--light-reuse", "world", "--method", "pt"]),
        ({"light_reuse": "world", "method": "ris", "reuse_cap": 0.5},
         ["--light-reuse", "world", "--method", "ris", "--reuse-cap", "0.5"]),
        ({"light_visibility": "learned", "method": "guided"},
         ["--light-visibility", "learned", "--method", "guided"]),
        ({"light_visibility": "learned", "method": "ris", "visibility_floor": 0.0},
         ["--light-visibility", "learned", "--method", "ris", "--visibility-floor", "0"]),
        ({"camera": "nope"}, ["--camera", "nope"]),
    ],
)
def test_bad_renderer_arguments(scene, cli, kwargs, flags):
    kwargs = dict(kwargs)
    s = scene
    if "camera" in kwargs:
        with pytest.raises(ValueError) as e:
            lanterna.load_scene(SCENE, camera=kwargs.pop("camera"))
    else:
        with pytest.raises(ValueError) as e:
            lanterna.Renderer(s, 8, 6, **kwargs)
    assert str(e.value) in cli_error(cli, *flags)


@pytest.mark.parametrize(
    "kwargs, flags",
    [({"spp": 0}, ["--spp", "0"]), ({"seconds": -1.0}, ["--time=-1"]), ({"seconds": 0}, ["--time", "0"])],
)
def test_bad_budgets(pt, cli, kwargs, flags):
    with pytest.raises(ValueError) as e:
        pt.render(**kwargs)
    assert str(e.value) in cli_error(cli, *flags)


def test_other_bad_arguments(scene, pt):
    with pytest.raises(ValueError, match="unknown AOV `colour`"):
        pt.render(spp=1, aovs=["colour"])
    with pytest.raises(ValueError, match="sample-offset"):
        pt.render(spp=1, sample_offset=-1)
    with pytest.raises(ValueError, match="--source"):
        lanterna.Renderer(scene, 8, 6, source="brightest")
    with pytest.raises(ValueError, match="expected auto, learned or a probability"):
        lanterna.Renderer(scene, 8, 6, method="guided", light_mix="sometimes")
    for mix in ("auto", "learned", None, 0.3):
        lanterna.Renderer(scene, 8, 6, method="guided", light_mix=mix)
    with pytest.raises(ValueError, match="--selection-learner"):
        lanterna.Renderer(scene, 8, 6, method="guided", selection_learner="adam")
    for learner in ("variance", "kl-adam"):
        lanterna.Renderer(scene, 8, 6, method="guided", selection_learner=learner)
    with pytest.raises(TypeError, match="unexpected keyword argument 'spp'"):
        lanterna.Renderer(scene, 8, 6, spp=4)
    with pytest.raises(ValueError, match="--load-guiding needs --method guided or guided-ris"):
        lanterna.Renderer(scene, 8, 6, load_guiding="tree.sdt")
    with pytest.raises(ValueError, match="train\\(\\) needs method guided or guided-ris"):
        pt.train(spp=3)
    with pytest.raises(ValueError):
        lanterna.Renderer(scene, 8, 6, device="no such device")


def test_missing_scene(cli, tmp_path):
    missing = tmp_path / "missing.gltf"
    with pytest.raises(FileNotFoundError) as e:
        lanterna.load_scene(missing)
    p = cli("render", str(missing), "--no-png", "-o", str(tmp_path / "x.exr"))
    assert p.returncode != 0 and str(e.value) in p.stderr
    with pytest.raises(FileNotFoundError):
        lanterna.read_exr(tmp_path / "missing.exr")
