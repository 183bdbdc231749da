"""Exports the lightness benchmark's stimuli and human data from stimupy into a folder.

Run as ``python3 -m shadelab._benchmark_data DIR [NAME ...]`` (or as a plain script: it imports
only stimupy and NumPy, so ``shadelab benchmark`` runs it without the shadelab package). It
writes ``DIR/stimuli.json`` and, per stimulus, ``SET_NAME_img.npy`` and
``SET_NAME_mask.npy``: every stimulus of ``stimupy.papers.RHS2007`` and
``stimupy.papers.murray2020`` that has human data, or those named (``NAME`` or ``SET/NAME``).

The human values are stimupy's: RHS2007's ``effect_strength`` (stimupy keeps it in
``experimental_data`` or, for the bullseyes, at the top of the dict) and murray2020's
``mean_proportion_expected`` with ``CI95_proportion_expected``. Which target people see as
lighter is stimupy's order: target 1 in RHS2007, target 2 in murray2020 (checked on the
classic simultaneous-contrast and White stimuli of both sets: the lighter-looking target is the
one on the dark surround).
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
        ("RHS2007", RHS2007, {}, 1, 2),
        ("murray2020", murray2020, {"ppd": MURRAY_PPD}, 2, 1),
    ]


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
    for set_name, module, kwargs, lighter, darker in _sets():
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
            np.save(os.path.join(folder, image), np.asarray(stim["img"], dtype=np.float64))
            np.save(os.path.join(folder, mask), np.asarray(stim["target_mask"], dtype=np.float64))
            stimuli.append(
                {
                    "set": set_name,
                    "name": name,
                    "image": image,
                    "mask": mask,
                    "ppd": float(np.ravel(stim["ppd"])[0]),
                    "lighter_target": lighter,
                    "darker_target": darker,
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
