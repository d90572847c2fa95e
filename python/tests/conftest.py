"""Shared fixtures: the scene, renderers kept for the whole session (pipelines compile
once), the CLI to compare against, and a check that Vulkan validation stayed quiet."""

import os
import subprocess
from pathlib import Path

# Validation layers on, as in the Rust tests (read when the Vulkan instance is created).
os.environ.setdefault("LANTERNA_VALIDATION", "1")

import pytest  # noqa: E402

import lanterna  # noqa: E402
from lanterna import _lanterna  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "cornell-lights.gltf"
# Tiny images keep every render well under a second on lavapipe.
W, H = 32, 24


def cli_path() -> Path:
    return Path(os.environ.get("LANTERNA_CLI", ROOT / "target" / "release" / "lanterna"))


@pytest.fixture(scope="session")
def cli():
    """Run the lanterna CLI; returns the CompletedProcess (text, never raises)."""
    path = cli_path()
    if not path.exists():
        pytest.skip(f"no CLI at {path} (cargo build --release, or set LANTERNA_CLI)")

    def run(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [str(path), "--log", "error", *args],
            capture_output=True,
            text=True,
            cwd=ROOT,
            timeout=300,
        )

    return run


@pytest.fixture(scope="session")
def scene():
    return lanterna.load_scene(SCENE)


@pytest.fixture(scope="session")
def ris(scene):
    """A RIS renderer (seed 3, depth 3) shared by the tests that only render."""
    return lanterna.Renderer(scene, W, H, method="ris", max_depth=3, seed=3)


@pytest.fixture(scope="session")
def pt(scene):
    return lanterna.Renderer(scene, W, H, method="pt")


@pytest.fixture(scope="session", autouse=True)
def no_validation_errors():
    yield
    assert _lanterna.validation_error_count() == 0, "Vulkan validation errors were reported"
