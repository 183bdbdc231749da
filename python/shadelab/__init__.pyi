"""Type stubs of ``shadelab`` (see ``__init__.py`` for the documentation)."""

import os
from typing import Any, Callable, Dict, Iterator, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

#: A (height, width) pair, or one number for a square.
Size = Union[float, Tuple[float, float], Sequence[float]]
#: An (x, y, z) vector toward the light, "tilt=T,slant=S", a name ("above", …).
LightSpec = Union[str, Tuple[float, float, float], Sequence[float], npt.NDArray[np.floating]]
#: A stimulus name, or an image (H×W, or H×W×3 where colour is accepted) of linear luminance.
PictureSpec = Union[str, npt.ArrayLike]

PathLike = Union[str, "os.PathLike[str]"]

class Stimulus(Dict[str, Any]):
    def _repr_png_(self) -> Optional[bytes]: ...
    def _repr_html_(self) -> Optional[str]: ...

class Result:
    report: Dict[str, Any]
    command: str
    def to_dict(self) -> Dict[str, Any]: ...
    def __getitem__(self, key: str) -> Any: ...
    def __contains__(self, key: object) -> bool: ...
    def __iter__(self) -> Iterator[str]: ...
    def keys(self) -> List[str]: ...
    def save(self, out: PathLike, *, force: bool = ...) -> str: ...
    def figures(self) -> Dict[str, npt.NDArray[np.uint8]]: ...
    def _repr_png_(self) -> Optional[bytes]: ...
    def _repr_html_(self) -> Optional[str]: ...

class PriorSweep(Result):
    @property
    def tilts(self) -> npt.NDArray[np.float64]: ...
    @property
    def convexities(self) -> npt.NDArray[np.float64]: ...
    @property
    def tokens(self) -> List[Dict[str, Any]]: ...

class Observer(Result):
    @property
    def percepts(self) -> List[Dict[str, Any]]: ...
    @property
    def tokens(self) -> List[Dict[str, Any]]: ...

class Lightness(Result):
    @property
    def output(self) -> npt.NDArray[np.float64]: ...
    @property
    def targets(self) -> List[Dict[str, Any]]: ...

class Fading(Result):
    @property
    def times(self) -> npt.NDArray[np.float64]: ...
    @property
    def blurred(self) -> npt.NDArray[np.float64]: ...
    @property
    def sharp(self) -> npt.NDArray[np.float64]: ...
    @property
    def frames(self) -> npt.NDArray[np.float64]: ...

class Outline(Result):
    @property
    def targets(self) -> List[Dict[str, Any]]: ...
    @property
    def layers(self) -> Dict[str, Dict[str, Any]]: ...

class Study(Result):
    results_csv: str
    sweep_csv: str
    folder: Optional[str]
    @property
    def results(self) -> Dict[str, npt.NDArray[Any]]: ...
    @property
    def sweep(self) -> Dict[str, npt.NDArray[Any]]: ...

class Evaluation(Result):
    table: str
    folder: Optional[str]
    @property
    def cases(self) -> List[Dict[str, Any]]: ...
    def mean_errors_deg(self) -> npt.NDArray[np.float64]: ...

class Gallery(Result):
    @property
    def folder(self) -> str: ...
    @property
    def presets(self) -> List[Dict[str, Any]]: ...

class Bench(Result):
    table: str
    @property
    def rows(self) -> List[Dict[str, Any]]: ...

class Benchmark(Result):
    table: str
    folder: Optional[str]
    @property
    def scores(self) -> List[Dict[str, Any]]: ...
    @property
    def checked_scores(self) -> List[Dict[str, Any]]: ...
    @property
    def conventions(self) -> List[Dict[str, Any]]: ...
    @property
    def rows(self) -> List[Dict[str, Any]]: ...

class Experiment(Result):
    folder: str
    kept: List[str]
    install_error: Optional[str]
    @property
    def design(self) -> Dict[str, Any]: ...

class Fit(Result):
    PARAMETERS: Tuple[str, ...]
    @property
    def pooled(self) -> Dict[str, Any]: ...
    @property
    def participants(self) -> List[Dict[str, Any]]: ...
    @property
    def group(self) -> Optional[Dict[str, Any]]: ...

#: Each command of the ``shadelab`` command line and its Python twin.
COMMANDS: Dict[str, Any]

class Reconstruction(Result):
    @property
    def normals(self) -> npt.NDArray[np.float64]: ...
    @property
    def depth(self) -> npt.NDArray[np.float64]: ...
    @property
    def f(self) -> npt.NDArray[np.float64]: ...
    @property
    def g(self) -> npt.NDArray[np.float64]: ...
    @property
    def converged(self) -> bool: ...
    @property
    def iterations(self) -> int: ...

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
) -> Stimulus: ...
def solve(
    image: npt.ArrayLike,
    *,
    light: Union[LightSpec, Literal["estimate"]],
    mask: Optional[npt.ArrayLike] = ...,
    boundary: str = ...,
    albedo: Optional[Union[float, Literal["estimate"]]] = ...,
    lam: float = ...,
    method: Optional[
        Literal["nested-lm", "multigrid", "jacobi", "literal", "integrable", "integrable-lm"]
    ] = ...,
    tol: Optional[float] = ...,
    max_iter: Optional[int] = ...,
    saturation: Optional[Union[float, Literal["auto", "none"]]] = ...,
    progress: Optional[Callable[[Dict[str, Any]], Any]] = ...,
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
    method: Optional[str] = ...,
    lam: Optional[float] = ...,
    tol: Optional[float] = ...,
    max_iter: Optional[int] = ...,
    seed: Optional[int] = ...,
    **params: Any,
) -> PriorSweep: ...
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
    method: Optional[str] = ...,
    lam: Optional[float] = ...,
    tol: Optional[float] = ...,
    max_iter: Optional[int] = ...,
    seed: Optional[int] = ...,
    **params: Any,
) -> Observer: ...
def lightness(
    picture: PictureSpec,
    *,
    ppd: Optional[float] = ...,
    model: str = ...,
    mask: Optional[npt.ArrayLike] = ...,
    seed: Optional[int] = ...,
    **params: Any,
) -> Lightness: ...

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

Names = Union[str, Sequence[str]]

def fading(
    picture: PictureSpec = ...,
    *,
    ppd: Optional[float] = ...,
    mask: Optional[npt.ArrayLike] = ...,
    tau: Optional[float] = ...,
    duration: Optional[float] = ...,
    dt: Optional[float] = ...,
    jitter: Optional[float] = ...,
    jitter_seed: Optional[int] = ...,
    dog_sigma: Optional[float] = ...,
    border: Optional[float] = ...,
    seed: Optional[int] = ...,
    **params: Any,
) -> Fading: ...
def outline(
    picture: PictureSpec,
    *,
    ppd: Optional[float] = ...,
    shape: Optional[Union[int, Tuple[int, int]]] = ...,
    mask: Optional[npt.ArrayLike] = ...,
    light: Optional[LightSpec] = ...,
    depth_scale: float = ...,
    lam: float = ...,
    seed: Optional[int] = ...,
    **params: Any,
) -> Outline: ...
def benchmark(
    *,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    models: Union[str, Sequence[str]] = ...,
    stimuli: Optional[Union[str, Sequence[str]]] = ...,
) -> Benchmark: ...
def study_run(spec: Union[PathLike, Dict[str, Any]], *, shard: Optional[str] = ...) -> Study: ...
def study_merge(folders: Sequence[PathLike], out: PathLike, *, force: bool = ...) -> Study: ...
def evaluate(
    data: PathLike,
    *,
    out: Optional[PathLike] = ...,
    force: bool = ...,
    only: Optional[Names] = ...,
    objects: Optional[Names] = ...,
    ball_images: Optional[Names] = ...,
    diligent_light: Optional[LightSpec] = ...,
    boundary: Optional[str] = ...,
    albedo_quantile: Optional[float] = ...,
    ball_albedo_from_truth: bool = ...,
    bunny_size: Optional[int] = ...,
    methods: Optional[Names] = ...,
    lam: Optional[float] = ...,
    tol: Optional[float] = ...,
    max_iter: Optional[int] = ...,
) -> Evaluation: ...
def gallery(out: PathLike, *, presets: Optional[PathLike] = ..., force: bool = ...) -> Gallery: ...
def bench(
    *,
    sizes: Sequence[int] = ...,
    methods: Union[str, Sequence[str]] = ...,
    lam: float = ...,
    shape: str = ...,
    light: LightSpec = ...,
    jacobi_up_to: int = ...,
    integrable_up_to: int = ...,
    reference: PathLike = ...,
    reference_up_to: int = ...,
    repeat: int = ...,
) -> Bench: ...
def experiment(
    out: PathLike,
    *,
    stimulus: Optional[str] = ...,
    rotations: Optional[Sequence[float]] = ...,
    repeats: Optional[int] = ...,
    practice: Optional[int] = ...,
    slant: Optional[float] = ...,
    visual_size: Optional[Size] = ...,
    ppd: Optional[float] = ...,
    viewing_distance: Optional[float] = ...,
    seed: Optional[int] = ...,
    keys: Optional[str] = ...,
    break_every: Optional[int] = ...,
    counterbalance_keys: bool = ...,
    save_url: Optional[str] = ...,
    save_format: Optional[Literal["json", "csv"]] = ...,
    prolific_code: Optional[str] = ...,
    completion_url: Optional[str] = ...,
    install: bool = ...,
    force: bool = ...,
    **params: Any,
) -> Experiment: ...
def experiment_pilot(
    study: PathLike,
    simulate: str,
    *,
    participant: Optional[str] = ...,
    out: Optional[PathLike] = ...,
    force: bool = ...,
) -> str: ...
def fit_observer(
    responses: Union[PathLike, Dict[str, Any], Any],
    *,
    keys: Optional[str] = ...,
    include_simulated: bool = ...,
    mixed_designs: bool = ...,
    design: Optional[PathLike] = ...,
    lapse: Optional[float] = ...,
    nonparametric: bool = ...,
    bootstrap: Optional[int] = ...,
    seed: Optional[int] = ...,
) -> Fit: ...
