"""Type stubs of the compiled module ``shadelab._shadelab`` (called by ``shadelab``; use the
functions of ``shadelab`` itself, which take and give dicts, tuples and NumPy arrays)."""

from typing import Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

def stimuli() -> List[Tuple[str, str]]: ...
def describe(name: str) -> str: ...
def render(
    name: str,
    params_json: str,
    visual_size: Optional[Tuple[float, float]],
    ppd: Optional[float],
    shape: Optional[Tuple[int, int]],
    seed: int,
    layers: bool,
) -> Tuple[
    str,
    npt.NDArray[np.float64],
    Optional[npt.NDArray[np.uint16]],
    List[str],
    Dict[str, npt.NDArray[np.float64]],
]: ...
def solve(
    image: npt.NDArray[np.float64],
    mask: Optional[npt.NDArray[np.bool_]],
    light: str,
    boundary: str,
    albedo: Optional[float],
    lam: float,
    method: str,
    tol: float,
    max_iter: Optional[int],
) -> Tuple[
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
    str,
]: ...
def prior_sweep(
    image: Optional[npt.NDArray[np.float64]],
    stimulus: Optional[str],
    params_json: str,
    seed: Optional[int],
    ppd: Optional[float],
    shape: Optional[Tuple[int, int]],
    labels: Optional[npt.NDArray[np.uint16]],
    tilts: Optional[List[float]],
    binding: Optional[str],
    domain: str,
    boundary: str,
    slant: float,
    albedo: Optional[float],
    ambient: Optional[float],
) -> Tuple[str, npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
def observer(
    image: Optional[npt.NDArray[np.float64]],
    stimulus: Optional[str],
    params_json: str,
    seed: Optional[int],
    ppd: Optional[float],
    shape: Optional[Tuple[int, int]],
    labels: Optional[npt.NDArray[np.uint16]],
    prior_tilt: Optional[float],
    kappas: Optional[List[float]],
    convexity_bias: Optional[float],
    noise: Optional[float],
    rotations: Optional[List[float]],
    tilts: Optional[List[float]],
    domain: str,
    boundary: str,
    slant: float,
    albedo: Optional[float],
    ambient: Optional[float],
) -> str: ...
def lightness(
    image: Optional[npt.NDArray[np.float64]],
    stimulus: Optional[str],
    params_json: str,
    seed: Optional[int],
    ppd: Optional[float],
    labels: Optional[npt.NDArray[np.uint16]],
    model: str,
) -> Tuple[npt.NDArray[np.float64], str]: ...
