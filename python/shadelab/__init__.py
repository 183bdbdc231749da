"""shadelab: shape-from-shading stimuli and analyses for vision science, as NumPy arrays.

Every command of the ``shadelab`` command line has its function here (``COMMANDS`` maps
each command to it), calling the same library pipeline in-process: no subprocess. Analyses
return typed results (:class:`PriorSweep`, :class:`Observer`, :class:`Lightness`,
:class:`Fading`, :class:`Outline`, :class:`Study`, …) holding NumPy arrays and the command's
report, each with ``to_dict()``, ``save(out)`` (the command line's output folder, by the same
writer) and ``figures()`` (its figures as arrays). Conventions are stimupy's and NumPy's:

* sizes are ``(height, width)``: ``visual_size`` in degrees of visual angle, ``shape`` in
  pixels, ``ppd`` pixels per degree (any two give the third);
* images are float64 arrays of linear luminance 0..1, row 0 the top row;
* normals are ``H×W×3`` unit vectors, x right, y up, z toward the viewer; a light's tilt 0 is
  from above and +90 from the left.

Errors are ``ValueError`` (bad values), ``FileNotFoundError``/``OSError`` (files named in a
parameter) and ``RuntimeError`` (a computation that cannot be done), each with the command
line's one-line message. The GIL is released while the library works.

>>> import shadelab
>>> s = shadelab.render("checkerboard", visual_size=(4, 8), ppd=8)
>>> s["img"].shape, s["shape"], s["visual_size"]
((32, 64), (32, 64), (4.0, 8.0))
"""

from ._api import (
    Reconstruction,
    __version__,
    describe,
    lightness,
    observer,
    prior_sweep,
    render,
    save,
    solve,
    stimuli,
)
from ._commands import (
    bench,
    benchmark,
    evaluate,
    experiment,
    experiment_pilot,
    fading,
    fit_observer,
    gallery,
    outline,
    study_merge,
    study_run,
)
from ._display import to_psychopy
from ._results import (
    Bench,
    Benchmark,
    Evaluation,
    Experiment,
    Fading,
    Fit,
    Gallery,
    Lightness,
    Observer,
    Outline,
    PriorSweep,
    Result,
    Stimulus,
    Study,
)

#: Each command of the ``shadelab`` command line and the function that is its twin here.
COMMANDS = {
    "render": render,
    "list": stimuli,
    "describe": describe,
    "gallery": gallery,
    "solve": solve,
    "analyze lightness": lightness,
    "analyze fading": fading,
    "analyze prior-sweep": prior_sweep,
    "analyze observer": observer,
    "analyze outline": outline,
    "bench": bench,
    "benchmark": benchmark,
    "study run": study_run,
    "study merge": study_merge,
    "eval": evaluate,
    "experiment": experiment,
    "experiment pilot": experiment_pilot,
    "fit observer": fit_observer,
}

__all__ = [
    "COMMANDS",
    "Bench",
    "Benchmark",
    "Evaluation",
    "Experiment",
    "Fading",
    "Fit",
    "Gallery",
    "Lightness",
    "Observer",
    "Outline",
    "PriorSweep",
    "Reconstruction",
    "Result",
    "Stimulus",
    "Study",
    "bench",
    "benchmark",
    "describe",
    "evaluate",
    "experiment",
    "experiment_pilot",
    "fading",
    "fit_observer",
    "gallery",
    "lightness",
    "observer",
    "outline",
    "prior_sweep",
    "render",
    "save",
    "solve",
    "stimuli",
    "study_merge",
    "study_run",
    "to_psychopy",
]
