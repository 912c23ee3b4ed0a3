from os import PathLike
from typing import Any, Optional, Union

import numpy as np
import numpy.typing as npt

class SceneError(Exception):
    """A scene that cannot be read: ``file``, ``line`` and ``column`` say where."""

    file: str
    line: Optional[int]
    column: Optional[int]

def render(
    scene: Union[str, PathLike[str]],
    *,
    passes: Optional[int] = None,
    time: Optional[float] = None,
    resolution: Optional[tuple[int, int]] = None,
    seed: int = 1,
    threads: int = 0,
    **settings: Any,
) -> npt.NDArray[np.float32]: ...
class Render:
    """A render seen pass by pass: iterating yields the image after each pass."""

    def __init__(self, scene: Union[str, PathLike[str]], **settings: Any) -> None:
        """Starts rendering; ``settings`` are ``render``'s keywords."""
    def __iter__(self) -> "Render": ...
    def __next__(self) -> npt.NDArray[np.float32]: ...
    @property
    def stats(self) -> Optional[dict[str, Any]]:
        """The phase table, passes and seconds once the render has ended."""
    @property
    def pass_seconds(self) -> list[float]: ...
    def save_film(self, path: Union[str, PathLike[str]]) -> None: ...

def merge(
    films: list[Union[str, PathLike[str]]],
    *,
    output: Optional[Union[str, PathLike[str]]] = None,
    film: Optional[Union[str, PathLike[str]]] = None,
    expect: Optional[int] = None,
) -> npt.NDArray[np.float32]: ...

def density(**settings: Any) -> tuple[npt.NDArray[np.float32], dict[str, Any]]:
    """The paper's density experiment (``dpm density``'s flags as keywords): the estimated
    density and its report (metrics against the exact density, seconds)."""

def check(scene: Union[str, PathLike[str]]) -> list[dict[str, Any]]: ...
