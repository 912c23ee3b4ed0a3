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
def check(scene: Union[str, PathLike[str]]) -> list[dict[str, Any]]: ...
