"""render, stimuli and describe: stimupy-style dicts in (height, width) order."""

import json
import os
import pathlib
import struct
import subprocess
import zlib

import numpy as np
import pytest

import shadelab
from conftest import owns_rust_buffer


def test_stimuli_lists_names_with_descriptions():
    s = shadelab.stimuli()
    assert {"sphere", "checkerboard", "checker-shadow", "bumps"} <= set(s)
    assert all(isinstance(v, str) and v for v in s.values())


def test_describe_gives_defaults_ranges_and_docs():
    d = shadelab.describe("checkerboard")
    assert set(d["params"]) == {
        "check",
        "intensity_first",
        "intensity_second",
        "targets",
        "intensity_target",
    }
    check = d["params"]["check"]
    assert check["default"] == 1.0 and "deg" in check["doc"] and check["range"]
    assert d["default_visual_size"] == (8.0, 8.0) and d["default_ppd"] == 32.0


def test_describe_unknown_stimulus_is_a_value_error():
    with pytest.raises(ValueError, match="unknown stimulus 'nope'"):
        shadelab.describe("nope")


def test_dict_keys_as_stimupy():
    s = shadelab.render("checkerboard", visual_size=(2, 3), ppd=10)
    for key in ("img", "target_mask", "visual_size", "ppd", "shape"):
        assert key in s
    assert s["check"] == 1.0 and s["intensity_first"] == 0.0  # every parameter by name
    assert s["stimulus"] == "checkerboard" and s["seed"] == 0


def test_shapes_are_height_width():
    s = shadelab.render("checkerboard", visual_size=(2, 3), ppd=10)
    assert s["img"].shape == (20, 30)
    assert s["shape"] == (20, 30)
    assert s["visual_size"] == (2.0, 3.0)
    assert s["target_mask"].shape == (20, 30)
    assert s["img"].dtype == np.float64


def test_shape_and_ppd_give_visual_size():
    s = shadelab.render("disc", shape=(40, 80), ppd=20)
    assert s["img"].shape == (40, 80)
    assert s["visual_size"] == (2.0, 4.0)


def test_one_number_is_a_square():
    s = shadelab.render("checkerboard", shape=24, ppd=8)
    assert s["img"].shape == (24, 24) and s["visual_size"] == (3.0, 3.0)


def test_inconsistent_size_is_a_value_error():
    with pytest.raises(ValueError, match="inconsistent size"):
        shadelab.render("checkerboard", visual_size=(2, 3), ppd=10, shape=(20, 40))


def checkerboard_by_hand(shape, check_px, first, second):
    """stimupy's checkerboard (check_visual_size × ppd an integer): check (i, j) of the grid has
    intensity_checks[0] where i + j is even, intensity_checks[1] where odd, from the top left."""
    rows = np.arange(shape[0])[:, None] // check_px
    cols = np.arange(shape[1])[None, :] // check_px
    return np.where((rows + cols) % 2 == 0, first, second).astype(float)


@pytest.mark.parametrize("size,ppd,check", [((4, 6), 10, 1.0), ((3, 5), 16, 0.5), ((8, 8), 32, 2.0)])
def test_checkerboard_equals_stimupy(size, ppd, check):
    s = shadelab.render("checkerboard", visual_size=size, ppd=ppd, check=check,
                        intensity_first=0.2, intensity_second=0.9)
    expected = checkerboard_by_hand(s["shape"], int(check * ppd), 0.2, 0.9)
    np.testing.assert_array_equal(s["img"], expected)


def _stimupy():
    """stimupy itself; the test skips saying why where it is not installed, unless
    SHADELAB_REQUIRE_STIMUPY=1 (set by .ci/run once it installed it), where it fails."""
    try:
        import stimupy
    except ImportError as e:
        if os.environ.get("SHADELAB_REQUIRE_STIMUPY") == "1":
            pytest.fail(f"stimupy cannot be imported, and SHADELAB_REQUIRE_STIMUPY=1: {e}")
        pytest.skip("stimupy is not installed (pip install stimupy==1.2.0)")
    return stimupy


def test_checkerboard_against_stimupy_itself():
    _stimupy()
    from stimupy.stimuli.checkerboards import checkerboard

    theirs = checkerboard(visual_size=(4, 6), ppd=10, check_visual_size=(1, 1),
                          intensity_checks=(0.0, 1.0))
    ours = shadelab.render("checkerboard", visual_size=(4, 6), ppd=10)
    assert ours["shape"] == tuple(theirs["shape"])
    np.testing.assert_array_equal(ours["img"], theirs["img"])
    # No targets unless asked for: stimupy's target_mask is all zeros, and so is ours.
    np.testing.assert_array_equal(ours["target_mask"], theirs["target_mask"])
    assert not ours["target_mask"].any() and ours["target_names"] == []
    # Targets named as stimupy's target_indices: the same mask and the same picture.
    theirs = checkerboard(visual_size=(4, 6), ppd=10, check_visual_size=(1, 1),
                          intensity_checks=(0.0, 1.0), target_indices=((1, 2), (3, 0)),
                          intensity_target=0.25)
    ours = shadelab.render("checkerboard", visual_size=(4, 6), ppd=10, targets="1,2;3,0",
                           intensity_target=0.25)
    np.testing.assert_array_equal(ours["target_mask"], theirs["target_mask"])
    np.testing.assert_array_equal(ours["img"], theirs["img"])


def test_stimupys_own_keywords_give_stimupys_stimulus():
    # The same call, keyword for keyword, to stimupy and to shadelab (stimupy's names are
    # aliases of shadelab's): the same picture, target mask and shape.
    _stimupy()
    from stimupy.stimuli.checkerboards import checkerboard

    for kw in [
        dict(visual_size=(4, 6), ppd=10, check_visual_size=(1, 1), intensity_checks=(0.0, 1.0)),
        dict(visual_size=(3, 5), ppd=16, check_visual_size=0.5, intensity_checks=(0.2, 0.9),
             target_indices=((1, 2), (3, 0), (0, 9)), intensity_target=0.4),
    ]:
        theirs, ours = checkerboard(**kw), shadelab.render("checkerboard", **kw)
        assert ours["shape"] == tuple(theirs["shape"])
        np.testing.assert_array_equal(ours["img"], theirs["img"])
        np.testing.assert_array_equal(ours["target_mask"], theirs["target_mask"])
    with pytest.raises(ValueError, match="square"):
        shadelab.render("checkerboard", visual_size=(4, 6), ppd=10, check_visual_size=(1, 2))
    with pytest.raises(ValueError, match="same parameter"):
        shadelab.render("checkerboard", visual_size=(4, 6), ppd=10, check_visual_size=1, check=1)
    assert shadelab.describe("checkerboard")["stimupy_names"]["check_visual_size"] == "check"


def stimupy_shape(visual_size, ppd):
    """stimupy 1.2's rule (stimupy.utils.resolution.resolve_1D), written out: the product
    rounded to 10 decimals, then rounded down to whole pixels."""
    return tuple(int(np.floor(np.round(v * ppd, 10))) for v in visual_size)


GRID = [((h, w), ppd) for h, w in [(3.3, 5.1), (0.29, 1.0), (2.0, 7.77), (4.0, 4.0)]
        for ppd in [10, 16, 31.7, 37.3, 100]]


@pytest.mark.parametrize("visual_size,ppd", GRID)
def test_shape_from_visual_size_is_stimupys(visual_size, ppd):
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = shadelab.render("checkerboard", visual_size=visual_size, ppd=ppd)
    expected = stimupy_shape(visual_size, ppd)
    assert s["shape"] == expected
    exact = all(abs(v * ppd - round(v * ppd)) < 1e-9 for v in visual_size)
    said = [str(w.message) for w in caught if "rounded down to whole pixels" in str(w.message)]
    assert len(said) == (0 if exact else 1), said
    stimupy = _stimupy()
    from stimupy.utils import resolution

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        shape, _, _ = resolution.resolve(visual_size=visual_size, ppd=ppd)
    assert s["shape"] == (shape.height, shape.width), stimupy.__version__


def test_3_3_by_5_1_degrees_at_31_7_ppd_warns_as_stimupy():
    with pytest.warns(UserWarning, match=r"3.3° high × 5.1° wide at 31.7 ppd is 104 px high × 161 px wide"):
        s = shadelab.render("checkerboard", visual_size=(3.3, 5.1), ppd=31.7)
    assert s["shape"] == (104, 161)
    assert s["notes"]["visual_size_rounded"]["asked_visual_size"] == [3.3, 5.1]


def test_ppd_as_stimupys_pair():
    a = shadelab.render("checkerboard", visual_size=(2, 3), ppd=(10, 10))
    assert a["shape"] == (20, 30) and a["ppd"] == 10
    with pytest.raises(ValueError, match="pixels are square"):
        shadelab.render("checkerboard", visual_size=(2, 3), ppd=(10, 12))


def test_a_stimupy_dict_is_taken_as_a_picture():
    # A dict with img, target_mask and ppd (stimupy's habit) stands for an image with its mask
    # and resolution: the same numbers as the array with them given by hand.
    s = shadelab.render("checker-shadow", ppd=16)
    theirs = {"img": s["img"], "target_mask": s["target_mask"], "ppd": (16, 16)}
    by_dict = shadelab.lightness(theirs, model="odog")
    by_hand = shadelab.lightness(s["img"], mask=s["target_mask"], ppd=16, model="odog")
    out_dict, means_dict = by_dict.output, by_dict.targets
    out_hand, means_hand = by_hand.output, by_hand.targets
    np.testing.assert_array_equal(out_dict, out_hand)
    assert means_dict == means_hand and [m["label"] for m in means_dict] == [1, 2]
    with pytest.raises(ValueError, match="needs 'img'"):
        shadelab.lightness({"image": s["img"]}, model="retinex")


def test_layers_of_a_surface():
    s = shadelab.render("sphere", shape=(30, 40), layers=True)
    assert s["depth"].shape == (30, 40)
    assert s["normals"].shape == (30, 40, 3)
    assert s["shading"].shape == (30, 40)
    n = np.linalg.norm(s["normals"], axis=-1)
    np.testing.assert_allclose(n, 1.0, atol=1e-9)
    inside = s["target_mask"] == 1
    assert s["target_names"] == ["object"] and inside.sum() > 0
    assert np.all(s["depth"][~inside] == 0) and s["depth"][inside].max() > 0


def test_layers_of_a_flat_stimulus_is_a_value_error():
    with pytest.raises(ValueError, match="not a rendered surface"):
        shadelab.render("checkerboard", layers=True)


def test_light_as_vector_or_text():
    a = shadelab.render("sphere", shape=32, light=(0, 0, 1))
    b = shadelab.render("sphere", shape=32, light="front")
    np.testing.assert_array_equal(a["img"], b["img"])
    c = shadelab.render("sphere", shape=32, light="left")
    assert not np.array_equal(a["img"], c["img"])


def test_targets_of_checker_shadow():
    s = shadelab.render("checker-shadow", ppd=16)
    assert s["target_names"] == ["A", "B"]
    a, b = s["img"][s["target_mask"] == 1], s["img"][s["target_mask"] == 2]
    assert a.size > 0 and b.size > 0
    assert np.all(a == a[0]) and np.all(b == a[0])  # the illusion: A and B are identical


def test_target_names_are_each_calls_own_list():
    # Repeated renders share the name strings, never the list: changing one result's list
    # leaves the next result's alone, and other targets get their own names.
    named = "0,0;0,1;0,2;1,3"
    a = shadelab.render("checkerboard", shape=(16, 32), ppd=8, targets=named)
    assert a["target_names"] == ["r0c0", "r0c1", "r0c2", "r1c3"]
    assert len(a["target_names"]) == int(a["target_mask"].max()) == 4
    a["target_names"].append("mine")
    b = shadelab.render("checkerboard", shape=(16, 32), ppd=8, targets=named)
    assert b["target_names"] == a["target_names"][:-1] and b["target_names"] is not a["target_names"]
    assert shadelab.render("checker-shadow", ppd=16)["target_names"] == ["A", "B"]
    assert shadelab.render("checkerboard", shape=(16, 32), ppd=8, targets=named)["target_names"] == b["target_names"]


def test_same_numbers_as_the_cli_sidecar(tmp_path):
    """The dict's parameters and size are those the library records in a sidecar."""
    s = shadelab.render("bumps", shape=(96, 128), ppd=8, seed=3, rows=2)
    assert s["rows"] == 2 and s["seed"] == 3 and s["shape"] == (96, 128)
    assert json.loads(json.dumps(s["parameters"])) == s["parameters"]


def test_seed_changes_random_layouts_only():
    a = shadelab.render("bumps", shape=96, ppd=8, seed=1)
    b = shadelab.render("bumps", shape=96, ppd=8, seed=1)
    np.testing.assert_array_equal(a["img"], b["img"])


def test_unknown_parameter_is_a_value_error():
    with pytest.raises(ValueError, match="parameter"):
        shadelab.render("checkerboard", chek=1.0)


def test_out_of_range_parameter_is_a_value_error():
    with pytest.raises(ValueError):
        shadelab.render("checkerboard", intensity_first=3.0)


def test_missing_file_is_file_not_found():
    with pytest.raises(FileNotFoundError, match="no-such-file.npy"):
        shadelab.render("heightfield", path="no-such-file.npy")


def test_outputs_are_not_copied():
    s = shadelab.render("sphere", shape=48, layers=True)
    for key in ("img", "target_mask", "depth", "normals"):
        assert owns_rust_buffer(s[key]), key
        assert s[key].flags.c_contiguous and s[key].flags.writeable, key


@pytest.mark.parametrize("name", ["checker-shadow", "strips", "boundary-strips"])
def test_default_size_is_height_width_like_describe(name):
    """Non-square defaults: describe's (height, width) is the render's, and the image's."""
    d = shadelab.describe(name)
    h_deg, w_deg = d["default_visual_size"]
    assert h_deg != w_deg
    s = shadelab.render(name)
    assert s["visual_size"] == (h_deg, w_deg)
    assert s["img"].shape[:2] == (round(h_deg * d["default_ppd"]), round(w_deg * d["default_ppd"]))


def test_a_picture_brighter_than_white_is_a_value_error_with_the_fix():
    # The range rule (docs/display.md): 0..1, refused rather than clipped, as the CLI does.
    with pytest.raises(ValueError, match=r"luminance reaches 1\.3\d+ .*set albedo=0\.\d+ ambient=0 specular=0\.\d+"):
        shadelab.render("sphere", shape=64, brdf="blinn-phong")
    stim = shadelab.render("sphere", shape=64, brdf="blinn-phong", albedo=0.7, specular=0.3)
    assert 0.0 <= stim["img"].min() and stim["img"].max() <= 1.0


def test_save_writes_what_the_command_line_writes(tmp_path):
    # The same pipeline and writer as `shadelab render`: the same bytes, picture, mask and
    # sidecar (tests/python.rs names the command line's binary in SHADELAB_BIN).
    cli = os.environ.get("SHADELAB_BIN")
    if not cli:
        pytest.skip("SHADELAB_BIN is not set (cargo test sets it to the shadelab binary)")
    s = shadelab.render("sphere", shape=(40, 60), ppd=20, light="tilt=30,slant=40")
    (tmp_path / "py").mkdir()
    (tmp_path / "cli").mkdir()
    lab = tmp_path / "lab.json"
    lab.write_text(json.dumps(dict(LAB, quantise="bit-stealing")))
    shown = shadelab.render(
        "sphere", shape=(40, 60), ppd=20, light="tilt=30,slant=40", display=str(lab), luminance=(5, 90)
    )
    for name, extra in [
        ("s.png", {}),
        ("e.png", {"bit_depth": 8, "gamma": 2.2}),
        ("f.npy", {"range": "psychopy"}),
        ("d.png", {"display": None}),
    ]:
        if "display" in extra:
            # The display and luminance that render was given, taken from the dict.
            written = shadelab.save(shown, tmp_path / "py" / name)
        else:
            written = shadelab.save(s, tmp_path / "py" / name, **extra)
        flags = []
        if "bit_depth" in extra:
            flags += ["--bit-depth", "8", "--gamma", "2.2"]
        if "range" in extra:
            flags += ["--range", "psychopy"]
        if "display" in extra:
            flags += ["--display", str(lab), "--luminance", "5,90"]
        subprocess.run(
            [cli, "--quiet", "render", "sphere", "--size", "60x40", "--ppd", "20",
             "--light", "tilt=30,slant=40", *flags, "--out", str(tmp_path / "cli" / name)],
            check=True,
        )
        assert sorted(os.listdir(tmp_path / "cli")) == sorted(os.listdir(tmp_path / "py"))
        for path in written:
            p = pathlib.Path(path)
            assert p.read_bytes() == (tmp_path / "cli" / p.name).read_bytes(), p.name


LAB = {"name": "lab", "gamma": 2.2, "black_cd_m2": 0.5, "white_cd_m2": 120}


def test_render_for_a_display_gives_codes_and_candelas():
    s = shadelab.render("bumps", shape=(60, 80), display=LAB, luminance={"background": 40, "michelson": 0.5})
    codes, cd = s["codes"], s["luminance_cd_m2"]
    assert codes.shape == (60, 80) and codes.dtype == np.uint16 and codes.max() <= 255
    # The model, evaluated here: each code's luminance is what luminance_cd_m2 says, and it is
    # within half a step of what was asked (0.5 -> 40 cd/m², contrast 0.5: 20..60 cd/m²).
    model = lambda c: 0.5 + 119.5 * (c / 255.0) ** 2.2  # noqa: E731
    assert np.allclose(cd, model(codes.astype(float)), rtol=0, atol=1e-9)
    wanted = 40 * (1 + 0.5 * (2 * s["img"] - 1))
    step = model(codes + 1.0) - model(codes - 1.0)
    assert (np.abs(cd - wanted) <= 0.5 * step + 1e-9).all()
    assert s["img"].min() >= 0 and s["img"].max() <= 1, "img stays the linear stimulus"
    targets = {t["name"]: t for t in s["display"]["targets"]}
    for label, name in enumerate(s["target_names"], start=1):
        mean = float(cd[s["target_mask"] == label].mean())
        assert abs(targets[name]["luminance_cd_m2"] - mean) < 1e-9
        assert abs(targets[name]["weber_vs_background"] - (mean - 40) / 40) < 1e-12
    assert s["display"]["luminance"]["black_cd_m2"] == pytest.approx(20.0)


def test_render_range_bit_depth_and_gamma_as_the_command_line():
    s = shadelab.render("sphere", shape=(20, 30), light="above", range="psychopy", bit_depth=8, gamma=2.2)
    linear = shadelab.render("sphere", shape=(20, 30), light="above")["img"]
    assert np.array_equal(s["img"], linear * 2 - 1)
    assert np.array_equal(s["codes"], np.round(linear ** (1 / 2.2) * 255).astype(np.uint16))
    assert s["export"] == {"bit_depth": 8, "gamma": 2.2, "range": "psychopy", "display": None, "luminance": None}


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        ({"display": LAB, "luminance": (1, 500)}, ValueError, "outside what the display 'lab' shows"),
        ({"display": LAB, "gamma": 2.0}, ValueError, "without gamma, bit_depth or range"),
        ({"luminance": (1, 50)}, ValueError, "needs a display"),
        ({"display": dict(LAB, gama=1)}, ValueError, "unknown key 'gama'"),
        ({"display": dict(LAB, quantise="bit-stealing", bit_depth=10)}, ValueError, "8-bit"),
        ({"display": 3}, ValueError, "display file's path or a dict"),
        ({"display": "no-such-display.json"}, FileNotFoundError, "no-such-display.json"),
        ({"display": LAB, "luminance": {"background": 40}}, ValueError, "'background' and 'michelson'"),
        ({"display": LAB, "luminance": {"background": 40, "michelson": 2}}, ValueError, "Michelson"),
        ({"gamma": 0.0}, ValueError, "gamma 0"),
        ({"bit_depth": 10}, ValueError, "bit_depth 10"),
    ],
)
def test_render_refuses_display_options_it_cannot_honour(kwargs, error, match):
    with pytest.raises(error, match=match):
        shadelab.render("sphere", shape=(16, 16), **kwargs)


def test_save_refuses_bad_options_and_keeps_a_foreign_file(tmp_path):
    s = shadelab.render("checkerboard", shape=(16, 24), ppd=8)
    with pytest.raises(ValueError, match="bit_depth 12"):
        shadelab.save(s, tmp_path / "c.png", bit_depth=12)
    with pytest.raises(ValueError, match="range 'half'"):
        shadelab.save(s, tmp_path / "c.png", range="half")
    with pytest.raises(ValueError, match="psychopy"):
        shadelab.save(s, tmp_path / "c.png", range="psychopy")
    with pytest.raises(ValueError, match="render returned"):
        shadelab.save({"img": s["img"]}, tmp_path / "c.png")
    mine = tmp_path / "c.png"
    mine.write_bytes(b"the user's own file")
    with pytest.raises((ValueError, OSError)):
        shadelab.save(s, mine)
    assert mine.read_bytes() == b"the user's own file"
    assert sorted(os.listdir(tmp_path)) == ["c.png"]


def test_sizes_in_messages_name_their_axes():
    # (height, width) = (14, 10): 10° wide, too narrow for the 11° the 3 × 4 discs need.
    with pytest.raises(ValueError, match=r"bumps: 3 rows × 4 columns of discs need 8\.0° high × "
                                         r"11\.0° wide but the frame is 14\.0° high × 10\.0° wide"):
        shadelab.render("bumps", visual_size=(14, 10))
    with pytest.raises(ValueError, match=r"1 px high × 100000 px wide .* 800000\.0° wide: over 180°"):
        shadelab.render("checkerboard", shape=(1, 100000))


@pytest.mark.parametrize("visual_size,ppd,check", [
    ((4, 6), 10, 0.75), ((4, 6), 31.7, 0.8), ((3.3, 5.1), 10, 1.0), ((7, 13), 23, 0.33),
    ((4, 6), 10, 1.0), ((2.5, 9), 37.3, 1.3),
])
def test_checkerboard_rounds_its_check_as_stimupy_does(visual_size, ppd, check):
    # stimupy 1.2 rounds the check to whole pixels (0.75° at 10 ppd: 8 px, 0.8°) and warns;
    # its square waves move an edge by a pixel on some frames (33 rows at 10 ppd, 1° checks).
    import warnings

    kw = dict(visual_size=visual_size, ppd=ppd, check_visual_size=check,
              intensity_checks=(0.2, 0.9), target_indices=((1, 2), (0, 0)), intensity_target=0.5)
    with warnings.catch_warnings(record=True) as ours_said:
        warnings.simplefilter("always")
        ours = shadelab.render("checkerboard", **kw)
    rounded = [str(w.message) for w in ours_said if "rounded to whole pixels as stimupy" in str(w.message)]
    px = int(np.round(check * ppd))
    assert len(rounded) == (0 if abs(px / ppd - check) < 1e-9 else 1), rounded
    _stimupy()
    from stimupy.stimuli.checkerboards import checkerboard

    with warnings.catch_warnings(record=True) as theirs_said:
        warnings.simplefilter("always")
        theirs = checkerboard(**kw)
    assert bool(rounded) == any("phase_width" in str(w.message) for w in theirs_said)
    np.testing.assert_array_equal(ours["img"], theirs["img"])
    np.testing.assert_array_equal(ours["target_mask"], theirs["target_mask"])

def read_gray_png(path):
    """The codes of a gray, non-interlaced 8- or 16-bit PNG (shadelab's stimulus PNGs) and the
    largest code, decoded here (no imaging library needed)."""
    data = pathlib.Path(path).read_bytes()
    pos, idat, head = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            head = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = head
    assert colour == 0 and interlace == 0 and depth in (8, 16)
    bpp = depth // 8
    raw, stride = zlib.decompress(idat), width * bpp
    rows, prev = [], bytearray(stride)
    for r in range(height):
        kind, line = raw[r * (stride + 1)], bytearray(raw[r * (stride + 1) + 1 : (r + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    codes = np.frombuffer(b"".join(rows), dtype=">u2" if depth == 16 else np.uint8)
    return codes.reshape(height, width).astype(np.float64), float(2**depth - 1)


def test_save_writes_the_array_it_is_given(tmp_path):
    # An edited img is what is written: .npy exactly (float32 of it), a PNG within half its
    # quantisation step; the sidecar carries the picture's own digest and says it was edited.
    s = shadelab.render("bumps", ppd=8)
    shadelab.save(s, tmp_path / "unedited.npy")
    unedited = json.loads((tmp_path / "unedited.json").read_text())
    assert "edited" not in unedited
    s["img"] = s["img"] * 0.5 + 0.25
    shadelab.save(s, tmp_path / "edited.npy")
    assert np.array_equal(np.load(tmp_path / "edited.npy"), s["img"].astype(np.float32))
    shadelab.save(s, tmp_path / "e16.png")
    shadelab.save(s, tmp_path / "e8.png", bit_depth=8)
    for name in ("e16.png", "e8.png"):
        codes, top = read_gray_png(tmp_path / name)
        assert np.abs(codes / top - s["img"]).max() <= 0.5 / top + 1e-12, name
    for name in ("edited", "e16", "e8"):
        record = json.loads((tmp_path / f"{name}.json").read_text())
        assert record["md5_float64_rounded8"] != unedited["md5_float64_rounded8"]
        assert record["edited"]["rendered_md5_float64_rounded8"] == unedited["md5_float64_rounded8"]
    # In the range render handed it over: PsychoPy's -1..1 is read back as such.
    p = shadelab.render("bumps", ppd=8, range="psychopy")
    p["img"] = p["img"] * 0.5
    shadelab.save(p, tmp_path / "p.npy")
    assert np.abs(np.load(tmp_path / "p.npy") - p["img"]).max() <= 6e-8
    # What no picture can be is refused, naming img, and nothing is written.
    for bad, match in [
        (s["img"] * 4, "img: .*outside 0..1"),
        (s["img"][:20], r"img: the picture is 20 high × (\d+) wide but the render it records is \d+ high × \1 wide"),
        (np.full(s["img"].shape, np.nan), "img: .*non-finite"),
    ]:
        with pytest.raises(ValueError, match=match):
            shadelab.save(dict(s, img=bad), tmp_path / "bad.npy")
    assert not (tmp_path / "bad.npy").exists()
    # render --spec of the edited sidecar refuses to claim it reproduces the picture.
    cli = os.environ.get("SHADELAB_BIN")
    if cli:
        out = subprocess.run(
            [cli, "render", "--spec", str(tmp_path / "edited.json"), "--out", str(tmp_path / "again.npy")],
            capture_output=True, text=True,
        )
        assert out.returncode == 1 and "edited after rendering" in out.stderr
        assert len(out.stderr.strip().splitlines()) == 1
        assert not (tmp_path / "again.npy").exists()


def test_save_writes_the_target_mask_it_is_given(tmp_path):
    # An edited target_mask is the mask written (its labels read back from the mask PNG) and
    # the targets its sidecar lists; `edited` says so. The render's own mask changes nothing.
    s = shadelab.render("bumps", ppd=8)
    shadelab.save(s, tmp_path / "same.npy")
    same = json.loads((tmp_path / "same.json").read_text())
    assert "edited" not in same
    mask = s["target_mask"].copy()
    mask[mask == 2] = 0
    mask[:2, :2] = 2
    shadelab.save(dict(s, target_mask=mask), tmp_path / "m.npy")
    codes, _ = read_gray_png(tmp_path / "m_mask.png")
    assert np.array_equal(codes, mask)
    record = json.loads((tmp_path / "m.json").read_text())
    assert "target_mask" in record["edited"] and "rendered_md5_float64_rounded8" not in record["edited"]
    assert record["md5_float64_rounded8"] == same["md5_float64_rounded8"]
    assert [t["name"] for t in record["targets"]] == s["target_names"]
    # Renamed targets are an edit too; a label without a name is refused, naming the mask.
    names = ["t%d" % (i + 1) for i in range(len(s["target_names"]))]
    shadelab.save(dict(s, target_names=names), tmp_path / "n.npy")
    assert [t["name"] for t in json.loads((tmp_path / "n.json").read_text())["targets"]] == names
    with pytest.raises(ValueError, match=r"target_mask: label \d+ has no name \(2 target names given\)"):
        shadelab.save(dict(s, target_names=names[:2]), tmp_path / "bad.npy")
    assert not (tmp_path / "bad.npy").exists()


def test_two_saves_of_one_name_never_share_a_sidecar_or_mask(tmp_path):
    # exp1.npy then exp1.png would both be recorded in exp1.json: the second is refused,
    # naming the first, whose set stays as it was (and so with the command line's --out).
    bumps = shadelab.render("bumps", shape=(40, 60))
    crater = shadelab.render("crater", shape=(40, 60))
    shadelab.save(bumps, tmp_path / "exp1.npy")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    for force in (False, True):
        with pytest.raises(ValueError, match="exp1.json beside it is the record of exp1.npy, another picture"):
            shadelab.save(crater, tmp_path / "exp1.png", force=force)
        assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    # Another name is its own set; the lookup X.png -> X.json finds each picture's record.
    shadelab.save(crater, tmp_path / "exp1-crater.png")
    assert json.loads((tmp_path / "exp1.json").read_text())["stimulus"] == "bumps"
    assert json.loads((tmp_path / "exp1-crater.json").read_text())["stimulus"] == "crater"


def test_numbers_are_accepted_where_a_number_is_meant():
    # crater's rotation is a choice of "0" and "180": a number names it as well as its text.
    by_text = shadelab.render("crater", shape=(32, 32), rotation="180")
    for given in (180, 180.0, np.int64(180)):
        s = shadelab.render("crater", shape=(32, 32), rotation=given)
        assert s["rotation"] == "180"
        assert np.array_equal(s["img"], by_text["img"])
    assert not np.array_equal(shadelab.render("crater", shape=(32, 32), rotation=0)["img"], by_text["img"])
    with pytest.raises(ValueError, match="parameter rotation: '90' is not one of 0, 180"):
        shadelab.render("crater", shape=(32, 32), rotation=90)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: shadelab.render("crater", rotaton=180), "unknown parameter 'rotaton'; did you mean 'rotation'\\?"),
        (lambda: shadelab.render("bumps", visual_sise=4), "did you mean the keyword 'visual_size'\\?"),
        (lambda: shadelab.observer("bumps", shape=(32, 48), prior_kappa=2), "unknown parameter 'prior_kappa'; did you mean the keyword 'kappas'\\?"),
        (lambda: shadelab.prior_sweep("bumps", tilt=[0]), "did you mean the keyword 'tilts'\\?"),
        (lambda: shadelab.lightness("checker-shadow", modl="odog"), "did you mean the keyword 'model'\\?"),
        (lambda: shadelab.render("bumps", teapot=1), "unknown parameter 'teapot' \\(valid: "),
    ],
)
def test_an_unknown_keyword_names_the_nearest_valid_one(call, match):
    with pytest.raises(ValueError, match=match):
        call()
