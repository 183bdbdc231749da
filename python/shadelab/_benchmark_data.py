"""Exports the lightness benchmark's stimuli and human data from stimupy into a folder.

Run as ``python3 -m shadelab._benchmark_data DIR [NAME ...]`` (or as a plain script: it imports
only stimupy and NumPy, so ``shadelab benchmark`` runs it without the shadelab package). It
writes ``DIR/stimuli.json`` and, per stimulus, ``SET_NAME_img.npy`` and
``SET_NAME_mask.npy``: every stimulus of ``stimupy.papers.RHS2007`` and
``stimupy.papers.murray2020`` that has human data, or those named (``NAME`` or ``SET/NAME``).

The human values are stimupy's: RHS2007's ``effect_strength`` (stimupy keeps it in
``experimental_data`` or, for the bullseyes, at the top of the dict) and murray2020's
``mean_proportion_expected`` with ``CI95_proportion_expected``.

Which target people see as lighter is stated per stimulus in ``CONVENTIONS`` below: for the
classic illusions it follows from the illusion's published direction (a rule, cited there)
applied to stimupy's own pixel values, so it cannot silently disagree with the picture; for
the others it is stimupy's order, marked as not checked. Each exported stimulus records the
targets, the rule or its absence (``convention``) and whether a published rule decided it
(``convention_checked``).
"""

import json
import os
import sys
import warnings

# murray2020's stimuli are 16 x 16 pixels at 2 ppd; stimupy repeats each pixel ppd/2 times.
MURRAY_PPD = 16


def _sets():
    from stimupy.papers import RHS2007, murray2020

    return [
        ("RHS2007", RHS2007, {}),
        ("murray2020", murray2020, {"ppd": MURRAY_PPD}),
    ]


def _neighbours(img, mask, target):
    """The luminance just outside ``target`` (pixels of no target sharing an edge with it):
    ``border`` (all of them), ``ends`` (across the target's short sides: beyond the ends of
    its long axis) and ``sides`` (across its long sides), each a mean."""
    import numpy as np

    inside = mask == target
    free = mask == 0
    vertical = np.zeros_like(inside)
    horizontal = np.zeros_like(inside)
    vertical[1:] |= inside[:-1]
    vertical[:-1] |= inside[1:]
    horizontal[:, 1:] |= inside[:, :-1]
    horizontal[:, :-1] |= inside[:, 1:]
    vertical &= free
    horizontal &= free
    # A target taller than wide has fewer pixels above and below it than beside it: its
    # ends are above and below.
    if vertical.sum() <= horizontal.sum():
        ends, sides = vertical, horizontal
    else:
        ends, sides = horizontal, vertical
    border = vertical | horizontal
    return {
        "border": float(img[border].mean()),
        "ends": float(img[ends].mean()),
        "sides": float(img[sides].mean()),
    }


# The published direction of each classic illusion, as a rule on stimupy's pixels: which of
# the two targets people see as lighter. Each returns the key of ``_neighbours`` to compare
# and whether the target with the *lower* value there is the lighter-looking one.
RULES = {
    # Simultaneous contrast: a grey patch looks lighter on a dark background (Adelson 1993,
    # Science 262:2042, abstract; Zeman, Brooks & Ghebreab 2015, Front. Hum. Neurosci.
    # 9:368, abstract).
    "contrast": ("border", True),
    # White's effect: "a test patch placed on a dark stripe of the grating looks lighter than
    # one placed on a light stripe" (Betz, Shapley, Wichmann & Maertens 2015, J. Vis.
    # 15(11):14, abstract). The stripe a patch lies on continues beyond its ends.
    "white": ("ends", True),
    # Checkerboard contrast: the grey square surrounded by four white squares looks lighter
    # than the one surrounded by black squares, contrary to simultaneous contrast (De Valois &
    # De Valois 1988, as summarised by Hudak & Geier, ECVP abstract 771; assimilation as in
    # Barkan, Spitzer & Einav 2008, J. Vis. 8(7):27, abstract).
    "checkerboard": ("border", False),
    # Grating induction: the grey test strip takes on the grating's opposite phase (Foley &
    # McCourt 1985, JOSA A 2:1220, abstract: "an opposite phase grating will be perceived in
    # the test field"; McCourt 1982, cited by stimupy's docstring): the part flanked by the
    # dark phase looks lighter. The grating lies across the strip's long sides.
    "grating_induction": ("sides", True),
}

# Which rule decides each stimulus. Stimuli not listed keep stimupy's order (RHS2007: target
# 1; murray2020: target 2, the order of Murray's data file, which the rules confirm on simcon,
# simcon_articulated, white and checkassim) and are marked as not checked: for Anderson's and
# Howe's White variants, Todorovic's figures, the corrugated Mondrian, Benary's cross and its
# Todorovic variants, and Murray's argyle, snake and Koffka stimuli, no published statement of
# which of stimupy's two targets looks lighter was verified for this project.
CONVENTIONS = {
    "RHS2007": {
        "WE_thick": "white",
        "WE_thin_wide": "white",
        "grating_induction": "grating_induction",
        "sbc_large": "contrast",
        "sbc_small": "contrast",
        "checkerboard_016": "checkerboard",
        "checkerboard_094": "checkerboard",
        "checkerboard_21": "checkerboard",
    },
    "murray2020": {
        "simcon": "contrast",
        "simcon_articulated": "contrast",
        "white": "white",
        "checkassim": "checkerboard",
    },
}

# stimupy's order where no rule decides: (lighter, darker).
DEFAULT_ORDER = {"RHS2007": (1, 2), "murray2020": (2, 1)}


def convention(set_name, name, img, mask):
    """(lighter target, darker target, rule name or None) for one stimulus: the rule's
    verdict on the pixels where ``CONVENTIONS`` names one, else stimupy's order. Raises
    ValueError when the rule cannot tell the targets apart."""
    rule = CONVENTIONS.get(set_name, {}).get(name)
    if rule is None:
        lighter, darker = DEFAULT_ORDER[set_name]
        return lighter, darker, None
    key, lower_is_lighter = RULES[rule]
    v1 = _neighbours(img, mask, 1)[key]
    v2 = _neighbours(img, mask, 2)[key]
    if abs(v1 - v2) < 1e-6:
        raise ValueError(f"{set_name}/{name}: rule {rule} cannot tell the targets apart")
    first = (v1 < v2) == lower_is_lighter
    return (1, 2, rule) if first else (2, 1, rule)


def _human(set_name, stim):
    data = stim.get("experimental_data") or {}
    if set_name == "murray2020":
        if "mean_proportion_expected" not in data:
            return None
        ci = data.get("CI95_proportion_expected", (0.0, 0.0))
        return {
            "kind": "proportion_expected",
            "value": float(data["mean_proportion_expected"]),
            "ci95": float(abs(ci[1])),
        }
    value = data.get("effect_strength", stim.get("effect_strength"))
    if value is None:
        return None
    return {"kind": "effect_strength", "value": float(value)}


def export(folder, names=()):
    """Writes the benchmark's stimuli and human data into ``folder`` (created if needed);
    ``names`` keeps only those stimuli (``NAME`` or ``SET/NAME``). Returns the index written."""
    try:
        import numpy as np
        import stimupy
    except ImportError as e:
        raise ImportError(
            f"the benchmark needs stimupy ({e}): pip install stimupy==1.2.0"
        ) from None
    os.makedirs(folder, exist_ok=True)
    wanted = set(names)
    found = set()
    stimuli = []
    for set_name, module, kwargs in _sets():
        for name in module.__all__:
            full = f"{set_name}/{name}"
            if wanted and name not in wanted and full not in wanted:
                continue
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                stim = getattr(module, name)(**kwargs)
            human = _human(set_name, stim)
            if human is None:
                continue
            found.update({name, full})
            image = f"{set_name}_{name}_img.npy"
            mask = f"{set_name}_{name}_mask.npy"
            img = np.asarray(stim["img"], dtype=np.float64)
            labels = np.asarray(stim["target_mask"])
            lighter, darker, rule = convention(set_name, name, img, labels)
            np.save(os.path.join(folder, image), img)
            np.save(os.path.join(folder, mask), labels.astype(np.float64))
            stimuli.append(
                {
                    "set": set_name,
                    "name": name,
                    "image": image,
                    "mask": mask,
                    "ppd": float(np.ravel(stim["ppd"])[0]),
                    "lighter_target": lighter,
                    "darker_target": darker,
                    "convention": rule
                    or f"stimupy's order (target {lighter} lighter), not checked",
                    "convention_checked": rule is not None,
                    "human": human,
                }
            )
    missing = sorted(wanted - found)
    if missing:
        raise ValueError(f"no stimulus with human data called {', '.join(missing)}")
    index = {"stimupy_version": stimupy.__version__, "stimuli": stimuli}
    with open(os.path.join(folder, "stimuli.json"), "w") as f:
        json.dump(index, f, indent=1)
    return index


def main(argv):
    if len(argv) < 2:
        print("usage: benchmark_data.py DIR [NAME ...]", file=sys.stderr)
        return 2
    try:
        export(argv[1], argv[2:])
    except (ImportError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 3 if isinstance(e, ImportError) else 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
