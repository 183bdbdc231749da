"""Handing a stimulus to the program that shows it (docs/display.md)."""

from __future__ import annotations

from typing import Any, Dict, Optional, Tuple

import numpy as np

_UNITS = ("pix", "deg")


def to_psychopy(
    stim: Any,
    *,
    units: str = "pix",
    codes: Optional[bool] = None,
    display: Any = None,
    luminance: Any = None,
) -> Dict[str, Any]:
    """The keyword arguments of PsychoPy's ``visual.ImageStim`` that show ``stim`` upright.

    ``stim`` is a :func:`render` dict (or a bare H×W or H×W×3 array of linear luminance 0..1,
    for ``units="pix"`` only). The result holds ``image``: the picture flipped top to bottom
    and mapped to PsychoPy's −1..1 (float32), ``size`` in PsychoPy's (width, height) order and
    ``units`` (``"pix"``: one image pixel per screen pixel; ``"deg"``: the stimulus's
    ``visual_size``, for a window whose monitor knows its distance and width).

    An H×W×3 picture stays 0..1: PsychoPy maps a gray array's −1..1 to black..white but draws
    an RGB float array's 0..1 as it is (its image shader; measured in a window: 0.5686 → code
    145, where −1..1 would give 200).

    Why the flip: PsychoPy uploads a NumPy array as it is, and OpenGL puts a texture's first
    row at the bottom of the screen (PsychoPy flips image files, not arrays). Unflipped, a
    stimulus lit from above is shown lit from below: every bump a dimple. The test
    ``python/tests/test_psychopy_window.py`` reads the frame back from a real PsychoPy window.

    The values stay linear: this assumes a gamma-corrected window (PsychoPy's monitor
    calibration loads the display's gamma into the graphics card's lookup table), so that −1..1
    is the display's black to white in luminance. Values outside 0..1 or not finite are a
    ``ValueError`` (shadelab's stimuli never leave 0..1).

    A dict rendered for a display (``render(..., display=...)``) is shown by its ``codes``
    instead (``codes=None`` chooses so; ``codes=False`` shows the linear ``img``): each code c
    becomes c / top · 2 − 1, so that a window *without* gamma correction (the display's own
    response, which the codes already invert) puts exactly those codes in the frame buffer —
    8-bit codes in an 8-bit window, 10-bit ones in a window opened with ``bpc=10``; bit-stolen
    codes are RGB. The test reads them back from a real window, code for code. ``display=``
    (and ``luminance=``, as :func:`render` takes them) renders a dict again for that display
    first: ``to_psychopy(s, display="lab.json")`` is ``to_psychopy(render(..., display=...))``
    of the same stimulus.

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
    if display is not None:
        if not is_dict or "stimulus" not in stim:
            raise ValueError("to_psychopy: display= needs a dict that shadelab.render returned")
        from ._api import render

        stim = render(
            stim["stimulus"],
            shape=stim["shape"],
            ppd=stim["ppd"],
            seed=stim["seed"],
            display=display,
            luminance=luminance,
            **stim["parameters"],
        )
    elif luminance is not None:
        raise ValueError("to_psychopy: luminance= needs display=")
    shown = is_dict and isinstance(stim.get("display"), dict) and "codes" in stim
    if codes and not shown:
        raise ValueError("to_psychopy: codes=True needs a dict rendered with display=...")
    if shown and codes is not False:
        top = float(2 ** int(stim["display"]["bit_depth"]) - 1)
        values = np.asarray(stim["codes"], dtype=np.float64) / top
        return {
            "image": _texture(values),
            "size": _size(stim, values.shape, units),
            "units": units,
        }
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
    return {"image": _texture(img), "size": _size(stim, img.shape, units), "units": units}


def _texture(values: np.ndarray) -> np.ndarray:
    """Linear 0..1 as the array ``ImageStim`` shows: flipped top to bottom; a gray H×W array
    mapped to −1..1 (PsychoPy's signed luminance texture), an H×W×3 one left 0..1 (PsychoPy
    draws RGB float arrays through its image shader as they are, checked in a window)."""
    signed = values * 2.0 - 1.0 if values.ndim == 2 else values
    return np.ascontiguousarray(np.flipud(signed), dtype=np.float32)


def _size(stim: Any, shape: Tuple[int, ...], units: str) -> Tuple[float, float]:
    """PsychoPy's (width, height): the picture's pixels, or the dict's visual size."""
    if units == "pix":
        return (shape[1], shape[0])
    if not isinstance(stim, dict) or "visual_size" not in stim:
        raise ValueError("to_psychopy: units='deg' needs a render dict (its visual_size)")
    vh, vw = stim["visual_size"]
    return (float(vw), float(vh))
