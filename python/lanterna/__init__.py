"""lanterna — a GPU path tracer for scenes lit by many lights, from Python.

The same Rust library as the ``lanterna`` command line (Vulkan ray queries; lavapipe as
the fallback device), with numpy arrays in and out::

    import lanterna
    scene = lanterna.load_scene("scenes/cornell-lights.gltf")
    r = lanterna.Renderer(scene, 64, 48, method="ris")
    img = r.render(spp=64)              # float32 (48, 64, 3) array with img.meta
    ref = r.render(spp=1024, sample_offset=64)
    print(lanterna.mae(img, ref), img.meta["gpu_seconds"])

A ``Renderer`` keeps the device, the acceleration structures and the compiled pipelines,
so renders in a loop pay no setup. Rendering releases the GIL; Ctrl-C raises
``KeyboardInterrupt`` within about half a second and leaves the renderer usable. Errors
are Python exceptions with the command line's messages: ``ValueError`` for bad
arguments, ``FileNotFoundError`` for a missing file, ``RuntimeError`` for the device.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _lanterna
from ._image import Image, from_parts, to_parts

__version__: str = _lanterna.__version__
Scene = _lanterna.Scene

__all__ = [
    "Image",
    "Renderer",
    "Scene",
    "compare",
    "load_scene",
    "mae",
    "merge",
    "read_exr",
    "relmse",
    "write_exr",
    "METHODS",
]

#: The rendering methods, as the command line's ``--method`` names them.
METHODS: Tuple[str, ...] = ("pt", "ris", "guided", "guided-ris")

PathLike = Union[str, "os.PathLike[str]"]
#: ``progress=`` of ``render``/``train``/``compare``: None for a tqdm bar when tqdm is
#: installed, False for none, or a callable taking (spp done, seconds elapsed).
Progress = Union[None, bool, Callable[[int, float], Any]]


def load_scene(
    path: PathLike,
    camera: Union[str, int, None] = None,
    look_at: Optional[Sequence[float]] = None,
    fov: Optional[float] = None,
    clip_planes: bool = True,
    animation_time: Optional[float] = None,
    animation: Union[str, int, None] = None,
    variant: Union[str, int, None] = None,
) -> Scene:
    """Load a glTF 2.0 scene (.gltf or .glb) and its light table.

    Args:
        path: the scene file; ``FileNotFoundError`` if it does not exist.
        camera: the file's camera by index or name (default: the first), like ``--camera``.
        look_at: ``(ex, ey, ez, tx, ty, tz)``: view from eye to target instead, like ``--look-at``.
        fov: vertical field of view in degrees (overrides the camera's), like ``--fov``.
        clip_planes: honour the file camera's znear/zfar (False: ``--no-clip-planes``).
        animation_time: pose the file's animations at this time in seconds, like ``--animation-time``.
        animation: play only this animation, by index or name, like ``--animation``.
        variant: the material variant (KHR_materials_variants) by name or index, like ``--variant``.

    ``scene.info()`` returns the statistics of ``lanterna info SCENE`` as a dict.
    """
    return _lanterna.load_scene(
        os.fspath(path),
        camera=camera,
        look_at=None if look_at is None else [float(v) for v in look_at],
        fov=fov,
        clip_planes=bool(clip_planes),
        animation_time=None if animation_time is None else float(animation_time),
        animation=animation,
        variant=variant,
    )


class _Bar:
    """The progress callback for ``progress=``: a tqdm bar, a user callback, or nothing."""

    def __init__(self, progress: Progress, total: Optional[int], seconds: Optional[float], what: str):
        self.callback: Optional[Callable[[int, float], Any]] = None
        self.bar = None
        self.seconds = seconds is not None
        if callable(progress):
            self.callback = progress
        elif progress is None or progress is True:
            try:
                from tqdm.auto import tqdm
            except ImportError:
                return
            if seconds is not None:
                self.bar = tqdm(total=round(seconds, 1), desc=what, unit="s", leave=False)
            else:
                self.bar = tqdm(total=total, desc=what, unit="spp", leave=False)

    def __call__(self, done: int, elapsed: float) -> None:
        if self.callback is not None:
            self.callback(done, elapsed)
        if self.bar is not None:
            self.bar.n = round(min(elapsed, self.bar.total), 1) if self.seconds else done
            self.bar.set_postfix_str(f"{done} spp", refresh=False)
            self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()

    def native(self) -> Optional[Callable[[int, float], Any]]:
        return self if (self.callback or self.bar) else None


class Renderer:
    """A scene on a Vulkan device, ready to render repeatedly.

    Args:
        scene: from ``load_scene``.
        width, height: image size; give one and the other follows the camera's aspect
            ratio (default width 512), as on the command line.
        method: ``"pt"``, ``"ris"``, ``"guided"`` or ``"guided-ris"``.
        max_depth: path segments, counted like Mitsuba's ``max_depth``.
        seed: seed of the random numbers; the image is a deterministic function of it.
        device: Vulkan device by index or name substring (default: the best capable).
        load_guiding: a saved SD-tree (``save_guiding``) for guided renders to use.
        **options: the command line's other estimator flags with ``_`` for ``-``:
            ``rr_depth``, ``source`` ("uniform"/"power"/"tree"), ``ris_candidates``,
            ``bsdf_fraction``, ``selection_learner`` ("variance", the default, or
            "kl-adam"), ``train_fraction``, ``record_nee`` (bool),
            ``guide_target`` ("all"/"indirect"/"contribution"), ``guide_density``
            ("radiance"/"variance-aware"), ``guide_history`` (0–1, weight of the earlier
            training iterations in each refit; default 0),
            ``strategy`` ("mis"/"nee"/"bsdf"), ``hide_emitters``, ``emission_rays`` (camera
            rays per sample, 1–64), ``pixel_emitters`` (bool, default True: small
            emitters seen directly are sampled inside their pixels), ``guiding_threshold``,
            ``guiding_memory`` (MiB), ``spatial_filter`` ("nearest", the default, or "jitter"),
            ``directional_filter`` ("box"/"nearest"), ``guided_output``
            ("all-passes", the default, "late-passes", "render-phase" or
            "inverse-variance"), ``learn_lights`` (bool,
            default True; False: the paper's light selection),
            ``light_mix`` (a probability, "learned", or "auto"/None), ``light_reuse``
            ("off", the default, or "world": RIS reservoirs shared between samples through
            a world-space hash grid; `ris` and `guided-ris`), ``reuse_cell_pixels``,
            ``reuse_cap``, ``light_visibility`` ("off", the default, or "learned": RIS's
            target weighs each light by its learned unoccluded share; `ris` and
            `guided-ris`), ``visibility_cell_pixels``, ``visibility_floor``, ``traversal``
            ("auto"/"ray-query"/"software"); and
            ``validation`` (Vulkan validation layers),
            ``shader_dir`` (compile the GLSL kernels from a directory).

    Renderers with the same device share it. Construction uploads the scene, builds
    the acceleration structures and compiles the method's pipelines (the first time a
    kernel variant is compiled on lavapipe takes a while; the driver caches it on disk).
    """

    def __init__(
        self,
        scene: Scene,
        width: Optional[int] = None,
        height: Optional[int] = None,
        method: str = "pt",
        max_depth: int = 4,
        seed: int = 0,
        device: Union[int, str, None] = None,
        load_guiding: Optional[PathLike] = None,
        **options: Any,
    ) -> None:
        self._native = _lanterna.Renderer(
            scene,
            width,
            height,
            method,
            max_depth,
            seed,
            device,
            None if load_guiding is None else os.fspath(load_guiding),
            **options,
        )

    scene = property(lambda self: self._native.scene, doc="The scene.")
    width = property(lambda self: self._native.width, doc="Image width in pixels.")
    height = property(lambda self: self._native.height, doc="Image height in pixels.")
    method = property(lambda self: self._native.method, doc="The rendering method.")
    max_depth = property(lambda self: self._native.max_depth, doc="Maximum path segments.")
    seed = property(lambda self: self._native.seed, doc="The random seed.")
    device = property(lambda self: self._native.device, doc="The Vulkan device's name.")
    setup_seconds = property(
        lambda self: self._native.setup_seconds,
        doc="Seconds construction took (scene upload, acceleration structures, pipelines).",
    )
    has_guiding = property(
        lambda self: self._native.has_guiding,
        doc="Whether guided renders use a fixed SD-tree (from train() or load_guiding=).",
    )

    def render(
        self,
        spp: Optional[int] = None,
        seconds: Optional[float] = None,
        *,
        sample_offset: int = 0,
        aovs: Optional[Iterable[str]] = None,
        progress: Progress = None,
    ) -> Image:
        """Render ``spp`` samples per pixel (default 16), or for ``seconds`` of wall time.

        Args:
            spp: samples per pixel (guided methods: training included, unless the
                renderer has a fixed SD-tree).
            seconds: render for this long instead (every pixel gets the same spp).
            sample_offset: first sample index: renders samples
                ``[sample_offset, sample_offset + spp)``. Renders of disjoint ranges
                are independent and ``merge`` combines them exactly.
            aovs: first-hit layers to return in ``image.aovs``: ``albedo``, ``normal``,
                ``depth``, ``position``, ``light-count``, ``ris-weight``,
                ``selected-light``, ``guide-fraction``, ``sample-count``. The first
                render with AOVs sets the renderer up for them (once).
            progress: None for a tqdm bar when tqdm is installed, False for none, or a
                callable ``f(spp_done, seconds_elapsed)`` called between chunks.

        Returns:
            An ``Image``: the float32 ``(height, width, 3)`` mean radiance with
            ``meta`` (spp, sample_offset, render_seconds, gpu_seconds, rays, ...) and
            ``sums``, the film's exact sums. Guided methods with
            ``guided_output="inverse-variance"`` have no exact sums.
        """
        bar = _Bar(progress, spp if seconds is None else None, seconds, f"{self.method}")
        try:
            parts = self._native.render(
                spp=spp,
                seconds=seconds,
                sample_offset=sample_offset,
                aovs=None if aovs is None else list(aovs),
                progress=bar.native(),
            )
        finally:
            bar.close()
        return from_parts(parts)

    def train(
        self,
        spp: Optional[int] = None,
        seconds: Optional[float] = None,
        *,
        sample_offset: int = 1 << 31,
        progress: Progress = None,
    ) -> Dict[str, Any]:
        """Train an SD-tree (guided methods) with the whole budget: iterations of 1, 2,
        4, … spp while they fit in ``spp`` (or in ``seconds``). Later renders use it
        for their whole budget until ``reset_guiding()``.

        Training samples start at ``sample_offset`` (default 2^31), disjoint from
        renders' usual ranges, so that the image is independent of what the tree
        learned from.

        Returns:
            ``{"spp": …, "seconds": …, "iterations": [{…}, …]}`` with each iteration's
            spp, timings, leaves and nodes.
        """
        bar = _Bar(progress, spp if seconds is None else None, seconds, f"train {self.method}")
        try:
            return self._native.train(
                spp=spp, seconds=seconds, sample_offset=sample_offset, progress=bar.native()
            )
        finally:
            bar.close()

    def reset_guiding(self) -> None:
        """Forget the fixed SD-tree: guided renders train their share of the budget again."""
        self._native.reset_guiding()

    def save_guiding(self, path: PathLike) -> None:
        """Save the SD-tree the last guided render or ``train()`` used (for
        ``load_guiding=`` or ``lanterna render --load-guiding``)."""
        self._native.save_guiding(os.fspath(path))

    def guiding_leaf(self, x: int, y: int, size: int = 256) -> Dict[str, Any]:
        """The sampling quadtree of the SD-tree leaf that pixel (x, y)'s first hit falls
        in (what ``lanterna guiding view`` draws).

        Returns a dict with ``density`` (float32 ``(size, size)``: the directional
        density on the (cosθ, φ) square, 1 = uniform; x = (cosθ + 1)/2, y = φ/2π),
        ``image`` (float32 ``(size, size, 3)``: the same colour-mapped on a log scale
        with cell lines), ``position`` (the first hit), and the leaf's ``leaf``,
        ``depth``, ``box_min``, ``box_size``, ``sampling_weight``, ``training_weight``,
        ``nodes``, ``quad_depth``, ``min_density``, ``max_density``, ``uniform``.
        """
        size, density, rgb, info, position = self._native._guiding_leaf(x, y, size)
        out = dict(info)
        out["density"] = np.frombuffer(density, dtype="<f4").reshape(size, size)
        out["image"] = np.frombuffer(rgb, dtype="<f4").reshape(size, size, 3)
        out["position"] = tuple(position)
        return out

    def __repr__(self) -> str:
        return repr(self._native)


def _image_arg(x: Any, name: str) -> Tuple[tuple, str]:
    if isinstance(x, (str, os.PathLike)):
        return _lanterna.read_exr(os.fspath(x)), os.fspath(x)
    return to_parts(x), name


def read_exr(path: PathLike) -> Image:
    """Read an EXR: lanterna's own (mean, exact sums, metadata, AOV layers) or any flat
    RGB(A) OpenEXR file (then with empty metadata and no sums)."""
    return from_parts(_lanterna.read_exr(os.fspath(path)))


def write_exr(path: PathLike, image: Any, meta: Optional[Dict[str, Any]] = None) -> None:
    """Write an image (an ``Image`` or any ``(height, width, 3)`` array) as lanterna's
    EXR: the mean, the exact sums and AOV layers when the image has them, and the
    metadata (``meta``, default ``image.meta``), so that ``read_exr`` gives it back and
    ``lanterna merge`` accepts it. The file is written to a temporary name and renamed."""
    nonfinite = _lanterna.write_exr(os.fspath(path), to_parts(image, meta))
    if nonfinite:
        warnings.warn(f"{os.fspath(path)}: {nonfinite} non-finite pixel values", stacklevel=2)


def merge(images: Sequence[Any], names: Optional[Sequence[str]] = None) -> Image:
    """Merge renders of disjoint sample ranges of one scene and setting (images or EXR
    paths), like ``lanterna merge``: exactly, by adding the film sums, when every input
    has them. Raises ``ValueError`` for another scene, size, method, seed or depth, or
    overlapping ranges."""
    parts, labels = [], []
    for i, x in enumerate(images):
        p, label = _image_arg(x, names[i] if names else f"image {i}")
        parts.append(p)
        labels.append(label)
    merged, _exact, notes = _lanterna.merge_images(parts, labels)
    for note in notes:
        warnings.warn(note, stacklevel=2)
    return from_parts(merged)


def mae(image: Any, reference: Any) -> float:
    """Mean absolute error over pixels and RGB channels (images, arrays or EXR paths),
    in f64, as ``lanterna compare`` computes it."""
    return _lanterna.mae(_image_arg(image, "image")[0], _image_arg(reference, "reference")[0])


def relmse(image: Any, reference: Any) -> float:
    """Relative MSE: mean of (x − r)² / (r² + 0.01) over pixels and RGB channels."""
    return _lanterna.relmse(_image_arg(image, "image")[0], _image_arg(reference, "reference")[0])


def compare(
    renderer: Renderer,
    reference: Any,
    methods: Sequence[str] = METHODS,
    spp: Sequence[int] = (),
    seconds: Sequence[float] = (),
    *,
    out_dir: Optional[PathLike] = None,
    crop: Optional[Tuple[int, int, int, int]] = None,
    exposure: float = 0.0,
    save_images: bool = False,
    progress: Progress = False,
) -> Dict[str, Any]:
    """``lanterna compare`` on the renderer's scene, view and settings: every method at
    every equal-spp and equal-time budget, scored against ``reference`` (an image or an
    EXR path of the same size and max depth).

    Writes ``report.json``, ``report.csv``, the plots, the image grid and
    ``index.html`` into ``out_dir`` (a temporary directory, removed afterwards, when
    None) and returns the report as a dict: ``records`` holds per method and budget the
    spp, render/setup/GPU/training seconds, MAE, relMSE and their ratios to ``pt``.
    The renderer keeps its own method afterwards.
    """
    ref, name = _image_arg(reference, "reference")
    bar = _Bar(progress, None, None, "compare")
    tmp = tempfile.TemporaryDirectory(prefix="lanterna-compare-") if out_dir is None else None
    try:
        return renderer._native._compare(
            ref,
            name,
            list(methods),
            [int(n) for n in spp],
            [float(s) for s in seconds],
            tmp.name if tmp else os.fspath(out_dir),
            crop=None if crop is None else tuple(int(v) for v in crop),
            exposure=exposure,
            save_images=save_images,
            progress=bar.native(),
        )
    finally:
        bar.close()
        if tmp:
            tmp.cleanup()
