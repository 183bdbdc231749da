"""prior_sweep, observer, lightness: the analyses on a stimulus by name or on an array."""

import numpy as np
import pytest

import shadelab
from conftest import owns_rust_buffer


def test_prior_sweep_on_a_stimulus():
    r = shadelab.prior_sweep("bumps", shape=(64, 96), ppd=8, tilts=[0, 90, 180, 270])
    np.testing.assert_array_equal(r["tilts"], [0, 90, 180, 270])
    assert r["convexities"].shape == (len(r["tokens"]), 4)
    assert r["width"] == 96 and r["height"] == 64 and r["command"] == "analyze prior-sweep"
    # Each token flips between convex and concave as the assumed light turns round.
    assert np.all(np.sign(r["convexities"][:, 0]) == -np.sign(r["convexities"][:, 2]))


def test_prior_sweep_on_an_array_equals_the_stimulus_by_name():
    s = shadelab.render("bumps", shape=(64, 96), ppd=8)
    by_name = shadelab.prior_sweep("bumps", shape=(64, 96), ppd=8, tilts=[0, 180])
    on_array = shadelab.prior_sweep(s["img"], mask=s["target_mask"], tilts=[0, 180])
    np.testing.assert_allclose(on_array["convexities"], by_name["convexities"], atol=1e-12)
    assert owns_rust_buffer(on_array["convexities"])


def test_the_default_domain_is_the_clis_auto():
    # An object on a backdrop (the sphere) is solved on its target; a relief (bumps) whole.
    sphere = shadelab.prior_sweep("sphere", shape=48, ppd=8, tilts=[0, 180])
    bumps = shadelab.prior_sweep("bumps", shape=(64, 96), ppd=8, tilts=[0, 180])
    assert sphere["parameters"]["domain"] == "tokens"
    assert bumps["parameters"]["domain"] == "image"
    whole = shadelab.prior_sweep("sphere", shape=48, ppd=8, tilts=[0, 180], domain="image")
    assert whole["parameters"]["domain"] == "image"
    assert not np.array_equal(whole["convexities"], sphere["convexities"])
    with pytest.raises(ValueError, match="domain"):
        shadelab.prior_sweep("sphere", shape=48, tilts=[0], domain="everything")


def test_prior_sweep_method_is_recorded_and_a_lone_sideways_disc_flips_at_the_vertical():
    # A disc lit from the side is mirror-symmetric top to bottom: under either method its
    # convexity changes sign exactly where the assumed light turns above or below.
    for method in ["multigrid", "integrable-lm"]:
        r = shadelab.prior_sweep("sideways", ppd=12, rows=1, columns=1, method=method)
        assert r["parameters"]["method"] == method
        flips = r["tokens"][0]["flips_deg"]
        assert len(flips) == 2 and all(min(abs(f - v) for v in (0, 180, 360)) < 0.01 for f in flips), flips
    with pytest.raises(ValueError, match="solver method"):
        shadelab.prior_sweep("sideways", ppd=12, tilts=[0], method="newton")


def test_prior_sweep_solver_settings_are_the_clis():
    default = shadelab.prior_sweep("bumps", shape=(64, 96), ppd=8, tilts=[0])
    cli_defaults = {k: default["parameters"][k] for k in ("lambda", "tol", "max_iter")}
    r = shadelab.prior_sweep("bumps", shape=(64, 96), ppd=8, tilts=[0], lam=10, tol=1e-5, max_iter=7)
    assert {k: r["parameters"][k] for k in cli_defaults} == {"lambda": 10, "tol": 1e-5, "max_iter": 7}
    assert cli_defaults != {"lambda": 10, "tol": 1e-5, "max_iter": 7}
    for bad, word in [({"lam": 0}, "lambda"), ({"tol": float("nan")}, "tol"), ({"max_iter": 0}, "max_iter")]:
        with pytest.raises(ValueError, match=word):
            shadelab.observer("bumps", shape=(64, 96), ppd=8, **bad)


def test_prior_sweep_bad_tilt_is_a_value_error():
    with pytest.raises(ValueError, match="tilt"):
        shadelab.prior_sweep("bumps", shape=32, tilts=[float("nan")])


def test_observer_reports_percepts():
    r = shadelab.observer("bumps", shape=(64, 96), ppd=8, rotations=[0, 180], tilts=list(range(0, 360, 30)))
    assert r["command"] == "analyze observer" and r["width"] == 96
    assert len(r["percepts"]) >= 1


def test_observer_bad_noise_is_a_value_error():
    with pytest.raises(ValueError, match="noise"):
        shadelab.observer("bumps", shape=32, noise=-1.0)


def test_lightness_on_an_array_and_by_name_agree():
    s = shadelab.render("checker-shadow", ppd=16)
    on_array = shadelab.lightness(s["img"], ppd=16, model="retinex").output
    by_name = shadelab.lightness("checker-shadow", ppd=16, model="retinex").output
    assert on_array.shape == s["shape"]
    np.testing.assert_array_equal(on_array, by_name)
    assert owns_rust_buffer(on_array)


def test_lightness_target_means_with_a_mask():
    s = shadelab.render("checker-shadow", ppd=16)
    r = shadelab.lightness(s["img"], ppd=16, mask=s["target_mask"])
    out, means = r.output, r.targets
    assert [m["label"] for m in means] == [1, 2]
    for m in means:
        np.testing.assert_allclose(m["output"], out[s["target_mask"] == m["label"]].mean())
    # The luminance of A and B is the same (the illusion); the report says so per target.
    assert means[0]["luminance"] == means[1]["luminance"]


def test_lightness_needs_ppd_for_an_array():
    with pytest.raises(ValueError, match="pixels per degree"):
        shadelab.lightness(np.ones((16, 16)), model="odog")


def test_lightness_unknown_model_is_a_value_error():
    with pytest.raises(ValueError, match="unknown model"):
        shadelab.lightness(np.ones((16, 16)), ppd=8, model="magic")


def test_lightness_rgb_is_read_as_luminance():
    gray = np.linspace(0, 1, 256).reshape(16, 16)
    rgb = np.repeat(gray[:, :, None], 3, axis=2)
    np.testing.assert_allclose(shadelab.lightness(rgb, ppd=8, model="retinex").output,
                               shadelab.lightness(gray, ppd=8, model="retinex").output, atol=1e-12)


def test_lightness_without_targets_has_none():
    r = shadelab.lightness(np.linspace(0, 1, 256).reshape(16, 16), ppd=8, model="retinex")
    assert r.targets == [] and r.output.shape == (16, 16)


ROUTE_STIMULI = [
    "crater",
    "bumps",
    "sideways",
    "strips",
    "hollow-mask",
    "circles-binary",
    "boundary-strips",
    "sphere",
    "checker-shadow",
]


def _numbers(value, path=""):
    """Every number in a report by its path, without timings and the input's description."""
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            if key not in ("seconds", "input"):
                out.update(_numbers(item, f"{path}/{key}"))
        return out
    if isinstance(value, (list, tuple)):
        out = {}
        for i, item in enumerate(value):
            out.update(_numbers(item, f"{path}[{i}]"))
        return out
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return {path: float(value)}
    if isinstance(value, str):
        return {path: value}
    return {}


@pytest.mark.parametrize("name", ROUTE_STIMULI)
def test_every_analysis_of_a_rendered_dict_gives_the_stimulus_numbers(name):
    # The dict carries what a sidecar carries (albedo, ambient level, light, targets and
    # whether they are silhouettes): every analysis of it gives the numbers of the stimulus
    # by name, to rounding (the CLI's routes: tests/routes.rs).
    ppd = 12
    stim = shadelab.render(name, ppd=ppd)
    analyses = {
        "outline": lambda p, **k: shadelab.outline(p, **k),
        "lightness": lambda p, **k: shadelab.lightness(p, model="flodog", **k),
    }
    if name != "checker-shadow":
        analyses["prior_sweep"] = lambda p, **k: shadelab.prior_sweep(p, tilts=[0, 90, 180, 270], **k)
        analyses["observer"] = lambda p, **k: shadelab.observer(
            p, tilts=list(range(0, 360, 45)), rotations=[0, 90, 180, 270], **k
        )
    for analysis, run in analyses.items():
        by_name = _numbers(run(name, ppd=ppd).report)
        by_dict = _numbers(run(stim).report)
        assert by_name.keys() == by_dict.keys(), analysis
        assert len(by_name) > 3, analysis
        for key, expected in by_name.items():
            got = by_dict[key]
            if isinstance(expected, str):
                assert got == expected, f"{name} {analysis} {key}"
            else:
                assert got == pytest.approx(expected, rel=1e-9, abs=1e-9), f"{name} {analysis} {key}"


def test_a_mask_given_with_a_dict_is_not_its_silhouettes():
    # The hollow mask's face is a silhouette on a backdrop (solved on its target); a mask
    # given beside the dict says nothing of a backdrop, as --mask beside a sidecar does not.
    stim = shadelab.render("hollow-mask", ppd=8)
    own = shadelab.prior_sweep(stim, tilts=[0, 180])
    given = shadelab.prior_sweep(stim, tilts=[0, 180], mask=stim["target_mask"])
    assert own["parameters"]["domain"] == "tokens"
    assert given["parameters"]["domain"] == "image"
