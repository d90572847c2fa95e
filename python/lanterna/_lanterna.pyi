"""Type stubs of the extension module (src/python/). Images cross it as tuples
``(width, height, rgb, sums, meta, aovs)``: ``rgb`` little-endian float32 bytes
(H×W×3), ``sums`` little-endian uint64 bytes (H×W×3) or None, ``meta`` a dict, ``aovs``
a list of ``(name, [channel, ...], float32 bytes)``. Use the ``lanterna`` package, which
turns them into numpy arrays."""

from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

ImageParts = Tuple[
    int,
    int,
    Union[bytes, bytearray],
    Optional[Union[bytes, bytearray]],
    Optional[Dict[str, Any]],
    List[Tuple[str, List[str], Union[bytes, bytearray]]],
]
ProgressCallback = Callable[[int, float], Any]

__version__: str
#: The keyword options ``Renderer`` accepts besides its named parameters.
OPTIONS: List[str]

class Scene:
    """A glTF scene with its light table (``load_scene``)."""

    @property
    def path(self) -> str: ...
    @property
    def hash(self) -> str: ...
    @property
    def cameras(self) -> List[str]: ...
    @property
    def load_seconds(self) -> float: ...
    def info(self) -> Dict[str, Any]:
        """``lanterna info SCENE --json`` as a dict, plus the cameras' names."""

def load_scene(
    path: str,
    camera: Union[str, int, None] = None,
    look_at: Optional[Sequence[float]] = None,
    fov: Optional[float] = None,
    clip_planes: bool = True,
    animation_time: Optional[float] = None,
    animation: Union[str, int, None] = None,
    variant: Union[str, int, None] = None,
) -> Scene: ...

class Renderer:
    def __init__(
        self,
        scene: Scene,
        width: Optional[int] = None,
        height: Optional[int] = None,
        method: str = "pt",
        max_depth: int = 4,
        seed: int = 0,
        device: Union[int, str, None] = None,
        load_guiding: Optional[str] = None,
        **options: Any,
    ) -> None: ...
    @property
    def scene(self) -> Scene: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def method(self) -> str: ...
    @property
    def max_depth(self) -> int: ...
    @property
    def seed(self) -> int: ...
    @property
    def device(self) -> str: ...
    @property
    def setup_seconds(self) -> float: ...
    @property
    def has_guiding(self) -> bool: ...
    def render(
        self,
        spp: Optional[int] = None,
        seconds: Optional[float] = None,
        sample_offset: int = 0,
        aovs: Optional[List[str]] = None,
        progress: Optional[ProgressCallback] = None,
    ) -> ImageParts: ...
    def train(
        self,
        spp: Optional[int] = None,
        seconds: Optional[float] = None,
        sample_offset: int = 2147483648,
        progress: Optional[ProgressCallback] = None,
    ) -> Dict[str, Any]: ...
    def reset_guiding(self) -> None: ...
    def save_guiding(self, path: str) -> None: ...
    def _guiding_leaf(
        self, x: int, y: int, size: int = 256
    ) -> Tuple[int, bytearray, bytearray, Dict[str, Any], List[float]]: ...
    def _compare(
        self,
        reference: ImageParts,
        reference_name: str,
        methods: List[str],
        spp: List[int],
        seconds: List[float],
        out_dir: str,
        crop: Optional[Tuple[int, int, int, int]] = None,
        exposure: float = 0.0,
        save_images: bool = False,
        progress: Optional[ProgressCallback] = None,
    ) -> Dict[str, Any]: ...
    def _device_memory(self) -> Tuple[int, int]: ...

def read_exr(path: str) -> ImageParts: ...
def write_exr(path: str, image: ImageParts) -> int: ...
def merge_images(
    images: List[ImageParts], names: List[str]
) -> Tuple[ImageParts, bool, List[str]]: ...
def mae(image: ImageParts, reference: ImageParts) -> float: ...
def relmse(image: ImageParts, reference: ImageParts) -> float: ...
def png(image: ImageParts, exposure: float = 0.0) -> bytes: ...
def validation_error_count() -> int: ...
