"""Handing a stimulus to the program that shows it (docs/display.md)."""

from __future__ import annotations

from typing import Any, Dict, Tuple

import numpy as np

_UNITS = ("pix", "deg")


def to_psychopy(stim: Any, *, units: str = "pix") -> Dict[str, Any]:
    """The keyword arguments of PsychoPy's ``visual.ImageStim`` that show ``stim`` upright.

    ``stim`` is a :func:`render` dict (or a bare H×W or H×W×3 array of linear luminance 0..1,
    for ``units="pix"`` only). The result holds ``image``: the picture flipped top to bottom
    and mapped to PsychoPy's −1..1 (float32), ``size`` in PsychoPy's (width, height) order and
    ``units`` (``"pix"``: one image pixel per screen pixel; ``"deg"``: the stimulus's
    ``visual_size``, for a window whose monitor knows its distance and width).

    Why the flip: PsychoPy uploads a NumPy array as it is, and OpenGL puts a texture's first
    row at the bottom of the screen (PsychoPy flips image files, not arrays). Unflipped, a
    stimulus lit from above is shown lit from below: every bump a dimple. The test
    ``python/tests/test_psychopy_window.py`` reads the frame back from a real PsychoPy window.

    The values stay linear: this assumes a gamma-corrected window (PsychoPy's monitor
    calibration loads the display's gamma into the graphics card's lookup table), so that −1..1
    is the display's black to white in luminance. Values outside 0..1 or not finite are a
    ``ValueError`` (shadelab's stimuli never leave 0..1).

    >>> s = shadelab.render("sphere", shape=(48, 64), light="above")
    >>> kw = to_psychopy(s)
    >>> kw["size"], kw["units"], kw["image"].shape
    ((64, 48), 'pix', (48, 64))
    >>> bool((kw["image"][::-1] == np.float32(2 * s["img"] - 1)).all())  # row 0 now last
    True
    """
    if units not in _UNITS:
        raise ValueError(f"to_psychopy: unknown units {units!r} (valid: pix, deg)")
    is_dict = isinstance(stim, dict)
    img = np.asarray(stim["img"] if is_dict else stim)
    if img.dtype.kind not in "fiub" or img.ndim not in (2, 3) or (img.ndim == 3 and img.shape[2] != 3):
        raise ValueError(
            f"to_psychopy: the picture must be a real H×W or H×W×3 array, not {img.dtype} {img.shape}"
        )
    if img.size == 0:
        raise ValueError("to_psychopy: the picture is empty")
    # Integer pictures as the command line reads them: a PNG's codes.
    if img.dtype == np.uint8:
        img = img / 255.0
    elif img.dtype == np.uint16:
        img = img / 65535.0
    elif img.dtype.kind in "iub":
        raise ValueError(f"to_psychopy: {img.dtype} pictures are not read (use float, uint8 or uint16)")
    img = img.astype(np.float64)
    bad = ~np.isfinite(img)
    if bad.any():
        raise ValueError(
            f"to_psychopy: the picture holds {int(bad.sum())} NaN or infinite values "
            f"(the first at row, column {tuple(int(i) for i in np.argwhere(bad)[0][:2])})"
        )
    lo, hi = float(img.min()), float(img.max())
    if lo < 0.0 or hi > 1.0:
        out = int(((img < 0.0) | (img > 1.0)).sum())
        raise ValueError(
            f"to_psychopy: the picture reaches {lo:.4g}..{hi:.4g} ({out} values outside); "
            "linear luminance is 0..1"
        )
    height, width = img.shape[:2]
    size: Tuple[float, float]
    if units == "pix":
        size = (width, height)
    else:
        if not is_dict or "visual_size" not in stim:
            raise ValueError("to_psychopy: units='deg' needs a render dict (its visual_size)")
        vh, vw = stim["visual_size"]
        size = (float(vw), float(vh))
    image = np.ascontiguousarray(np.flipud(img * 2.0 - 1.0), dtype=np.float32)
    return {"image": image, "size": size, "units": units}
