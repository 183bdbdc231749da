"""shadelab: shape-from-shading stimuli and analyses for vision science, as NumPy arrays.

The functions here call the same library pipelines as the ``shadelab`` command line
(``render``, ``solve``, ``analyze prior-sweep``, ``analyze observer``, ``analyze lightness``),
in-process: no files, no subprocess. Conventions are stimupy's and NumPy's:

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
from ._display import to_psychopy

__all__ = [
    "Reconstruction",
    "describe",
    "lightness",
    "observer",
    "prior_sweep",
    "render",
    "save",
    "solve",
    "stimuli",
    "to_psychopy",
]
