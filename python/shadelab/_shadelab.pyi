"""Type stubs of the compiled module ``shadelab._shadelab`` (called by ``shadelab``; use the
functions of ``shadelab`` itself, which take and give dicts, tuples and NumPy arrays)."""

from typing import Any, Callable, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

def stimuli() -> List[Tuple[str, str]]: ...
def describe(name: str) -> str: ...
def check_params(stimulus: str, given: List[str], keywords: List[str]) -> None: ...
def check_shape(shape: List[int], what: str) -> None: ...
def render(
    name: str,
    params_json: str,
    visual_size: Optional[Tuple[float, float]],
    ppd: Optional[float],
    shape: Optional[Tuple[int, int]],
    seed: int,
    layers: bool,
    bit_depth: Optional[int],
    gamma: Optional[float],
    range: str,
    display: Optional[str],
    display_json: Optional[str],
    luminance: Optional[str],
) -> Tuple[
    str,
    npt.NDArray[np.float64],
    Optional[npt.NDArray[np.uint16]],
    str,
    Dict[str, Any],
]: ...
def solve(
    image: npt.NDArray[np.float64],
    mask: Optional[npt.NDArray[np.bool_]],
    light: str,
    boundary: str,
    albedo: Optional[float],
    albedo_estimate: bool,
    lam: float,
    method: Optional[str],
    tol: Optional[float],
    max_iter: Optional[int],
    saturation: str,
    progress: Optional[Callable[[Dict[str, Any]], Any]] = ...,
) -> Tuple[
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
    npt.NDArray[np.float64],
    str,
    ReportHandle,
]: ...
class ReportHandle:
    """A command's report kept by the compiled module: writes its output folder, decodes its
    figures."""
    def write(self, out: str, force: bool) -> str: ...
    def figures(self) -> Dict[str, npt.NDArray[np.uint8]]: ...

#: (image, stimulus name, parameters JSON, seed, ppd, shape (h, w), target labels)
PictureArgs = Tuple[
    Optional[npt.NDArray[np.float64]],
    Optional[str],
    str,
    Optional[int],
    Optional[float],
    Optional[Tuple[int, int]],
    Optional[npt.NDArray[np.uint16]],
]
#: (domain, boundary, slant, albedo, ambient)
AssumptionArgs = Tuple[str, str, float, Optional[float], Optional[float]]
SolverArgs = Tuple[Optional[str], Optional[float], Optional[float], Optional[int]]

def prior_sweep(
    picture: PictureArgs,
    assumptions: AssumptionArgs,
    solver: SolverArgs,
    tilts: Optional[List[float]],
    binding: Optional[str],
) -> Tuple[str, npt.NDArray[np.float64], npt.NDArray[np.float64], ReportHandle]: ...
def observer(
    picture: PictureArgs,
    assumptions: AssumptionArgs,
    solver: SolverArgs,
    settings: Tuple[
        Optional[float],
        Optional[List[float]],
        Optional[float],
        Optional[float],
        Optional[List[float]],
        Optional[List[float]],
    ],
) -> Tuple[str, ReportHandle]: ...
def lightness(
    picture: PictureArgs, model: str
) -> Tuple[npt.NDArray[np.float64], str, ReportHandle]: ...
def save(
    image: np.ndarray,
    image_range: str,
    name: str,
    params_json: str,
    ppd: float,
    shape: Tuple[int, int],
    seed: int,
    out: str,
    bit_depth: int,
    gamma: Optional[float],
    range: str,
    display: Optional[str],
    display_json: Optional[str],
    luminance: Optional[str],
    layers: bool,
    force: bool,
) -> List[str]: ...
def fading(
    picture: PictureArgs,
    settings: Tuple[
        Optional[float],
        Optional[float],
        Optional[float],
        Optional[float],
        Optional[int],
        Optional[float],
        Optional[float],
    ],
) -> Tuple[str, Dict[str, npt.NDArray[np.float64]], ReportHandle]: ...
def outline(
    picture: PictureArgs, light: Optional[str], depth_scale: float, lam: float
) -> Tuple[str, Dict[str, Dict[str, Any]], ReportHandle]: ...
def study_run(
    spec_path: Optional[str], spec_json: Optional[str], shard: Optional[str]
) -> Tuple[str, str, str, ReportHandle]: ...
def benchmark(
    export: str, models: str, stimuli: List[str], out: Optional[str], force: bool
) -> Tuple[str, str, Optional[str]]: ...
def study_merge(dirs: List[str], out: str, force: bool) -> Tuple[str, str, str, str]: ...
def evaluate(
    data: str,
    out: Optional[str],
    force: bool,
    settings: Tuple[Any, ...],
) -> Tuple[str, str, Optional[str]]: ...
def gallery(out: str, presets: Optional[str], force: bool) -> str: ...
def bench(
    sizes: List[int],
    methods: List[str],
    lam: float,
    shape: str,
    light: str,
    jacobi_up_to: int,
    integrable_up_to: int,
    reference: str,
    reference_up_to: int,
    repeat: int,
) -> Tuple[str, str]: ...
def experiment(
    out: str, stimulus: Optional[str], params_json: str, settings_json: str, force: bool
) -> Tuple[str, str, List[str], Optional[str]]: ...
def experiment_pilot(
    study: str, simulate: str, participant: Optional[str], out: Optional[str], force: bool
) -> Tuple[str, str, int]: ...
def fit_observer(
    responses: str,
    text: Optional[str],
    keys: Optional[str],
    include_simulated: bool,
    mixed_designs: bool,
    design: Optional[str],
    lapse: Optional[float],
    nonparametric: bool,
    bootstrap: Optional[int],
    seed: Optional[int],
) -> Tuple[str, ReportHandle]: ...
