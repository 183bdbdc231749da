"""The commands beyond render, solve and the perception sweeps: the fading disk, the outline
analysis, studies (run and merge), the evaluation, the gallery and the benchmark. Each calls
the same library pipeline as its command line twin (named in its docstring)."""

from __future__ import annotations

import csv
import io
import json
import os
from os import fspath as _fspath
from typing import Any, Dict, Optional, Sequence, Union

import numpy as np

from . import _shadelab
from ._api import _light_text, _opt, _pair, _params_json, _picture_args, _ppd
from ._results import (
    Bench,
    Benchmark,
    Evaluation,
    Experiment,
    Fading,
    Fit,
    Gallery,
    Outline,
    Study,
)

PathLike = Union[str, "os.PathLike[str]"]


def fading(
    picture: Any = "fading-disk",
    *,
    ppd: Optional[float] = None,
    mask: Any = None,
    tau: Optional[float] = None,
    duration: Optional[float] = None,
    dt: Optional[float] = None,
    jitter: Optional[float] = None,
    jitter_seed: Optional[int] = None,
    dog_sigma: Optional[float] = None,
    border: Optional[float] = None,
    seed: Optional[int] = None,
    **params: Any,
) -> Fading:
    """The fading (Troxler) disk (``shadelab analyze fading``): the band-pass energy along the
    borders of a blurred and a sharp disk, and the perceived-contrast time course of a
    first-order adaptation model with fixational jitter.

    ``picture`` is a stimulus name (default ``"fading-disk"``, rendered with ``params``,
    ``seed`` and ``ppd``), or an array (or stimupy dict) with ``ppd`` and ``mask`` (label
    1 = the blurred disk, 2 = the sharp one). ``tau`` (s), ``duration`` (s), ``dt`` (s),
    ``jitter`` (deg), ``jitter_seed``, ``dog_sigma`` (the band-pass filter's centre σ, deg)
    and ``border`` (half-width of the band measured, deg) default to the command line's.
    Returns a :class:`Fading` (``times``, ``blurred``, ``sharp``, ``eye``, ``frames``, the
    report; ``save(out)`` writes the CSV, plot, GIF and JSON).

    >>> r = fading(ppd=16, duration=2.0)
    >>> bool(r.blurred[-1] < r.sharp[-1])
    True
    """
    report, arrays, handle = _shadelab.fading(
        _picture_args(picture, True, params, seed, ppd, None, mask, fading),
        (
            _opt(float, tau),
            _opt(float, duration),
            _opt(float, dt),
            _opt(float, jitter),
            _opt(int, jitter_seed),
            _opt(float, dog_sigma),
            _opt(float, border),
        ),
    )
    return Fading(json.loads(report), dict(arrays), handle)


def outline(
    picture: Any,
    *,
    ppd: Optional[float] = None,
    shape: Any = None,
    mask: Any = None,
    light: Any = None,
    depth_scale: float = 1.0,
    lam: float = 1.0,
    seed: Optional[int] = None,
    **params: Any,
) -> Outline:
    """The outline decides (Knill & Kersten; ``shadelab analyze outline``): per target strip,
    the shape its outline implies, the shading that shape predicts, and the split of the
    picture into what the shape explains and what is left as paint.

    ``picture`` is a stimulus name (rendered with ``params``, ``seed``, ``ppd`` and ``shape``
    (height, width)) or an image array with ``mask`` (target labels); ``light`` the light
    (as for :func:`solve`; default: estimated per target); ``depth_scale`` scales the
    outline's profile, ``lam`` the crease-preserving smoothness. Returns an
    :class:`Outline` (``targets``, ``layers`` per target, the report).

    >>> r = outline("knill-kersten", shape=(64, 128), ppd=16)
    >>> sorted(r.layers) == sorted(t["name"] for t in r.targets)
    True
    """
    report, layers, handle = _shadelab.outline(
        _picture_args(picture, False, params, seed, ppd, shape, mask, outline),
        None if light is None else _light_text(light),
        float(depth_scale),
        float(lam),
    )
    return Outline(json.loads(report), {"layers": {k: dict(v) for k, v in layers.items()}}, handle)


def _spec_args(spec: Any) -> Any:
    """A study spec as (path, None) or (None, JSON text)."""
    if isinstance(spec, dict):
        return None, json.dumps(spec)
    return _fspath(spec), None


def study_run(spec: Union[PathLike, Dict[str, Any]], *, shard: Optional[str] = None) -> Study:
    """Runs a study (``shadelab study run``): a grid of stimuli × parameters × priors, whole
    or one ``shard`` (``"I/N"``, as the command line's ``--shard``). ``spec`` is a study spec
    file's path or the same JSON as a dict (docs/study.md). Returns a :class:`Study`
    (``results`` and ``sweep`` as columns of arrays, the report); ``save(out)`` writes the
    folder ``study merge`` joins."""
    path, text = _spec_args(spec)
    report, results, sweep, handle = _shadelab.study_run(path, text, _opt(str, shard))
    return Study(json.loads(report), results, sweep, handle)


def study_merge(folders: Sequence[PathLike], out: PathLike, *, force: bool = False) -> Study:
    """Joins the output folders of every shard of a study into ``out``
    (``shadelab study merge``), identical to an unsharded run. Returns a :class:`Study` with
    the merged ``results`` and ``sweep`` and the ``folder`` written."""
    report, results, sweep, folder = _shadelab.study_merge(
        [_fspath(f) for f in folders], _fspath(out), bool(force)
    )
    return Study(json.loads(report), results, sweep, None, folder)


def _names(values: Optional[Union[str, Sequence[str]]]) -> Optional[list]:
    if values is None:
        return None
    if isinstance(values, str):
        return [v for v in values.split(",") if v.strip()]
    return [str(v) for v in values]


def evaluate(
    data: PathLike,
    *,
    out: Optional[PathLike] = None,
    force: bool = False,
    only: Optional[Union[str, Sequence[str]]] = None,
    objects: Optional[Union[str, Sequence[str]]] = None,
    ball_images: Optional[Union[str, Sequence[str]]] = None,
    diligent_light: Any = None,
    boundary: Optional[str] = None,
    albedo_quantile: Optional[float] = None,
    ball_albedo_from_truth: bool = False,
    bunny_size: Optional[int] = None,
    methods: Optional[Union[str, Sequence[str]]] = None,
    lam: Optional[float] = None,
    tol: Optional[float] = None,
    max_iter: Optional[int] = None,
) -> Evaluation:
    """The shape-from-shading engine measured on real data (``shadelab eval``): the bunny,
    Mozart, DiLiGenT, Beethoven and the ball, from the data folder ``data``
    (docs/evaluation.md). ``only`` the sets, ``objects`` the DiLiGenT objects,
    ``ball_images`` the ball photographs, ``methods`` the solvers (a row each; by default
    the one ``solve`` uses, nested-lm; ``"multigrid"`` is the fast choice), and the other
    settings as the command line's flags. With ``out``, the folder (the table, every number,
    a picture per row) is written as the command line writes it. Returns an
    :class:`Evaluation` (``cases``, ``table``, ``folder``)."""
    cases, table, folder = _shadelab.evaluate(
        _fspath(data),
        None if out is None else _fspath(out),
        bool(force),
        (
            _names(only),
            _names(objects),
            _names(ball_images),
            None if diligent_light is None else _light_text(diligent_light),
            _opt(str, boundary),
            _opt(float, albedo_quantile),
            bool(ball_albedo_from_truth),
            _opt(int, bunny_size),
            _names(methods),
            _opt(float, lam),
            _opt(float, tol),
            _opt(int, max_iter),
        ),
    )
    return Evaluation(json.loads(cases), table, folder)


def gallery(out: PathLike, *, presets: Optional[PathLike] = None, force: bool = False) -> Gallery:
    """Renders every preset (the built-in ones, or a folder of preset JSON files) into ``out``
    with thumbnails and an ``index.html`` (``shadelab gallery``). Returns a :class:`Gallery`
    (``folder``, ``presets``)."""
    report = _shadelab.gallery(
        _fspath(out), None if presets is None else _fspath(presets), bool(force)
    )
    return Gallery(json.loads(report), {})


def bench(
    *,
    sizes: Sequence[int] = (128, 256, 512, 1024),
    methods: Union[str, Sequence[str]] = ("multigrid", "nested-lm", "jacobi"),
    lam: float = 1.0,
    shape: str = "sphere",
    light: Any = (0.0, 0.0, 1.0),
    jacobi_up_to: int = 256,
    integrable_up_to: int = 512,
    reference: PathLike = "../shared/reference",
    reference_up_to: int = 256,
    repeat: int = 3,
) -> Bench:
    """Times the shape-from-shading solvers on a synthetic ``shape`` at each size
    (``shadelab bench``): multigrid (always: every ratio is to it) and the ``methods`` named
    (a list or a comma-separated string: jacobi up to ``jacobi_up_to``, integrable,
    integrable-lm and nested-lm up to ``integrable_up_to``) at brightness weight ``lam``, and
    the NumPy reference solver from ``reference`` up to ``reference_up_to`` when python3 with
    NumPy and that folder are there. Returns a :class:`Bench` (``rows``, ``table``)."""
    names = methods.split(",") if isinstance(methods, str) else [str(m) for m in methods]
    report, table = _shadelab.bench(
        [int(n) for n in sizes],
        names,
        float(lam),
        str(shape),
        _light_text(light),
        int(jacobi_up_to),
        int(integrable_up_to),
        _fspath(reference),
        int(reference_up_to),
        int(repeat),
    )
    return Bench(json.loads(report), table)


def benchmark(
    *,
    out: Optional[PathLike] = None,
    force: bool = False,
    models: Union[str, Sequence[str]] = "all",
    stimuli: Optional[Union[str, Sequence[str]]] = None,
) -> Benchmark:
    """Scores the lightness models against people (``shadelab benchmark``): every model
    (``all`` or the names given: odog, lodog, flodog, retinex, highpass) on every stimulus of
    stimupy's ``papers.RHS2007`` and ``papers.murray2020`` that has human data, or the
    ``stimuli`` named (``NAME`` or ``SET/NAME``). The stimuli and human values come from
    stimupy (``pip install stimupy==1.2.0``), exported by :mod:`shadelab._benchmark_data`;
    ``out`` gets the command line's folder. Returns a :class:`Benchmark`."""
    import tempfile

    from . import _benchmark_data as benchmark_data

    names = _names(stimuli) or []
    model_text = models if isinstance(models, str) else ",".join(str(m) for m in models)
    with tempfile.TemporaryDirectory(prefix="shadelab-benchmark-") as export:
        benchmark_data.export(export, names)
        report, table, folder = _shadelab.benchmark(
            export,
            model_text,
            names,
            None if out is None else _fspath(out),
            bool(force),
        )
    return Benchmark(json.loads(report), table, folder)


def experiment(
    out: PathLike,
    *,
    stimulus: Optional[str] = None,
    rotations: Optional[Sequence[float]] = None,
    repeats: Optional[int] = None,
    practice: Optional[int] = None,
    slant: Optional[float] = None,
    visual_size: Any = None,
    ppd: Optional[float] = None,
    viewing_distance: Optional[float] = None,
    seed: Optional[int] = None,
    keys: Optional[str] = None,
    break_every: Optional[int] = None,
    counterbalance_keys: bool = False,
    save_url: Optional[str] = None,
    save_format: Optional[str] = None,
    prolific_code: Optional[str] = None,
    completion_url: Optional[str] = None,
    install: bool = False,
    force: bool = False,
    **params: Any,
) -> Experiment:
    """Writes a browser experiment ("bump or dimple?") into the folder ``out``
    (``shadelab experiment``): a jsPsych 8 study with its images, design and pilot mode
    (docs/experiments.md).

    ``stimulus`` (default bumps) with ``params``; ``rotations`` of the picture (degrees),
    ``repeats`` of each, ``practice`` trials, the light's ``slant``; the images'
    ``visual_size`` (height, width) in degrees at ``ppd`` for a ``viewing_distance`` in cm;
    the trial order's ``seed``; ``keys`` for bump then dimple (``"fj"``); a break every
    ``break_every`` trials; ``counterbalance_keys`` across participants; ``save_url`` (and
    ``save_format``, ``"json"`` or ``"csv"``) where the data are POSTed; ``prolific_code`` or
    ``completion_url`` where a participant goes at the end. With ``install=True`` jsPsych is
    installed into the folder by ``npm install`` (the command line does so by default); else
    the folder's README gives the command. Returns an :class:`Experiment` (``design``,
    ``folder``, ``kept`` files the design did not write, ``install_error``)."""
    settings = {
        k: v
        for k, v in dict(
            rotations=None if rotations is None else [float(r) for r in rotations],
            repeats=_opt(int, repeats),
            practice=_opt(int, practice),
            slant=_opt(float, slant),
            visual_size=_pair(visual_size, "visual_size", float),
            ppd=_ppd(ppd),
            viewing_distance=_opt(float, viewing_distance),
            seed=_opt(int, seed),
            keys=_opt(str, keys),
            break_every=_opt(int, break_every),
            counterbalance_keys=bool(counterbalance_keys),
            save_url=_opt(str, save_url),
            save_format=_opt(str, save_format),
            prolific_code=_opt(str, prolific_code),
            completion_url=_opt(str, completion_url),
            install=bool(install),
        ).items()
        if v is not None
    }
    report, folder, kept, install_error = _shadelab.experiment(
        _fspath(out), _opt(str, stimulus), _params_json(params, stimulus, experiment), json.dumps(settings), bool(force)
    )
    return Experiment(json.loads(report), folder, list(kept), install_error)


def _responses_text(responses: Any) -> Optional[str]:
    """A table handed over in memory as CSV text (None for a path): anything with ``to_csv``
    (a pandas or polars DataFrame), or a dict of equal-length columns (``rotation_deg`` and
    ``response``, optionally ``participant``, ``block``, …)."""
    if isinstance(responses, (str, os.PathLike)):
        return None
    if hasattr(responses, "to_csv"):
        try:
            return responses.to_csv(index=False)
        except TypeError:
            return responses.to_csv()
    if isinstance(responses, dict):
        columns = {str(k): list(np.asarray(v).ravel()) for k, v in responses.items()}
        lengths = {len(v) for v in columns.values()}
        if len(lengths) != 1:
            raise ValueError(f"responses: the columns have different lengths {sorted(lengths)}")
        buffer = io.StringIO()
        w = csv.writer(buffer, lineterminator="\n")
        w.writerow(columns)
        for row in zip(*columns.values()):
            w.writerow([_cell(v) for v in row])
        return buffer.getvalue()
    raise ValueError(
        "responses: a CSV or jsPsych JSON file or folder, a DataFrame, or a dict of columns "
        f"(rotation_deg, response, …), not {type(responses).__name__}"
    )


def _cell(v: Any) -> str:
    """A CSV cell: booleans as convex/concave judgements' 1/0, numbers as Python prints them."""
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, np.generic):
        return str(v.item())
    return str(v)



def experiment_pilot(
    study: PathLike,
    simulate: str,
    *,
    participant: Optional[str] = None,
    out: Optional[PathLike] = None,
    force: bool = False,
) -> str:
    """The study's simulated participant without a browser (``shadelab experiment pilot``):
    the trial rows the page in ``study`` (its folder or ``design.json``) writes in pilot mode
    for the observer ``simulate`` (the page's ``simulate`` text,
    ``"tilt:T,kappa:K[,convex:C][,lapse:L][,seed:S]"``) and ``participant`` (default
    ``simulated-seedS``), as CSV text; written to ``out`` too when given (a file is replaced
    only with ``force=True``). Its ``simulated`` column says whose rows they are: give
    ``include_simulated=True`` to :func:`fit_observer` to fit them."""
    csv_text, _participant, _seed = _shadelab.experiment_pilot(
        _fspath(study),
        str(simulate),
        None if participant is None else str(participant),
        None if out is None else _fspath(out),
        bool(force),
    )
    return csv_text


def fit_observer(
    responses: Any,
    *,
    keys: Optional[str] = None,
    include_simulated: bool = False,
    mixed_designs: bool = False,
    design: Optional[PathLike] = None,
    lapse: Optional[float] = None,
    nonparametric: bool = False,
    bootstrap: Optional[int] = None,
    seed: Optional[int] = None,
) -> Fit:
    """Fits the observer model P(convex | θ) — a von Mises light prior (μ, κ), a convexity
    prior π and a lapse rate — to bump/dimple responses by maximum likelihood
    (``shadelab fit observer``), per participant and pooled, with a group summary.

    ``responses``: a file (shadelab's responses CSV, jsPsych's data as CSV or JSON), a folder
    of them, a DataFrame (anything with ``to_csv``), or a dict of columns (``rotation_deg``,
    ``response`` as convex/concave/1/0 or booleans, optionally ``participant``). ``keys`` maps
    key presses to judgements (``"fj"`` or ``"arrowleft,arrowright"``, bump then dimple);
    ``include_simulated`` fits rows whose ``simulated`` column is set (a pilot's) too, which
    are otherwise counted and left out (the Methods paragraph then says they were simulated);
    ``mixed_designs`` pools files of different designs (``design_hash``), otherwise refused;
    ``design`` the experiment's design.json for the Methods paragraph; ``lapse`` fixes the
    lapse rate; ``bootstrap`` replicates (with ``seed``) give intervals beside the
    profile-likelihood ones. Returns a :class:`Fit` (``pooled``, ``participants``, ``group``,
    the report; ``save(out)`` writes the command line's folder: fit.json, the figures and the
    Methods paragraph, methods.md)."""
    text = _responses_text(responses)
    name = "<data>" if text is not None else _fspath(responses)
    report, handle = _shadelab.fit_observer(
        name,
        text,
        _opt(str, keys),
        bool(include_simulated),
        bool(mixed_designs),
        None if design is None else _fspath(design),
        _opt(float, lapse),
        bool(nonparametric),
        _opt(int, bootstrap),
        _opt(int, seed),
    )
    return Fit(json.loads(report), {}, handle)
