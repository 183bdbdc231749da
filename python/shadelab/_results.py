"""What the analyses and commands return: typed results holding NumPy arrays and the report
the command line writes, each with ``to_dict()``, ``save(out)`` (the command line's output
folder, by the same writer) and ``figures()`` (that folder's figures as arrays)."""

from __future__ import annotations

import base64
import csv
import fnmatch
import html
import io
import os
import tempfile
from os import fspath as _fspath
from typing import Any, Dict, Iterator, List, Optional, Tuple, Union

import numpy as np

PathLike = Union[str, "os.PathLike[str]"]

#: The most pictures a result shows in a notebook (a gallery or an evaluation writes dozens).
_MAX_SHOWN = 6

#: Which of the figures ``save`` writes a notebook shows for each command (patterns of their
#: paths in the folder without ``.png``, in the order shown); a command not named here shows
#: its first figures. Masks and the stimulus an analysis keeps beside its figures are not
#: pictures of the result.
_SHOWN = {
    "solve": ("depth", "normals", "convergence"),
    "analyze prior-sweep": ("sweep",),
    "analyze observer": ("p_convex",),
    "analyze lightness": ("*_figure",),
    "analyze fading": ("time_course",),
    "analyze outline": ("*-shape", "*-shading", "*-paint"),
    "fit observer": ("fit",),
}


def _figure_pngs(write: Any, command: str) -> List[Tuple[str, bytes]]:
    """The PNG figures of the folder ``write(folder)`` makes, as ``(name, bytes)`` chosen by
    :data:`_SHOWN`: the same files ``save`` writes, read back byte for byte."""
    with tempfile.TemporaryDirectory(prefix="shadelab-repr-") as scratch:
        folder = os.path.join(scratch, "out")
        write(folder)
        found = {}
        for parent, _, files in os.walk(folder):
            for f in files:
                if f.endswith(".png") and not f.endswith("_mask.png"):
                    path = os.path.join(parent, f)
                    name = os.path.relpath(path, folder)[: -len(".png")].replace(os.sep, "/")
                    found[name] = path
        names = sorted(found)
        patterns = _SHOWN.get(command, ("*",))
        chosen: List[str] = []
        for pattern in patterns:
            chosen += [n for n in names if fnmatch.fnmatchcase(n, pattern) and n not in chosen]
        pictures = []
        for name in chosen[:_MAX_SHOWN]:
            with open(found[name], "rb") as fh:
                pictures.append((name, fh.read()))
        return pictures


def _html(title: str, pictures: List[Tuple[str, bytes]]) -> str:
    """The pictures side by side with their names under them, and a title line above."""
    cells = "".join(
        '<figure style="display:inline-block;margin:0 8px 8px 0;vertical-align:top">'
        f'<img src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}" '
        f'alt="{html.escape(name)}" style="max-width:360px;image-rendering:pixelated"/>'
        f'<figcaption style="font-size:smaller">{html.escape(name)}</figcaption></figure>'
        for name, png in pictures
    )
    return f"<div><div>{html.escape(title)}</div>{cells}</div>"


class Stimulus(dict):
    """What :func:`shadelab.render` returns: a plain dict in stimupy's form (``img``,
    ``target_mask``, ``visual_size``, ``shape`` as (height, width), …) that shows its picture
    in Jupyter. The picture is the PNG :func:`shadelab.save` writes at 8 bits display-encoded
    with γ = 2.2 (as the browser experiment's images are; a stimulus rendered for a
    ``display`` shows that display's codes), so a notebook shows the stimulus as a calibrated
    screen would, not the too-dark linear codes."""

    __slots__ = ()

    def _png(self) -> Optional[bytes]:
        from ._api import save

        try:
            with tempfile.TemporaryDirectory(prefix="shadelab-repr-") as scratch:
                path = os.path.join(scratch, "stimulus.png")
                if self.get("display") is not None:
                    save(self, path, bit_depth=8)
                else:
                    save(self, path, bit_depth=8, gamma=2.2)
                with open(path, "rb") as fh:
                    return fh.read()
        except (ValueError, RuntimeError, OSError, KeyError, TypeError):
            # Not a dict render made (keys removed or changed): the text repr stands.
            return None

    def _repr_png_(self) -> Optional[bytes]:
        return self._png()

    def _repr_html_(self) -> Optional[str]:
        png = self._png()
        if png is None:
            return None
        h, w = self.get("shape", ("?", "?"))
        vh, vw = self.get("visual_size", ("?", "?"))
        title = (
            f"{self.get('stimulus', 'stimulus')}: {h} × {w} px (height × width), "
            f"{vh:g} × {vw:g} deg, ppd {self.get('ppd', '?'):g}"
            if isinstance(vh, float) and isinstance(self.get("ppd"), (int, float))
            else f"{self.get('stimulus', 'stimulus')}: {h} × {w} px (height × width)"
        )
        return _html(title, [("img", png)])


class Result:
    """The base of every result: ``report`` (the dict the command line writes as its JSON
    report), the arrays the analysis computed, and read access by key to both
    (``result["tokens"]``) as to a dict.

    ``to_dict()`` gives one plain dict (the report's fields and the arrays); ``save(out)``
    writes the command line's output folder (whole or not at all; a folder shadelab did not
    write is written into only with ``force=True``); ``figures()`` returns that folder's
    figures as ``{name: H×W×3 (or ×4) uint8 array}``.
    """

    __slots__ = ("report", "_arrays", "_handle", "_pictures")

    #: The command line's command this result is the twin of.
    command: str = ""

    def __init__(self, report: Dict[str, Any], arrays: Dict[str, Any], handle: Any = None) -> None:
        self.report = report
        self._arrays = arrays
        self._handle = handle
        self._pictures: Optional[List[Tuple[str, bytes]]] = None

    def to_dict(self) -> Dict[str, Any]:
        """The report's fields with the arrays added (a new dict; the arrays are shared)."""
        out = dict(self.report)
        out.update(self._arrays)
        return out

    def __getitem__(self, key: str) -> Any:
        if key in self._arrays:
            return self._arrays[key]
        return self.report[key]

    def __contains__(self, key: object) -> bool:
        return key in self._arrays or key in self.report

    def keys(self) -> List[str]:
        """The keys of :meth:`to_dict`."""
        return list(self.to_dict().keys())

    def __iter__(self) -> Iterator[str]:
        return iter(self.keys())

    def save(self, out: PathLike, *, force: bool = False) -> str:
        """Writes the command line's output folder ``out`` from this result (the same writer:
        the same files as ``shadelab {command} --out OUT``); returns the folder written."""
        if self._handle is None:
            raise ValueError(f"{type(self).__name__} has no output folder to write")
        return str(self._handle.write(_fspath(out), bool(force)))

    def figures(self) -> Dict[str, np.ndarray]:
        """The figures :meth:`save` writes, decoded: ``{name: H×W×C uint8}`` (C = 3 or 4),
        named by their file's path in the folder without ``.png``."""
        if self._handle is None:
            return {}
        return dict(self._handle.figures())

    def _notebook_pictures(self) -> List[Tuple[str, bytes]]:
        """The figures a notebook shows for this result, as ``(name, PNG bytes)``: the PNG
        files :meth:`save` writes (the same writer, read back), the main ones for the command
        first (the solve's depth and normals, a sweep's curves, a model's output beside the
        stimulus, …), at most six. Made once per result."""
        if self._pictures is None:
            if self._handle is None:
                self._pictures = []
            else:
                handle = self._handle
                self._pictures = _figure_pngs(lambda out: handle.write(out, True), self.command)
        return list(self._pictures)

    def _repr_png_(self) -> Optional[bytes]:
        pictures = self._notebook_pictures()
        return pictures[0][1] if pictures else None

    def _repr_html_(self) -> Optional[str]:
        pictures = self._notebook_pictures()
        if not pictures:
            return None
        return _html(repr(self), pictures)

    def __repr__(self) -> str:
        arrays = ", ".join(
            f"{k} {'×'.join(map(str, v.shape))}"
            for k, v in self._arrays.items()
            if isinstance(v, np.ndarray)
        )
        return f"<{type(self).__name__}{': ' + arrays if arrays else ''}>"


class PriorSweep(Result):
    """:func:`shadelab.prior_sweep`'s result: ``tilts`` (degrees), ``convexities`` (tokens ×
    tilts, positive convex), ``tokens`` (each token's name, flips and numbers) and the report
    (sweep.json)."""

    __slots__ = ()
    command = "analyze prior-sweep"

    @property
    def tilts(self) -> np.ndarray:
        return self._arrays["tilts"]

    @property
    def convexities(self) -> np.ndarray:
        return self._arrays["convexities"]

    @property
    def tokens(self) -> List[Dict[str, Any]]:
        return self.report["tokens"]


class Observer(Result):
    """:func:`shadelab.observer`'s result: ``percepts`` (per rotation and token, P(convex) and
    the light the observer infers), ``tokens`` and the report (observer.json)."""

    __slots__ = ()
    command = "analyze observer"

    @property
    def percepts(self) -> List[Dict[str, Any]]:
        return self.report["percepts"]

    @property
    def tokens(self) -> List[Dict[str, Any]]:
        return self.report["tokens"]


class Lightness(Result):
    """:func:`shadelab.lightness`'s result: ``output`` (the model's H×W output) and
    ``targets`` (one dict per target: ``label``, ``name``, ``pixels``, mean ``luminance`` and
    mean model ``output``; empty without targets), with the report (lightness.json)."""

    __slots__ = ()
    command = "analyze lightness"

    @property
    def output(self) -> np.ndarray:
        return self._arrays["output"]

    @property
    def targets(self) -> List[Dict[str, Any]]:
        found = self.report.get("targets") or []
        return found[0]["targets"] if found else []


class Fading(Result):
    """:func:`shadelab.fading`'s result: the time course (``times`` in s, the perceived
    contrast of the ``blurred`` and ``sharp`` disks, the ``eye`` position in degrees, N×2),
    the animation's ``frames`` (N×H×W×3, 0..1) and the report (fading.json: border energies,
    final contrasts, settings)."""

    __slots__ = ()
    command = "analyze fading"

    @property
    def times(self) -> np.ndarray:
        return self._arrays["times"]

    @property
    def blurred(self) -> np.ndarray:
        return self._arrays["blurred"]

    @property
    def sharp(self) -> np.ndarray:
        return self._arrays["sharp"]

    @property
    def frames(self) -> np.ndarray:
        return self._arrays["frames"]


class Outline(Result):
    """:func:`shadelab.outline`'s result: ``targets`` (the report's reading per target strip)
    and ``layers`` (per target name: the ``shape``, ``shading`` and ``paint`` images, the
    ``inside`` mask and the strip's ``origin`` (column, row) in the picture), with the report
    (outline.json)."""

    __slots__ = ()
    command = "analyze outline"

    @property
    def targets(self) -> List[Dict[str, Any]]:
        return self.report["targets"]

    @property
    def layers(self) -> Dict[str, Dict[str, Any]]:
        return self._arrays["layers"]


def _columns(text: str) -> Dict[str, np.ndarray]:
    """A CSV's columns as arrays: numbers as float64, anything else as strings."""
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return {}
    header, body = rows[0], rows[1:]
    out: Dict[str, np.ndarray] = {}
    for i, name in enumerate(header):
        values = [r[i] if i < len(r) else "" for r in body]
        try:
            out[name] = np.array([float(v) for v in values], dtype=np.float64)
        except ValueError:
            out[name] = np.array(values, dtype=str)
    return out


class Study(Result):
    """:func:`shadelab.study_run`'s and :func:`shadelab.study_merge`'s result: ``results``
    (results.csv's columns as arrays: P(convex) per point × prior × rotation × token),
    ``sweep`` (sweep.csv's columns), the CSV texts themselves (``results_csv``,
    ``sweep_csv``), the ``folder`` written (merge) and the report (study.json)."""

    __slots__ = ("results_csv", "sweep_csv", "folder")
    command = "study run"

    def __init__(
        self,
        report: Dict[str, Any],
        results_csv: str,
        sweep_csv: str,
        handle: Any = None,
        folder: Optional[str] = None,
    ) -> None:
        super().__init__(
            report, {"results": _columns(results_csv), "sweep": _columns(sweep_csv)}, handle
        )
        self.results_csv = results_csv
        self.sweep_csv = sweep_csv
        self.folder = folder

    @property
    def results(self) -> Dict[str, np.ndarray]:
        return self._arrays["results"]

    @property
    def sweep(self) -> Dict[str, np.ndarray]:
        return self._arrays["sweep"]


class Evaluation(Result):
    """:func:`shadelab.evaluate`'s result: ``cases`` (a dict per row: set, object, light,
    boundary, method, ``normal_error``, ``depth_error``, residual, seconds…), the Markdown
    ``table`` and the ``folder`` written (None without ``out``)."""

    __slots__ = ("table", "folder")
    command = "eval"

    def __init__(self, cases: List[Dict[str, Any]], table: str, folder: Optional[str]) -> None:
        super().__init__({"cases": cases}, {})
        self.table = table
        self.folder = folder

    @property
    def cases(self) -> List[Dict[str, Any]]:
        return self.report["cases"]

    def mean_errors_deg(self) -> np.ndarray:
        """Each row's mean angular error in degrees (NaN where there is no truth)."""
        return np.array(
            [
                (c.get("normal_error") or {}).get("mean_deg", np.nan)
                for c in self.cases
            ],
            dtype=np.float64,
        )


class Gallery(Result):
    """:func:`shadelab.gallery`'s result: the ``folder`` and ``index`` page written and the
    ``presets`` rendered (name, stimulus, geometry, seed, files)."""

    __slots__ = ()
    command = "gallery"

    @property
    def folder(self) -> str:
        return self.report["folder"]

    @property
    def presets(self) -> List[Dict[str, Any]]:
        return self.report["presets"]


class Bench(Result):
    """:func:`shadelab.bench`'s result: ``rows`` (per size, each solver's seconds, iterations
    and convergence), the printed ``table`` and the report."""

    __slots__ = ("table",)
    command = "bench"

    def __init__(self, report: Dict[str, Any], table: str) -> None:
        super().__init__(report, {})
        self.table = table

    @property
    def rows(self) -> List[Dict[str, Any]]:
        return self.report["rows"]


class Benchmark(Result):
    """:func:`shadelab.benchmark`'s result: ``scores`` (per stimulus set and model: direction
    agreement and Spearman ρ), ``directions`` (per stimulus, the target the source expects to
    look lighter, the one people saw as lighter or None, and the source), ``rows`` (every
    model on every stimulus), the Markdown ``table``, the ``folder`` written (or None) and the
    report."""

    __slots__ = ("table", "folder")
    command = "benchmark"

    def __init__(self, report: Dict[str, Any], table: str, folder: Optional[str]) -> None:
        super().__init__(report, {})
        self.table = table
        self.folder = folder

    @property
    def scores(self) -> List[Dict[str, Any]]:
        return self.report["scores"]

    @property
    def directions(self) -> List[Dict[str, Any]]:
        return self.report["directions"]

    @property
    def rows(self) -> List[Dict[str, Any]]:
        return self.report["rows"]


class Experiment(Result):
    """:func:`shadelab.experiment`'s result: the ``design`` (design.json: trials, rotations,
    keys, display, jsPsych versions), the ``folder`` written, the files it ``kept`` that the
    design did not write, and ``install_error`` (why jsPsych was not installed, or None)."""

    __slots__ = ("folder", "kept", "install_error")
    command = "experiment"

    def __init__(
        self, report: Dict[str, Any], folder: str, kept: List[str], install_error: Optional[str]
    ) -> None:
        super().__init__(report, {})
        self.folder = folder
        self.kept = kept
        self.install_error = install_error

    @property
    def design(self) -> Dict[str, Any]:
        return self.report["design"]


class Fit(Result):
    """:func:`shadelab.fit_observer`'s result: the ``pooled`` fit (``prior_tilt_deg`` μ,
    ``prior_kappa`` κ, ``convexity_prior`` π and ``lapse`` λ, each a dict of its ``value``
    and ``ci95``, the profile-likelihood 95 % interval, and ``ci95_bootstrap``), each
    participant's (``participants``, empty for one), the ``group`` summary across participants
    (None for one) and the report (fit.json, where the pooled fit's fields are top level)."""

    __slots__ = ()
    command = "fit observer"

    #: The fitted parameters, as the report names them.
    PARAMETERS = ("prior_tilt_deg", "prior_kappa", "convexity_prior", "lapse")

    @property
    def pooled(self) -> Dict[str, Any]:
        return {k: self.report[k] for k in self.PARAMETERS}

    @property
    def participants(self) -> List[Dict[str, Any]]:
        return self.report["participants"]

    @property
    def group(self) -> Optional[Dict[str, Any]]:
        return self.report.get("group")
