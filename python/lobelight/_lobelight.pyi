"""Type stubs of the native module (python/src/lib.rs)."""

from os import PathLike
from typing import Any, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

class LobelightError(Exception):
    """What lobelight refuses; the message is the command's one line."""

Vec3 = Union[Sequence[float], npt.NDArray[np.floating]]
ArrayParts = Tuple[str, npt.NDArray[np.float32], Optional[npt.NDArray[np.float32]],
                   Optional[npt.NDArray[np.float32]], Optional[npt.NDArray[np.float32]],
                   Optional[npt.NDArray[np.uint32]]]

class Scene:
    @staticmethod
    def load(path: Union[str, PathLike[str]]) -> Scene: ...
    @staticmethod
    def parse(text: str, path: Union[str, PathLike[str]], arrays: Sequence[ArrayParts]) -> Scene: ...
    @property
    def splats(self) -> int: ...
    @property
    def resolution(self) -> Tuple[int, int]: ...
    @property
    def surfaces(self) -> list[str]: ...
    @property
    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]: ...

class Renderer:
    def __init__(self, scene: Scene, engine: str = "auto", progress: bool = False) -> None: ...
    @property
    def engine(self) -> str: ...
    @property
    def adapter(self) -> str: ...
    @property
    def fallback(self) -> Optional[str]: ...
    @property
    def baked(self) -> bool: ...
    def bake(self, cache: Optional[Union[str, PathLike[str]]] = None) -> dict[str, Any]: ...
    def render(self, spp: int = 16, method: str = "lobes", eye: Optional[Vec3] = None,
               target: Optional[Vec3] = None, up: Optional[Vec3] = None,
               fov: Optional[float] = None, width: Optional[int] = None,
               height: Optional[int] = None) -> npt.NDArray[np.float32]: ...
    def object_ids(self, eye: Optional[Vec3] = None, target: Optional[Vec3] = None,
                   up: Optional[Vec3] = None, fov: Optional[float] = None,
                   width: Optional[int] = None,
                   height: Optional[int] = None) -> npt.NDArray[np.uint16]: ...
    def tone_map(self, key: float = 0.18, exposure: float = 0.0) -> npt.NDArray[np.uint8]: ...

def tone_map(hdr: npt.NDArray[np.float32], key: float = 0.18,
             exposure: float = 0.0) -> npt.NDArray[np.uint8]: ...

def save(path: Union[str, PathLike[str]],
         image: Union[npt.NDArray[np.uint8], npt.NDArray[np.float32]]) -> None: ...
