"""The image type renders and ``read_exr`` return, and the conversions between numpy
arrays and the extension module's image tuples ``(width, height, rgb bytes, sums bytes
or None, meta dict, [(aov name, [channels], bytes), ...])``."""

from __future__ import annotations

from typing import Any, Dict, Mapping, Optional, Sequence, Tuple

import numpy as np

from . import _lanterna

#: Channel names of single-channel AOVs and the defaults for arrays without names.
_DEFAULT_CHANNELS = {1: ("Y",), 2: ("X", "Y"), 3: ("R", "G", "B"), 4: ("R", "G", "B", "A")}


class Image(np.ndarray):
    """A linear-RGB image: a ``float32`` numpy array of shape ``(height, width, 3)``
    with the render's metadata attached.

    Attributes:
        meta: dict — ``spp``, ``sample_offset``, ``method``, ``seed``, ``max_depth``,
            ``render_seconds``, ``device``, ``scene_path``, ``scene_hash``, ``version``
            and free-form entries (a render adds ``gpu_seconds``, ``rays``,
            ``camera_rays``, ``bounce_rays``, ``shadow_rays``, ``probe_rays``, ...).
            ``write_exr`` stores all of it and ``read_exr`` gives it back.
        sums: ``uint64`` array ``(height, width, 3)`` of the film's exact fixed-point
            sums over ``meta["spp"]`` samples, or None. Renders of disjoint sample
            ranges merge exactly by adding them (``lanterna.merge``). Arrays derived
            from an image (slices, arithmetic) do not carry them.
        aovs: dict of AOV name to ``float32`` array, ``(height, width)`` for one
            channel, else ``(height, width, channels)``.
        aov_channels: dict of AOV name to its channel names.

    In Jupyter the image shows itself tonemapped (``_repr_png_``); ``png(exposure)``
    gives those bytes.
    """

    meta: Dict[str, Any]
    sums: Optional[np.ndarray]
    aovs: Dict[str, np.ndarray]
    aov_channels: Dict[str, Tuple[str, ...]]

    def __new__(
        cls,
        rgb: Any,
        meta: Optional[Mapping[str, Any]] = None,
        sums: Optional[np.ndarray] = None,
        aovs: Optional[Mapping[str, np.ndarray]] = None,
        aov_channels: Optional[Mapping[str, Sequence[str]]] = None,
    ) -> "Image":
        obj = np.asarray(rgb, dtype=np.float32).view(cls)
        if obj.ndim != 3 or obj.shape[2] != 3:
            raise ValueError(f"an image is an array of shape (height, width, 3), not {obj.shape}")
        obj.meta = dict(meta or {})
        obj.sums = None if sums is None else np.asarray(sums, dtype=np.uint64)
        if obj.sums is not None and obj.sums.shape != obj.shape:
            raise ValueError(f"sums have shape {obj.sums.shape}, the image {obj.shape}")
        obj.aovs = dict(aovs or {})
        names = dict(aov_channels or {})
        obj.aov_channels = {
            k: tuple(names.get(k) or _DEFAULT_CHANNELS[_channels(v)]) for k, v in obj.aovs.items()
        }
        return obj

    def __array_finalize__(self, obj: Any) -> None:
        # Views and results of arithmetic keep the metadata (a copy), not the exact sums.
        self.meta = dict(getattr(obj, "meta", None) or {})
        self.sums = None
        self.aovs = {}
        self.aov_channels = {}

    @property
    def width(self) -> int:
        return int(self.shape[1])

    @property
    def height(self) -> int:
        return int(self.shape[0])

    @property
    def spp(self) -> Optional[int]:
        """Samples per pixel (``meta["spp"]``)."""
        return self.meta.get("spp")

    def png(self, exposure: float = 0.0) -> bytes:
        """The image tonemapped like the command line's PNG (2^exposure, clamp, sRGB)."""
        return _lanterna.png(to_parts(self), exposure)

    def _repr_png_(self) -> Optional[bytes]:
        if self.ndim != 3 or self.shape[2] != 3 or self.size == 0:
            return None
        return self.png()

    def __repr__(self) -> str:
        if self.ndim != 3 or self.shape[2] != 3:
            return np.asarray(self).__repr__()
        keys = ", ".join(f"{k}={self.meta[k]!r}" for k in ("method", "spp") if k in self.meta)
        return f"<lanterna.Image {self.width}×{self.height}{' ' + keys if keys else ''}>"


def _channels(a: np.ndarray) -> int:
    return 1 if a.ndim == 2 else int(a.shape[2])


def to_parts(image: Any, meta: Optional[Mapping[str, Any]] = None) -> tuple:
    """An image (or any array of shape (height, width, 3)) as the extension's tuple."""
    rgb = np.ascontiguousarray(image, dtype="<f4")
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"expected an array of shape (height, width, 3), not {rgb.shape}")
    h, w, _ = rgb.shape
    if meta is None:
        meta = getattr(image, "meta", None)
    sums = getattr(image, "sums", None)
    if sums is not None:
        sums = np.ascontiguousarray(sums, dtype="<u8").tobytes()
    aovs = []
    names = getattr(image, "aov_channels", {}) or {}
    for name, data in (getattr(image, "aovs", None) or {}).items():
        data = np.ascontiguousarray(data, dtype="<f4")
        if data.shape[:2] != (h, w) or data.ndim not in (2, 3):
            raise ValueError(f"AOV {name!r} has shape {data.shape}, the image {rgb.shape}")
        channels = names.get(name) or _DEFAULT_CHANNELS[_channels(data)]
        aovs.append((name, list(channels), data.tobytes()))
    return (w, h, rgb.tobytes(), sums, None if meta is None else dict(meta), aovs)


def from_parts(parts: tuple) -> Image:
    """The extension's image tuple as an ``Image``."""
    w, h, rgb, sums, meta, aovs = parts
    image = Image(
        np.frombuffer(rgb, dtype="<f4").reshape(h, w, 3),
        meta=meta,
        sums=None if sums is None else np.frombuffer(sums, dtype="<u8").reshape(h, w, 3),
        aovs={
            name: np.frombuffer(data, dtype="<f4").reshape((h, w) if len(ch) == 1 else (h, w, len(ch)))
            for name, ch, data in aovs
        },
        aov_channels={name: tuple(ch) for name, ch, _ in aovs},
    )
    return image
