"""Exports the lightness benchmark's stimuli and human data from stimupy into a folder.

Run as ``python3 -m shadelab._benchmark_data DIR [NAME ...]`` (or as a plain script: it imports
only stimupy and NumPy, so ``shadelab benchmark`` runs it without the shadelab package). It
writes ``DIR/stimuli.json`` and, per stimulus, ``SET_NAME_img.npy`` and
``SET_NAME_mask.npy``: every stimulus of ``stimupy.papers.RHS2007`` and
``stimupy.papers.murray2020`` that has human data, or those named (``NAME`` or ``SET/NAME``).

The human values are stimupy's: RHS2007's ``effect_strength`` (stimupy 1.2.0 keeps it in
``experimental_data``, except for ``todorovic_benary1_2`` and ``todorovic_benary3_4``, which
keep it at the top of the dict; the bullseyes and the other stimuli without human data have
neither) and murray2020's ``mean_proportion_expected`` with ``CI95_proportion_expected``.

Which target the data's source expects people to see as lighter is stated per stimulus in
``SOURCES`` below, from the primary sources, in stimupy 1.2.0's target numbering: for RHS2007
the authors' own MATLAB code (``region.hi``, "supposed to be perceptually brighter"), for
murray2020 the paper's Figure 1 and text. Each entry also records where the source's region
lies in stimupy's picture (``at``: degrees from the picture's centre, x right, y up), which
the test suite checks against stimupy's own target masks. Each exported stimulus records the
expected-lighter target, the citation (``direction_source``), that position and, where the
source itself calls the stimulus's direction unreliable, why (``no_direction``).
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

# The RHS2007 authors' code: github srhande/flodog-models at this commit (Robinson, Hammon &
# de Sa's MATLAB, revised 2014). params/prep_params.m: "img.region.hi: label(s) of regions
# which are supposed to be perceptually brighter", "region.lo: ... darker"; each
# testpatterns/make_*.m sets hi and lo on the regions functions/label_regions.m numbers (the
# grey 0.5 regions of the padded 1024 x 1024 picture in raster order, the grey padding first);
# params/get_human_data.m holds the human values (stimupy's effect_strength are these times
# 4.18). START_HERE.m pairs each make_*.m with its data's name.
FLODOG_MODELS = "srhande/flodog-models@7d792958a1c377faf8a8ab82d42150011fc55806"

# Murray (2020), J. Vis. 20(7):28, full text github rfmurray/publications at this commit.
MURRAY_2020 = (
    "Murray 2020 J. Vis. 20(7):28 (rfmurray/publications@"
    "52fdd8b14df01e82863b3f618c6dfce84e583d3f 2020jov.pdf)"
)
# p. 6: "observers were expected to choose the leftmost target region in each stimulus in
# Figures 1 and 3"; Figure 5's caption: "Human observers judged the green target locations to
# be as light as or lighter than the red target locations". In Figure 1 the green dot marks
# the leftmost target of every panel; stimupy's pictures are Figure 1's, unmirrored, and its
# target 2 lies under the green dot.
MURRAY_EXPECTED = "p. 6 leftmost target expected lighter"
# p. 6: "Observers did not choose the expected target region at significantly above-chance
# rates with the connected Koffka or argyle control figures, which are known to create weak
# or nonexistent lightness illusions, and are typically used as control figures."
MURRAY_CONTROL = (
    "Murray 2020 p. 6: a control figure, known to create weak or nonexistent lightness "
    "illusions; not chosen above chance"
)


def _rhs(make, hi, target, at, frame="same"):
    """An RHS2007 entry: the source's make_*.m file and its region.hi label, the stimupy target
    it is (by position), where it lies in stimupy's picture, and how the source's picture
    maps onto stimupy's (``same``, or ``mirrored`` left-right: the recorded x is then the
    source's x negated)."""
    return {
        "lighter": target,
        "at": at,
        "source": f"{FLODOG_MODELS} testpatterns/{make} region.hi={hi}"
        + (" (stimupy's picture is the source's mirrored left-right)" if frame != "same" else ""),
    }


def _murray(panel, cell, none=None):
    """A murray2020 entry: Figure 1's panel and the grid cell (column, row from the top left;
    a half for a dot between cells) of its green dot, in stimupy's 0.5-degree cells."""
    return {
        "lighter": 2,
        "cell": cell,
        "source": f"{MURRAY_2020} {MURRAY_EXPECTED}; Fig. 1{panel} green dot",
        "no_direction": none,
    }


# Per stimulus: the target the source expects people to see as lighter (stimupy 1.2.0's
# numbering), the citation, and where the source's region lies. RHS2007 positions are the
# centroids of region.hi in the source's picture (the make_*.m files run as written, 32 px
# per degree, centred), in stimupy's frame; every one lies in or beside the recorded stimupy
# target and far from the other. Matching by pixels: the source's picture and stimupy's
# differ on under 5.2 % of the pixels in the frame named (sbc_large, sbc_small: mirrored
# left-right; in the same frame 37.7 % and 39.2 %); 9.2 % for the corrugated Mondrian and 17.1 %
# for the grating induction, whose details stimupy draws differently (region.hi still falls
# on one stimupy target); checkerboard_016's small checks are out of phase in either frame
# (10.7 %, mirrored 8.8 %), and there the surround decides: region.hi lies among white checks,
# as target 2 does.
SOURCES = {
    "RHS2007": {
        "WE_thick": _rhs("make_bm_whites_thick.m", 2, 1, (-3.00, 0.02)),
        "WE_thin_wide": _rhs("make_bm_whites_thin_wide.m", 2, 1, (-4.50, 0.02)),
        "WE_anderson": _rhs("make_whites_andersen.m", 3, 2, (2.48, -1.48)),
        "WE_howe": _rhs("make_whites_howe.m", 3, 2, (2.48, -2.98)),
        "grating_induction": _rhs("make_small_grating_induction.m", 3, 2, (-1.02, 0.02)),
        "sbc_large": _rhs("make_sbc_large.m", 3, 1, (-7.48, 0.02), "mirrored"),
        "sbc_small": _rhs("make_sbc_small.m", 3, 1, (-7.48, 0.02), "mirrored"),
        "todorovic_equal": _rhs("make_todorovic.m ('equal')", 2, 1, (-7.70, 0.02)),
        "todorovic_in_large": _rhs("make_todorovic.m ('in-large')", 2, 1, (-7.70, 0.02)),
        "todorovic_in_small": _rhs("make_todorovic.m ('in-small')", 2, 1, (-7.70, 0.02)),
        "todorovic_out": _rhs("make_todorovic.m ('out')", 2, 1, (-7.70, 0.02)),
        "checkerboard_016": _rhs("make_check_5.m", 3, 2, (5.30, -0.08)),
        "checkerboard_094": _rhs("make_check_30.m", 2, 1, (-5.62, 0.00)),
        "checkerboard_21": _rhs("make_check_67.m", 2, 1, (-5.23, 0.02)),
        "corrugated_mondrian": _rhs("make_mondrian_f.m", 3, 2, (-0.44, -2.03)),
        "benary_cross": _rhs("make_benary_cross.m", 3, 1, (-3.52, 1.44)),
        "todorovic_benary1_2": _rhs(
            "make_todorovic_benary_cross_1_2_diag.m", 4, 2, (-4.08, -0.75)
        ),
        "todorovic_benary3_4": _rhs(
            "make_todorovic_benary_cross_3_4_diag.m", 5, 2, (12.31, -0.53)
        ),
    },
    "murray2020": {
        "argyle": _murray("a", (5, 9)),
        "argyle_control": _murray("c", (5, 9), MURRAY_CONTROL),
        "argyle_long": _murray("b", (7, 9)),
        "snake": _murray("i", (4.5, 5)),
        "snake_control": _murray("j", (4.5, 5)),
        "koffka_adelson": _murray("e", (4, 6)),
        "koffka_broken": _murray("d", (2, 6)),
        "koffka_connected": _murray("f", (4, 6), MURRAY_CONTROL),
        "checkassim": _murray("h", (6, 7)),
        "simcon": _murray("k", (3.5, 7.5)),
        "simcon_articulated": _murray("l", (3.5, 7.5)),
        "white": _murray("g", (3.5, 8.5)),
    },
}


def direction(set_name, name, shape, ppd):
    """The source's verdict on one stimulus: (expected-lighter target, other target,
    citation, position (x, y) in degrees from the picture's centre, why the source gives no
    reliable direction or None). ``shape`` (height, width) and ``ppd`` place Murray's grid
    cells. Raises ValueError for a stimulus no source covers."""
    entry = SOURCES.get(set_name, {}).get(name)
    if entry is None:
        raise ValueError(f"{set_name}/{name}: no source says which target looks lighter")
    lighter = entry["lighter"]
    if "cell" in entry:
        # Murray's pictures are 16 rows of cells, 0.5 degrees each at stimupy's scale.
        cell = shape[0] / 16 / ppd
        col, row = entry["cell"]
        at = ((col + 0.5) * cell - shape[1] / ppd / 2, shape[0] / ppd / 2 - (row + 0.5) * cell)
    else:
        at = entry["at"]
    return lighter, 3 - lighter, entry["source"], at, entry.get("no_direction")


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
            ppd = float(np.ravel(stim["ppd"])[0])
            lighter, darker, source, at, no_direction = direction(
                set_name, name, img.shape, ppd
            )
            np.save(os.path.join(folder, image), img)
            np.save(os.path.join(folder, mask), labels.astype(np.float64))
            stimuli.append(
                {
                    "set": set_name,
                    "name": name,
                    "image": image,
                    "mask": mask,
                    "ppd": ppd,
                    "lighter_target": lighter,
                    "darker_target": darker,
                    "direction_source": source,
                    "source_position": [round(at[0], 4), round(at[1], 4)],
                    "no_direction": no_direction,
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
