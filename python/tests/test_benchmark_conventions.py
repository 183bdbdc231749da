"""The benchmark exporter's per-stimulus conventions (which target people see as lighter),
checked on synthetic pictures: the rules need only NumPy, not stimupy."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

_PATH = Path(__file__).resolve().parents[1] / "shadelab" / "_benchmark_data.py"
_SPEC = importlib.util.spec_from_file_location("benchmark_data_under_test", _PATH)
bd = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(bd)


def _two_sided(left, right):
    """A grey square on each half of a field whose halves are `left` and `right`;
    target 1 on the left, target 2 on the right."""
    img = np.full((40, 80), left, dtype=float)
    img[:, 40:] = right
    mask = np.zeros(img.shape, dtype=int)
    img[15:25, 15:25] = 0.5
    mask[15:25, 15:25] = 1
    img[15:25, 55:65] = 0.5
    mask[15:25, 55:65] = 2
    return img, mask


def _stripes():
    """Vertical stripes 8 px wide, black first; a tall grey patch replaces part of a black
    stripe (target 1) and of a white one (target 2), as in White's effect."""
    img = np.zeros((60, 64))
    for x0 in range(8, 64, 16):
        img[:, x0 : x0 + 8] = 1.0
    mask = np.zeros(img.shape, dtype=int)
    img[20:40, 16:24] = 0.5
    mask[20:40, 16:24] = 1
    img[20:40, 40:48] = 0.5
    mask[20:40, 40:48] = 2
    return img, mask


def test_simultaneous_contrast_makes_the_target_on_the_dark_side_lighter():
    img, mask = _two_sided(0.0, 1.0)
    assert bd.convention("murray2020", "simcon", img, mask) == (1, 2, "contrast")
    img, mask = _two_sided(1.0, 0.0)
    assert bd.convention("RHS2007", "sbc_small", img, mask) == (2, 1, "contrast")


def test_checkerboard_contrast_goes_the_other_way():
    img, mask = _two_sided(0.0, 1.0)
    assert bd.convention("RHS2007", "checkerboard_094", img, mask) == (2, 1, "checkerboard")


def test_whites_effect_follows_the_stripe_a_patch_lies_on_not_its_longer_border():
    img, mask = _stripes()
    # Target 1 lies on a black stripe, so its long sides border white; it looks lighter.
    assert bd._neighbours(img, mask, 1)["sides"] == 1.0
    assert bd.convention("RHS2007", "WE_thick", img, mask) == (1, 2, "white")
    # Plain contrast with the whole border would say the opposite.
    assert bd.convention("RHS2007", "sbc_large", img, mask)[0] == 2


def test_unlisted_stimuli_keep_the_sets_order_and_say_so():
    img, mask = _two_sided(0.0, 1.0)
    assert bd.convention("RHS2007", "benary_cross", img, mask) == (1, 2, None)
    assert bd.convention("murray2020", "snake", img, mask) == (2, 1, None)


def test_a_rule_that_cannot_tell_the_targets_apart_is_an_error():
    img, mask = _two_sided(0.5, 0.5)
    with pytest.raises(ValueError, match="cannot tell"):
        bd.convention("RHS2007", "sbc_small", img, mask)
