"""Type stubs of ``shadelab`` (see ``__init__.py`` for the documentation)."""

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

#: A (height, width) pair, or one number for a square.
Size = Union[float, Tuple[float, float], Sequence[float]]
#: An (x, y, z) vector toward the light, "tilt=T,slant=S", a name ("above", …).
LightSpec = Union[str, Tuple[float, float, float], Sequence[float], npt.NDArray[np.floating]]
#: A stimulus name, or an image (H×W, or H×W×3 where colour is accepted) of linear luminance.
PictureSpec = Union[str, npt.ArrayLike]

class Reconstruction:
    normals: npt.NDArray[np.float64]
    depth: npt.NDArray[np.float64]
    f: npt.NDArray[np.float64]
    g: npt.NDArray[np.float64]
    converged: bool
    iterations: int
    report: Dict[str, Any]
    def __init__(
        self,
        normals: npt.NDArray[np.float64],
        depth: npt.NDArray[np.float64],
        f: npt.NDArray[np.float64],
        g: npt.NDArray[np.float64],
        report: Dict[str, Any],
    ) -> None: ...

def stimuli() -> Dict[str, str]: ...
def describe(name: str) -> Dict[str, Any]: ...
# A display file's path (shadelab's display JSON, a PsychoPy monitor file, a photometer CSV) or
# a dict of the display JSON; a luminance mapping (lo, hi) in cd/m², "LO,HI" or
# {"background": B, "michelson": C}.
DisplaySpec = Union[str, "os.PathLike[str]", Dict[str, Any]]
LuminanceSpec = Union[Tuple[float, float], str, Dict[str, float]]

def render(
    name: str,
    *,
    visual_size: Optional[Size] = ...,
    ppd: Optional[float] = ...,
    shape: Optional[Union[int, Tuple[int, int], Sequence[int]]] = ...,
    light: Optional[LightSpec] = ...,
    seed: Optional[int] = ...,
    layers: bool = ...,
    bit_depth: Optional[Literal[8, 16]] = ...,
    gamma: Optional[float] = ...,
    range: Literal["unit", "psychopy"] = ...,
    display: Optional[DisplaySpec] = ...,
    luminance: Optional[LuminanceSpec] = ...,
    **params: Any,
) -> Dict[str, Any]: ...
def solve(
    image: npt.ArrayLike,
    *,
    light: Union[LightSpec, Literal["estimate"]],
    mask: Optional[npt.ArrayLike] = ...,
    boundary: str = ...,
    albedo: Optional[Union[float, Literal["estimate"]]] = ...,
    lam: float = ...,
    method: Literal["multigrid", "jacobi", "literal", "integrable", "integrable-lm"] = ...,
    tol: float = ...,
    max_iter: Optional[int] = ...,
    saturation: Optional[Union[float, Literal["auto", "none"]]] = ...,
) -> Reconstruction: ...
def prior_sweep(
    picture: PictureSpec,
    *,
    ppd: Optional[float] = ...,
    shape: Optional[Union[int, Tuple[int, int]]] = ...,
    mask: Optional[npt.ArrayLike] = ...,
    tilts: Optional[Sequence[float]] = ...,
    binding: Union[None, str, float] = ...,
    domain: str = ...,
    boundary: str = ...,
    slant: float = ...,
    albedo: Optional[float] = ...,
    ambient: Optional[float] = ...,
    seed: Optional[int] = ...,
    **params: Any,
) -> Dict[str, Any]: ...
def observer(
    picture: PictureSpec,
    *,
    ppd: Optional[float] = ...,
    shape: Optional[Union[int, Tuple[int, int]]] = ...,
    mask: Optional[npt.ArrayLike] = ...,
    prior_tilt: Optional[float] = ...,
    kappas: Optional[Sequence[float]] = ...,
    convexity_bias: Optional[float] = ...,
    noise: Optional[float] = ...,
    rotations: Optional[Sequence[float]] = ...,
    tilts: Optional[Sequence[float]] = ...,
    domain: str = ...,
    boundary: str = ...,
    slant: float = ...,
    albedo: Optional[float] = ...,
    ambient: Optional[float] = ...,
    seed: Optional[int] = ...,
    **params: Any,
) -> Dict[str, Any]: ...
@overload
def lightness(
    picture: PictureSpec,
    *,
    ppd: Optional[float] = ...,
    model: str = ...,
    mask: None = ...,
    targets: Literal[False] = ...,
    seed: Optional[int] = ...,
    **params: Any,
) -> npt.NDArray[np.float64]: ...
@overload
def lightness(
    picture: PictureSpec,
    *,
    ppd: Optional[float] = ...,
    model: str = ...,
    mask: Optional[npt.ArrayLike] = ...,
    targets: bool = ...,
    seed: Optional[int] = ...,
    **params: Any,
) -> Tuple[npt.NDArray[np.float64], List[Dict[str, Any]]]: ...

def to_psychopy(
    stim: Union[Dict[str, Any], npt.ArrayLike],
    *,
    units: Literal["pix", "deg"] = "pix",
    codes: Optional[bool] = None,
    display: Optional[DisplaySpec] = None,
    luminance: Optional[LuminanceSpec] = None,
) -> Dict[str, Any]: ...

def save(
    stim: Dict[str, Any],
    path: Union[str, "os.PathLike[str]"],
    *,
    bit_depth: Optional[Literal[8, 16]] = None,
    gamma: Optional[float] = None,
    range: Optional[Literal["unit", "psychopy"]] = None,
    display: Optional[DisplaySpec] = None,
    luminance: Optional[LuminanceSpec] = None,
    layers: bool = False,
    force: bool = False,
) -> List[str]: ...
