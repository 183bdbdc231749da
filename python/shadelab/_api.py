"""The package's Python half: each public function turns Python values into the compiled
module's arguments and its results into dicts and arrays (see ``shadelab``'s docstring)."""

from __future__ import annotations

import inspect
import json
import os as _os
import warnings
from os import fspath as _fspath
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _shadelab
from ._results import Lightness, Observer, PriorSweep, Result, Stimulus

__version__: str = _shadelab.__version__

# The keys every `render` dict has besides the stimulus's parameters (these win on a clash).
_RENDER_KEYS = ("img", "target_mask", "target_names", "visual_size", "ppd", "shape")


# The last target-name text and its names. Renders in a loop (an experiment's trials, a
# parameter sweep) usually repeat their targets, and a checkerboard has one per check: the
# names are then made once and each call's list shares them instead of splitting again.
_last_names: Tuple[str, Tuple[str, ...]] = ("", ())


def _target_names(text: str) -> List[str]:
    """The names of the "\\n"-joined ``text`` the compiled module hands over, as a new list."""
    global _last_names
    if text != _last_names[0]:
        _last_names = (text, tuple(text.split("\n")) if text else ())
    return list(_last_names[1])


def _pair(value: Any, what: str, kind: type) -> Optional[Tuple[Any, Any]]:
    """A (height, width) pair from a pair or a single number (square), as stimupy takes them."""
    if value is None:
        return None
    if np.ndim(value) == 0:
        return (kind(value), kind(value))
    items = list(np.asarray(value).ravel())
    if len(items) != 2:
        raise ValueError(f"{what} must be a number or a (height, width) pair, not {value!r}")
    if kind is int and any(float(v) != int(v) for v in items):
        raise ValueError(f"{what} must be whole pixels, not {value!r}")
    return (kind(items[0]), kind(items[1]))


def _light_text(light: Any) -> str:
    """A light as the library reads it: ``x,y,z``, ``tilt=T,slant=S``, a name or ``estimate``."""
    if isinstance(light, str):
        return light
    values = np.asarray(light, dtype=float).ravel()
    if values.size != 3:
        raise ValueError(
            f"light must be an (x, y, z) vector, 'tilt=T,slant=S', a name or 'estimate', not {light!r}"
        )
    return ",".join(repr(float(v)) for v in values)


def _params_json(params: Dict[str, Any], stimulus: Optional[str] = None, function: Any = None) -> str:
    """Parameter values as JSON (NumPy scalars and arrays become plain numbers and lists).

    Where the keywords enter: with the ``stimulus`` they are for, each name is checked against
    its parameters, and an unknown one is a ValueError naming the nearest among them and the
    keywords of the public ``function`` they were given to (``prior_kappa`` → ``kappas``)."""
    if stimulus is not None and params:
        keywords = [] if function is None else list(inspect.signature(function).parameters)
        _shadelab.check_params(str(stimulus), list(params), keywords)

    def plain(v: Any) -> Any:
        if isinstance(v, np.generic):
            return v.item()
        if isinstance(v, (np.ndarray, tuple)):
            return np.asarray(v).tolist() if isinstance(v, np.ndarray) else list(v)
        raise TypeError(f"parameter value {v!r} is not a number, string or boolean")

    try:
        return json.dumps(params, default=plain)
    except (TypeError, ValueError) as e:
        raise ValueError(str(e)) from None


def _ppd(ppd: Any) -> Optional[float]:
    """A ppd as stimupy takes it, a number or a (vertical, horizontal) pair; shadelab's pixels
    are square, so a pair's two values must agree."""
    if ppd is None:
        return None
    if isinstance(ppd, (tuple, list, np.ndarray)):
        values = [float(v) for v in np.asarray(ppd, dtype=float).ravel()]
        if len(values) != 2:
            raise ValueError(f"ppd: a number or a (vertical, horizontal) pair, not {ppd!r}")
        if values[0] != values[1]:
            raise ValueError(
                f"ppd: {values[0]} vertical and {values[1]} horizontal differ; shadelab's "
                "pixels are square (one ppd for both axes)"
            )
        return values[0]
    return float(ppd)


def _stimupy_dict(picture: Any) -> Optional[Dict[str, Any]]:
    """A stimupy-style dict (``img``, optional ``target_mask`` and ``ppd``) given as a picture,
    or None."""
    if isinstance(picture, dict):
        if "img" not in picture:
            raise ValueError(
                "image: a dict is taken as stimupy's (or shadelab's render): it needs 'img'"
            )
        return picture
    return None


def _float_image(image: Any, what: str, colour: bool) -> np.ndarray:
    """A float64 H×W (or, with `colour`, H×W×3) array from any real-valued array, read the
    way the command line reads a ``.npy`` picture (docs/conventions.md): uint8 and uint16
    divided by 255 and 65535 (as a PNG's codes), other integer types refused, floats and
    booleans as they are; the library then refuses values outside 0..1. A stimupy-style dict
    gives its ``img``."""
    given = _stimupy_dict(image)
    if given is not None:
        image = given["img"]
    a = np.asarray(image)
    _shadelab.check_shape(list(a.shape), what)
    if a.dtype.kind not in "biuf":
        raise ValueError(f"{what}: unsupported dtype {a.dtype} (need a real number type)")
    if a.dtype.kind in "iu":
        if a.dtype.kind != "u" or a.dtype.itemsize > 2:
            raise ValueError(
                f"{what}: {a.dtype.name} pictures are refused: only uint8 and uint16 integers "
                "have a largest value that means white (save 8- or 16-bit codes as uint8 or "
                "uint16, or luminance 0..1 as float)"
            )
        a = a.astype(np.float64) / float(np.iinfo(a.dtype).max)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if not (a.ndim == 2 or (colour and a.ndim == 3 and a.shape[2] == 3)):
        need = "H×W or H×W×3" if colour else "2-D H×W"
        raise ValueError(f"{what}: expected a {need} array, found shape {a.shape}")
    if a.size == 0:
        raise ValueError(f"{what}: the array is empty (shape {a.shape})")
    return a.astype(np.float64, copy=False)


def _labels(mask: Any, what: str) -> Optional[np.ndarray]:
    """Target labels (0 = background, 1..N = targets) as uint16, or None."""
    if mask is None:
        return None
    a = np.asarray(mask)
    if a.ndim != 2:
        raise ValueError(f"{what}: expected a 2-D H×W array, found shape {a.shape}")
    _shadelab.check_shape(list(a.shape), what)
    if a.dtype.kind == "b":
        return a.astype(np.uint16)
    if a.dtype.kind not in "iuf" or (a.size and (a.min() < 0 or a.max() > 65535)):
        raise ValueError(f"{what}: labels must be whole numbers 0..65535 (0 = background)")
    if a.dtype.kind == "f" and not np.all(a == np.round(a)):
        raise ValueError(f"{what}: labels must be whole numbers 0..65535 (0 = background)")
    return a.astype(np.uint16, copy=False)


def _opt(kind: type, value: Any) -> Any:
    """`value` as `kind`, or None."""
    return None if value is None else kind(value)


def _picture_args(
    picture: Any,
    colour: bool,
    params: Dict[str, Any],
    seed: Any,
    ppd: Any,
    shape: Any,
    mask: Any,
    function: Any = None,
) -> Tuple[Any, ...]:
    """An analysis's picture as the compiled module takes it: an array or a stimulus name, and
    the stimulus's parameters, seed, ppd, shape (height, width), target labels and, for a dict
    of :func:`render`, what its render recorded (its ``parameters`` and ``notes``, as a
    sidecar records them: the albedo, ambient level and light the library takes, and whether
    the labels passed are the dict's own target mask, which its notes may call silhouettes)."""
    record = None
    if isinstance(picture, str):
        image, stimulus = None, picture
    else:
        image, stimulus = _float_image(picture, "image", colour), None
        # A stimupy dict brings its geometry and targets; arguments given win.
        given = _stimupy_dict(picture)
        if given is not None:
            ppd = given.get("ppd") if ppd is None else ppd
            own_targets = False
            if mask is None and given.get("target_mask") is not None:
                labels = np.asarray(given["target_mask"])
                mask = labels if labels.any() else None
                own_targets = mask is not None
            if isinstance(given.get("parameters"), dict) or isinstance(given.get("notes"), dict):
                record = json.dumps(
                    {
                        "parameters": given.get("parameters") or {},
                        "notes": given.get("notes") or {},
                        # Whether the labels passed are the dict's own (what its notes describe).
                        "own_targets": own_targets,
                        "target_names": list(given.get("target_names") or []) if own_targets else [],
                    },
                    default=lambda v: v.tolist() if hasattr(v, "tolist") else str(v),
                )
    return (
        image,
        stimulus,
        _params_json(params, stimulus, function),
        _opt(int, seed),
        _ppd(ppd),
        _pair(shape, "shape", int),
        _labels(mask, "mask"),
        record,
    )


def _display_arg(display: Any) -> Tuple[Optional[str], Optional[str]]:
    """A display as (file path, None), (None, JSON text of a dict) or (None, None)."""
    if display is None:
        return None, None
    if isinstance(display, dict):
        return None, json.dumps(display)
    if isinstance(display, (str, _os.PathLike)):
        return _fspath(display), None
    raise ValueError(
        f"display: a display file's path or a dict of the display JSON, not {type(display).__name__}"
    )


def _luminance_arg(luminance: Any) -> Optional[str]:
    """A luminance mapping as the command line's ``--luminance`` text."""
    if luminance is None:
        return None
    if isinstance(luminance, str):
        return luminance
    if isinstance(luminance, dict):
        keys = sorted(luminance)
        if keys != ["background", "michelson"]:
            raise ValueError(
                f"luminance: a dict has 'background' and 'michelson', not {keys}"
            )
        return f"background={float(luminance['background'])!r},michelson={float(luminance['michelson'])!r}"
    pair = _pair(luminance, "luminance", float)
    if pair is None or not isinstance(luminance, (tuple, list)):
        raise ValueError("luminance: (lo, hi) in cd/m² or {'background': B, 'michelson': C}")
    return f"{pair[0]!r},{pair[1]!r}"


def _assumptions(domain: Any, boundary: Any, slant: Any, albedo: Any, ambient: Any) -> Tuple[Any, ...]:
    """What the perception analyses assume, as the compiled module takes it."""
    return (str(domain), str(boundary), float(slant), _opt(float, albedo), _opt(float, ambient))


def _solver(method: Any, lam: Any, tol: Any, max_iter: Any) -> Tuple[Any, ...]:
    """How the perception analyses solve, as the compiled module takes it (None: the default)."""
    return (_opt(str, method), _opt(float, lam), _opt(float, tol), _opt(int, max_iter))


def _floats(values: Optional[Sequence[float]]) -> Optional[List[float]]:
    return None if values is None else [float(v) for v in values]


def stimuli() -> Dict[str, str]:
    """Every stimulus and surface that :func:`render` knows, with a one-line description.

    >>> "checkerboard" in stimuli()
    True
    """
    return dict(_shadelab.stimuli())


def describe(name: str) -> Dict[str, Any]:
    """A stimulus's parameters: for each, its default, range and doc; its default size; and
    the stimupy parameter names it accepts (``stimupy_names``: stimupy's → shadelab's).

    >>> d = describe("checkerboard")
    >>> d["params"]["check"]["default"], d["default_visual_size"], d["default_ppd"]
    (1.0, (8.0, 8.0), 32.0)
    """
    raw = json.loads(_shadelab.describe(name))
    return {
        "name": raw["name"],
        "summary": raw["summary"],
        "default_visual_size": tuple(raw["default_visual_size"]),
        "default_ppd": raw["default_ppd"],
        "params": {
            p["name"]: {"default": p["default"], "range": p["range"], "doc": p["doc"]}
            for p in raw["params"]
        },
        "stimupy_names": dict(raw["stimupy_names"]),
    }


def render(
    name: str,
    *,
    visual_size: Any = None,
    ppd: Optional[float] = None,
    shape: Any = None,
    light: Any = None,
    seed: Optional[int] = None,
    layers: bool = False,
    bit_depth: Optional[int] = None,
    gamma: Optional[float] = None,
    range: str = "unit",
    display: Any = None,
    luminance: Any = None,
    **params: Any,
) -> Dict[str, Any]:
    """Renders a stimulus as a stimupy-style dict.

    ``visual_size`` (degrees) and ``shape`` (pixels) are ``(height, width)`` or one number for
    a square; with ``ppd`` any two fix the third and what is missing takes the stimulus's
    defaults (:func:`describe`). ``light`` is an ``(x, y, z)`` vector, ``"tilt=T,slant=S"`` or a
    name (``above``, ``left``, …); other keyword arguments are the stimulus's parameters.

    The dict holds ``img`` (float64, H×W or H×W×3, linear 0..1), ``target_mask`` (uint16,
    0 = background, 1..n = the targets), ``target_names``, ``visual_size`` and ``shape``
    ``(height, width)``, ``ppd``, ``stimulus``, ``seed``, ``notes`` (facts the stimulus
    recorded) and every resolved parameter by name (and all of them again under
    ``parameters``); with ``layers=True`` also ``depth``, ``normals`` (H×W×3) and ``shading``
    (and ``albedo`` where the surface varies it), which take the place of parameters of the
    same name. The numbers are those the command line writes.

    How it is shown, as ``shadelab render``'s flags (docs/display.md), recorded in the dict's
    ``export`` so that :func:`save` writes it so: ``range="psychopy"`` gives ``img`` in
    PsychoPy's −1..1; ``bit_depth`` (8 or 16) and ``gamma`` add ``codes``, the PNG's codes
    (uint16); ``display`` (a display file: shadelab's display JSON, a PsychoPy monitor file or a
    photometer CSV, or a dict of the display JSON) with ``luminance`` (``(lo, hi)`` cd/m² of 0
    and 1, or ``{"background": B, "michelson": C}``; default the display's black to white) adds
    ``codes`` (the display's codes, H×W, or H×W×3 with bit-stealing), ``luminance_cd_m2`` (what
    the display shows, H×W) and ``display`` (the display, the luminance mapping, the error and
    each target's cd/m²).

    >>> s = render("sphere", shape=(48, 64), light="tilt=30,slant=40", layers=True)
    >>> s["img"].shape, s["normals"].shape, s["target_names"]
    ((48, 64), (48, 64, 3), ['object'])
    >>> lab = {"name": "lab", "gamma": 2.2, "black_cd_m2": 0.5, "white_cd_m2": 120}
    >>> c = render("sphere", shape=(48, 64), display=lab, luminance=(10, 90))
    >>> c["codes"].dtype, round(float(c["luminance_cd_m2"].max()), 1) <= 90.5
    (dtype('uint16'), True)
    """
    if light is not None:
        params["light"] = _light_text(light)
    display_path, display_json = _display_arg(display)
    report_json, img, target_mask, names, extra = _shadelab.render(
        name,
        _params_json(params, name, render),
        _pair(visual_size, "visual_size", float),
        _ppd(ppd),
        _pair(shape, "shape", int),
        0 if seed is None else int(seed),
        bool(layers),
        _opt(int, bit_depth),
        _opt(float, gamma),
        str(range),
        display_path,
        display_json,
        _luminance_arg(luminance),
    )
    shown = extra.pop("display_json", None)
    codes = extra.pop("codes", None)
    luminance_cd = extra.pop("luminance_cd_m2", None)
    report = json.loads(report_json)
    for line in report.get("warnings", []):
        warnings.warn(line, stacklevel=2)
    geometry = report["geometry"]
    height, width, resolution = geometry["height"], geometry["width"], geometry["ppd"]
    out: Dict[str, Any] = Stimulus(report["parameters"])
    out.update(
        img=img,
        target_mask=target_mask
        if target_mask is not None
        else np.zeros((height, width), dtype=np.uint16),
        target_names=_target_names(names),
        visual_size=(height / resolution, width / resolution),
        ppd=resolution,
        shape=(height, width),
        stimulus=report["stimulus"],
        seed=report["seed"],
        notes=report["notes"],
        parameters=dict(report["parameters"]),
        export=dict(
            bit_depth=bit_depth,
            gamma=gamma,
            range=str(range),
            display=display,
            luminance=luminance,
        ),
    )
    if codes is not None:
        out["codes"] = codes
    if shown is not None:
        out["luminance_cd_m2"] = luminance_cd
        out["display"] = json.loads(shown)
    if layers:
        out.update(extra)
        # Where the library keeps no separate shading, the shading is the image itself.
        out.setdefault("shading", img)
    return out


class Reconstruction(Result):
    """What :func:`solve` recovered: ``normals`` (H×W×3, unit, x right, y up, z toward the
    viewer), ``depth`` (H×W, pixels toward the viewer, lowest masked point 0), the
    stereographic gradients ``f`` and ``g`` (H×W), whether the solver ``converged``, its
    ``iterations``, and the ``report`` dict (what the command line writes as report.json).
    ``save(out)`` writes the folder ``shadelab solve --out`` writes (normals, depth, figures),
    ``figures()`` its figures as arrays, ``to_dict()`` the report with the arrays."""

    __slots__ = ()
    command = "solve"

    def __init__(
        self,
        normals: np.ndarray,
        depth: np.ndarray,
        f: np.ndarray,
        g: np.ndarray,
        report: Dict[str, Any],
        handle: Any = None,
    ) -> None:
        super().__init__(report, {"normals": normals, "depth": depth, "f": f, "g": g}, handle)

    @property
    def normals(self) -> np.ndarray:
        return self._arrays["normals"]

    @property
    def depth(self) -> np.ndarray:
        return self._arrays["depth"]

    @property
    def f(self) -> np.ndarray:
        return self._arrays["f"]

    @property
    def g(self) -> np.ndarray:
        return self._arrays["g"]

    @property
    def converged(self) -> bool:
        return bool(self.report["solver"]["converged"])

    @property
    def iterations(self) -> int:
        return int(self.report["solver"]["iterations"])

    def __repr__(self) -> str:
        h, w = self.depth.shape
        state = "converged" if self.converged else "NOT converged"
        unit = self.report["solver"]["iteration_unit"]
        return f"<Reconstruction {h}×{w}, {state} after {self.iterations} {unit}>"


def save(
    stim: Dict[str, Any],
    path: Union[str, "os.PathLike[str]"],
    *,
    bit_depth: Optional[int] = None,
    gamma: Optional[float] = None,
    range: Optional[str] = None,
    display: Any = None,
    luminance: Any = None,
    layers: bool = False,
    force: bool = False,
) -> List[str]:
    """Writes a :func:`render` dict's picture as ``shadelab render`` writes a render.

    The format follows ``path``'s extension (``.png`` 8- or 16-bit, ``.npy`` float32, ``.mat``
    or ``.npz`` bundles, ``.svg`` for vector stimuli); the target mask (``NAME_mask.png``) and
    the JSON sidecar with every parameter go beside it, and with ``layers=True`` the surface
    layers. ``gamma`` display-encodes a PNG (recorded; its gAMA chunk says so too), ``range``
    is ``"unit"`` (0..1) or ``"psychopy"`` (−1..1, float formats), ``display`` and
    ``luminance`` write a display's codes (PNG; see :func:`render`); each not given is taken
    from the dict's ``export`` (what :func:`render` was asked for), else 16 bits, linear,
    0..1, no display. The picture written is the dict's ``img`` as it is now (in the range
    :func:`render` gave it: a ``.npy`` holds its values as float32, a PNG their codes); the
    mask, layers and sidecar are those of the render the dict records (its name, parameters,
    seed, shape and ppd), written by the command line's own writer, so an unchanged dict
    gives the files ``shadelab render`` writes, byte for byte. An ``img`` changed since
    :func:`render` (any value by more than 1e-9) is written as it is, and its sidecar says it
    was edited (``edited``, with the render's digest beside the picture's own); so are a
    ``target_mask`` or ``target_names`` changed since :func:`render`: the mask file and the
    sidecar's targets are the dict's, and ``edited`` says ``target_mask``. ``shadelab
    render --spec`` of such a sidecar refuses to claim it reproduces it. As with the command
    line, a file shadelab did not write is not replaced unless ``force=True``, another
    picture's sidecar and mask never are (``a.png`` beside ``a.npy``: give another name), and
    the set of files is written whole or not at all. Returns the paths written.

    >>> import tempfile, pathlib
    >>> s = render("checkerboard", shape=(16, 24), ppd=8, targets="0,0")
    >>> with tempfile.TemporaryDirectory() as d:
    ...     [pathlib.Path(p).name for p in save(s, pathlib.Path(d) / "c.png")]
    ['c_mask.png', 'c.png', 'c.json']
    """
    try:
        name, params = stim["stimulus"], stim["parameters"]
        shape, ppd, seed = stim["shape"], stim["ppd"], stim["seed"]
        img = stim["img"]
    except (KeyError, TypeError):
        raise ValueError(
            "save: stim must be a dict that shadelab.render returned (img, stimulus, "
            "parameters, shape, ppd, seed)"
        ) from None
    asked = stim.get("export") or {}
    image_range = asked.get("range") or "unit"
    if bit_depth is None:
        bit_depth = asked.get("bit_depth") or 16
    if gamma is None:
        gamma = asked.get("gamma")
    if range is None:
        range = asked.get("range") or "unit"
    if display is None:
        display = asked.get("display")
        if luminance is None:
            luminance = asked.get("luminance")
    display_path, display_json = _display_arg(display)
    targets = None
    if stim.get("target_mask") is not None:
        names = stim.get("target_names") or []
        if isinstance(names, str) or not all(isinstance(n, str) for n in names):
            raise ValueError("save: target_names must be a list of names (text), one per label")
        targets = (_labels(stim["target_mask"], "target_mask"), list(names))
    return list(
        _shadelab.save(
            _float_image(img, "img", colour=True),
            str(image_range),
            targets,
            str(name),
            _params_json(dict(params)),
            float(ppd),
            (int(shape[0]), int(shape[1])),
            int(seed),
            _fspath(path),
            int(bit_depth),
            _opt(float, gamma),
            str(range),
            display_path,
            display_json,
            _luminance_arg(luminance),
            bool(layers),
            bool(force),
        )
    )


def solve(
    image: Any,
    *,
    light: Any,
    mask: Any = None,
    boundary: str = "occluding",
    albedo: Union[float, str, None] = None,
    lam: float = 1.0,
    method: Optional[str] = None,
    tol: Optional[float] = None,
    max_iter: Optional[int] = None,
    saturation: Union[float, str, None] = "auto",
    progress: Optional[Callable[[Dict[str, Any]], Any]] = None,
) -> Reconstruction:
    """Recovers shape from one H×W image of linear luminance (``shadelab solve``).

    ``light`` is an ``(x, y, z)`` vector toward the light, ``"tilt=T,slant=S"``, a name, or
    ``"estimate"`` (estimated from the image with the albedo). ``mask``: nonzero = the object
    (default: the whole image). ``boundary``: ``occluding``, ``flat``, ``free``, ``limb``
    (occluding where the outline's shading allows a limb, else the outward direction at the
    slant the shading gives) or the path of an H×W×3 ``.npy`` of rim normals. ``albedo``: default 1, or the estimate when the light is
    estimated; or ``"estimate"``: the library's albedo rule (the bright tail of the brightness
    on the mask extrapolated, as ``solve --albedo estimate`` and ``eval``), so the answer does
    not depend on how the image was scaled; ``report["parameters"]["albedo_estimate"]`` gives
    it. ``saturation``: where the image was clipped, its pixels at or above that brightness
    carrying no brightness term (``"auto"``, the default: the clipped plateau the albedo
    estimate finds; ``"none"`` or ``None``: no pixel; or a level in the image's units);
    ``report["solver"]["clipped"]`` counts them. ``lam``, ``method``, ``tol`` and ``max_iter``
    are the solver's settings. ``method``: by default ``nested-lm``, the accurate answer (the
    normals of one surface: about 1.3° from the truth on a 256² sphere where multigrid is
    6.5° off, at 50–150× multigrid's time); ``"multigrid"`` is the fast choice (Ikeuchi–Horn,
    what the analyses use); also ``jacobi``, ``literal``, ``integrable``, ``integrable-lm``.
    ``report["parameters"]["method_source"]`` says ``"default"`` or ``"asked"``. ``tol``:
    by default 1e-2 for nested-lm (its finest grid's steps), 1e-6 for the others.
    ``progress``: a function called, on the calling thread, with a dict of where the solve
    stands (``stage``, ``message``, ``done`` and ``total`` steps, and ``seconds_left``: the
    solve's own estimate of the time it has left from the time its steps took so far, for
    nested-lm, integrable-lm and integrable; None for the quick methods and before a first
    estimate) about every 50 ms
    while it changes and once at the end; an exception it raises stops the solve and is raised.

    >>> s = render("sphere", shape=64, light=(0.3, 0.4, 0.866), layers=True)
    >>> r = solve(s["img"], light=(0.3, 0.4, 0.866), mask=s["target_mask"])
    >>> r.converged, r.normals.shape, r.depth.shape
    (True, (64, 64, 3), (64, 64))
    """
    img = _float_image(image, "image", colour=False)
    inside = None
    if mask is not None:
        m = np.asarray(mask)
        if m.ndim != 2:
            raise ValueError(f"mask: expected a 2-D H×W array, found shape {m.shape}")
        _shadelab.check_shape(list(m.shape), "mask")
        inside = m != 0
    estimate = isinstance(albedo, str)
    if estimate and albedo != "estimate":
        raise ValueError(f"albedo: {albedo!r} is neither a number nor 'estimate'")
    normals, depth, f, g, report_json, handle = _shadelab.solve(
        img,
        inside,
        _light_text(light),
        str(boundary),
        None if albedo is None or estimate else float(albedo),
        estimate,
        float(lam),
        _opt(str, method),
        _opt(float, tol),
        None if max_iter is None else int(max_iter),
        "none" if saturation is None else str(saturation),
        progress,
    )
    report = json.loads(report_json)
    warning = ((report.get("light") or {}).get("estimate") or {}).get("warning")
    if warning:
        warnings.warn(warning, stacklevel=2)
    return Reconstruction(normals, depth, f, g, report, handle)


def prior_sweep(
    picture: Any,
    *,
    ppd: Optional[float] = None,
    shape: Any = None,
    mask: Any = None,
    tilts: Optional[Sequence[float]] = None,
    binding: Union[None, str, float] = None,
    domain: str = "auto",
    boundary: str = "flat",
    slant: float = 45.0,
    albedo: Optional[float] = None,
    ambient: Optional[float] = None,
    method: Optional[str] = None,
    lam: Optional[float] = None,
    tol: Optional[float] = None,
    max_iter: Optional[int] = None,
    seed: Optional[int] = None,
    **params: Any,
) -> PriorSweep:
    """How the picture reads under each assumed light tilt (``shadelab analyze prior-sweep``).

    ``picture`` is a stimulus name (rendered with ``params``, ``seed``, ``ppd`` and ``shape``
    ``(height, width)``, and read with its own targets) or an image array; ``mask`` gives an
    array's target labels (0 = background). ``domain`` is what is solved: ``"auto"`` (the
    default, as the CLI: the targets of an object on a backdrop such as the sphere or the hollow
    mask, the whole picture otherwise), ``"image"``, ``"tokens"`` or a PNG mask's path. ``tilts`` in degrees (0 = from above, +90 = from the
    left); ``binding``: ``"estimate"`` or a global light tilt, to also read the tokens under one
    light. ``method``: the reconstruction method, as ``solve`` names them (default
    ``"multigrid"``, Ikeuchi–Horn; docs/perception.md says why the analyses keep it); ``lam``,
    ``tol`` and ``max_iter`` as for :func:`solve` (defaults: the analyses', as the CLI's). Returns a
    :class:`PriorSweep`: the report (what sweep.json holds) with two arrays,
    ``tilts`` and ``convexities`` (tokens × tilts, positive convex, negative concave);
    ``save(out)`` writes the command line's folder, ``figures()`` its plots as arrays.

    >>> r = prior_sweep("bumps", shape=(64, 96), ppd=8, tilts=[0, 180])
    >>> r["convexities"].shape == (len(r["tokens"]), 2)
    True
    """
    report_json, tilt_array, convexity, handle = _shadelab.prior_sweep(
        _picture_args(picture, False, params, seed, ppd, shape, mask, prior_sweep),
        _assumptions(domain, boundary, slant, albedo, ambient),
        _solver(method, lam, tol, max_iter),
        _floats(tilts),
        _opt(str, binding),
    )
    return PriorSweep(
        json.loads(report_json), {"tilts": tilt_array, "convexities": convexity}, handle
    )


def observer(
    picture: Any,
    *,
    ppd: Optional[float] = None,
    shape: Any = None,
    mask: Any = None,
    prior_tilt: Optional[float] = None,
    kappas: Optional[Sequence[float]] = None,
    convexity_bias: Optional[float] = None,
    noise: Optional[float] = None,
    rotations: Optional[Sequence[float]] = None,
    tilts: Optional[Sequence[float]] = None,
    domain: str = "auto",
    boundary: str = "flat",
    slant: float = 45.0,
    albedo: Optional[float] = None,
    ambient: Optional[float] = None,
    method: Optional[str] = None,
    lam: Optional[float] = None,
    tol: Optional[float] = None,
    max_iter: Optional[int] = None,
    seed: Optional[int] = None,
    **params: Any,
) -> Observer:
    """A Bayesian observer's percepts of the picture at each rotation
    (``shadelab analyze observer``): an :class:`Observer` holding the report, as
    observer.json holds it (``save(out)`` writes the command line's folder).

    ``picture``, ``ppd``, ``shape``, ``mask``, ``domain``, ``boundary``, ``slant``, ``albedo``,
    ``ambient``, ``method``, ``lam``, ``tol``, ``max_iter``, ``seed`` and ``params`` as for
    :func:`prior_sweep`; ``prior_tilt`` (degrees)
    and ``kappas`` describe the von Mises prior over the light's tilt, ``convexity_bias`` the
    log prior odds of convex, ``noise`` the image noise σ; ``rotations`` of the picture to
    judge and the sweep's ``tilts`` (covering the circle in equal steps), in degrees.
    """
    report_json, handle = _shadelab.observer(
        _picture_args(picture, False, params, seed, ppd, shape, mask, observer),
        _assumptions(domain, boundary, slant, albedo, ambient),
        _solver(method, lam, tol, max_iter),
        (
            _opt(float, prior_tilt),
            _floats(kappas),
            _opt(float, convexity_bias),
            _opt(float, noise),
            _floats(rotations),
            _floats(tilts),
        ),
    )
    return Observer(json.loads(report_json), {}, handle)


def lightness(
    picture: Any,
    *,
    ppd: Optional[float] = None,
    model: str = "odog",
    mask: Any = None,
    seed: Optional[int] = None,
    **params: Any,
) -> Lightness:
    """A lightness model's output for the picture (``shadelab analyze lightness``).

    ``picture`` is an image array (gray H×W, or RGB H×W×3 taken as its luminance), a
    stimupy-style dict (its ``img``, with its ``target_mask`` and ``ppd`` unless given) or a
    stimulus name (rendered at ``ppd`` with ``params`` and ``seed``). ``ppd`` is required for
    an array when the model works in degrees (every model but ``retinex``).
    ``model``: ``odog``, ``lodog``, ``flodog``, ``retinex`` or ``highpass``. Returns a
    :class:`Lightness`: its ``output`` (H×W) and, where the picture has targets (``mask``:
    target labels, 0 = background; a stimupy dict's ``target_mask``; a stimulus's own),
    ``targets``: one dict per target with its ``label``, ``name``, ``pixels``, mean
    ``luminance`` and mean model ``output``.

    >>> r = lightness("checker-shadow", ppd=16, model="retinex")
    >>> r.output.ndim, [t["name"] for t in r.targets]
    (2, ['A', 'B'])
    """
    out, report_json, handle = _shadelab.lightness(
        _picture_args(picture, True, params, seed, ppd, None, mask, lightness), str(model)
    )
    return Lightness(json.loads(report_json), {"output": out}, handle)
