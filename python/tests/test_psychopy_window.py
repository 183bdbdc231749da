"""shadelab stimuli in a real PsychoPy window (docs/display.md, docs/python.md).

The window runs on Xvfb; the frame is read back from PsychoPy's back buffer. Skips with the
reason when PsychoPy (with pyglet) or Xvfb is missing, unless ``SHADELAB_REQUIRE_PSYCHOPY=1``
(set by ``.ci/run`` once ``.ci/psychopy.sh`` has installed them), where it fails instead.
"""

import os
import shutil
import subprocess

import numpy as np
import pytest

import shadelab

SIDE = 400  # the window, in pixels


def _unavailable(why):
    if os.environ.get("SHADELAB_REQUIRE_PSYCHOPY") == "1":
        pytest.fail(f"PsychoPy window test cannot run, and SHADELAB_REQUIRE_PSYCHOPY=1: {why}")
    pytest.skip(why)


@pytest.fixture(scope="module")
def window():
    """A PsychoPy window (SIDE × SIDE pixels, black) on its own Xvfb display."""
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        _unavailable("no Xvfb on PATH (Debian: apt-get install xvfb)")
    try:
        import psychopy  # noqa: F401  (before a display: only the packages)
        import pyglet  # noqa: F401
    except ImportError as e:
        _unavailable(f"PsychoPy is not installed ({e}); .ci/psychopy.sh installs it")
    # Xvfb picks a free display number and writes it to the pipe.
    read, write = os.pipe()
    server = subprocess.Popen(
        [xvfb, "-displayfd", str(write), "-screen", "0", "640x480x24", "-nolisten", "tcp"],
        pass_fds=(write,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write)
    with os.fdopen(read) as pipe:
        number = pipe.readline().strip()
    if not number:
        server.kill()
        _unavailable("Xvfb did not start")
    previous = os.environ.get("DISPLAY")
    os.environ["DISPLAY"] = f":{number}"
    try:
        from psychopy import logging, visual

        logging.console.setLevel(logging.ERROR)
        win = visual.Window(
            size=(SIDE, SIDE),
            units="pix",
            color=(-1, -1, -1),
            allowGUI=False,
            fullscr=False,
            checkTiming=False,
            winType="pyglet",
        )
        yield visual, win
        win.close()
    finally:
        if previous is None:
            os.environ.pop("DISPLAY", None)
        else:
            os.environ["DISPLAY"] = previous
        server.terminate()
        server.wait(timeout=10)


def _frame(win):
    """The back buffer as an H×W array of red codes, row 0 the top row of the window."""
    frame = np.asarray(win._getFrame(buffer="back"))
    win.clearBuffer()
    return frame[..., 0].astype(int)


def test_the_frame_reads_top_row_first(window):
    # The read-back itself, checked against PsychoPy's own coordinates (y up): a white square
    # drawn above the centre is in the top half of the frame.
    visual, win = window
    visual.Rect(win, width=20, height=20, pos=(0, 150), fillColor=(1, 1, 1), lineWidth=0).draw()
    rows = np.nonzero(_frame(win).max(axis=1) > 128)[0]
    assert rows.size and rows.max() < SIDE // 2, rows


def test_to_psychopy_shows_the_stimulus_upright_with_its_codes(window):
    visual, win = window
    stim = shadelab.render("sphere", shape=(100, 120), light="above")
    img = stim["img"]
    kw = shadelab.to_psychopy(stim)
    visual.ImageStim(win, **kw).draw()
    frame = _frame(win)
    # Centred, one image pixel per screen pixel: rows 150..249, columns 140..259.
    top, left = (SIDE - 100) // 2, (SIDE - 120) // 2
    shown = frame[top : top + 100, left : left + 120]
    outside = np.delete(frame, np.s_[top : top + 100], axis=0)
    assert outside.max() == 0, "nothing drawn outside the stimulus"
    # Light from above: the sphere's upper half is the brighter, on screen as in the array.
    assert img[:50].mean() > 2 * img[50:].mean()
    assert shown[:50].mean() > 2 * shown[50:].mean()
    # Pixel for pixel: PsychoPy maps −1..1 to the 8-bit codes 0..255 (Xvfb has no gamma
    # ramp), so the codes are round(255 · img) to within one step.
    diff = np.abs(shown - np.round(255 * img))
    assert diff.max() <= 1, f"largest difference {diff.max()} codes"


def test_an_rgb_stimulus_is_shown_with_its_codes(window):
    # PsychoPy draws an H×W×3 float array as 0..1, a gray one as −1..1: to_psychopy hands each
    # the range PsychoPy reads, so both show round(255 · img).
    visual, win = window
    stim = shadelab.render("checker-shadow", shape=(100, 120))
    rgb = np.repeat(stim["img"][..., None], 3, axis=2) * np.array([1.0, 0.8, 0.6])
    visual.ImageStim(win, **shadelab.to_psychopy(rgb)).draw()
    frame = np.asarray(win._getFrame(buffer="back")).astype(int)
    win.clearBuffer()
    top, left = (SIDE - 100) // 2, (SIDE - 120) // 2
    shown = frame[top : top + 100, left : left + 120]
    assert np.abs(shown - np.round(255 * rgb)).max() <= 1


def test_an_array_given_as_it_is_is_upside_down(window):
    # The trap to_psychopy avoids (docs/python.md): PsychoPy draws an array's first row at
    # the bottom. Should PsychoPy ever flip arrays itself, this fails and the docs must change.
    visual, win = window
    stim = shadelab.render("sphere", shape=(100, 120), light="above")
    visual.ImageStim(win, image=stim["img"] * 2 - 1, size=(120, 100), units="pix").draw()
    frame = _frame(win)
    top, left = (SIDE - 100) // 2, (SIDE - 120) // 2
    shown = frame[top : top + 100, left : left + 120]
    assert shown[50:].mean() > 2 * shown[:50].mean(), "the lit side lands at the bottom"
    assert np.abs(shown[::-1] - np.round(255 * stim["img"])).max() <= 1


LAB = {"name": "lab", "gamma": 2.2, "black_cd_m2": 0.5, "white_cd_m2": 120}


@pytest.mark.parametrize("quantise", ["plain", "bit-stealing"])
def test_a_displays_codes_reach_the_frame_buffer_code_for_code(window, quantise):
    # A stimulus for a calibrated display (docs/display.md): the codes of its inverse model,
    # in an uncorrected window (Xvfb has no gamma ramp), land in the frame buffer unchanged.
    visual, win = window
    stim = shadelab.render(
        "sphere",
        shape=(100, 120),
        light="above",
        display=dict(LAB, quantise=quantise),
        luminance=(5, 100),
    )
    kw = shadelab.to_psychopy(stim)
    visual.ImageStim(win, **kw).draw()
    frame = np.asarray(win._getFrame(buffer="back")).astype(int)
    win.clearBuffer()
    top, left = (SIDE - 100) // 2, (SIDE - 120) // 2
    shown = frame[top : top + 100, left : left + 120]
    codes = stim["codes"].astype(int)
    if codes.ndim == 2:
        codes = np.repeat(codes[..., None], 3, axis=2)
    assert (shown == codes).all(), f"{int((shown != codes).sum())} codes differ"
    assert shown[:50].mean() > shown[50:].mean(), "upright: lit from above"
    # The same, asked of a plain render: to_psychopy renders it again for the display.
    plain = shadelab.render("sphere", shape=(100, 120), light="above")
    again = shadelab.to_psychopy(plain, display=dict(LAB, quantise=quantise), luminance=(5, 100))
    assert np.array_equal(again["image"], kw["image"])


def test_psychopys_own_inverse_gamma_agrees_with_the_display_codes():
    # PsychoPy's inverse of its eq. 4 model (calibTools.gammaInvFun, which Monitor.linearizeLums
    # calls per gun; its luminance-only path fails for eq. 4 in 2026.2.5, passing b=None) for
    # the luminances asked of the display, against the codes shadelab chose from the monitor
    # file PsychoPy wrote: the nearest code to PsychoPy's continuous one.
    try:
        from psychopy.monitors import calibTools
    except ImportError as e:
        _unavailable(f"PsychoPy is not installed ({e})")
    here = os.path.dirname(os.path.abspath(__file__))
    path = os.path.join(here, "..", "..", "tests", "data", "psychopy-monitor-labcrt.json")
    # The monitor file's method-4 calibration, named: [0.4, 118, 2.2, 0, 0.1, 0].
    lab = {"psychopy_monitor": os.path.abspath(path), "calibration": "2026_11_20 lab"}
    stim = shadelab.render("sphere", shape=(64, 64), light="above", display=lab, luminance=(2, 100))
    assert stim["display"]["psychopy_calibration"]["taken"] == "named"
    lo, hi = 0.4, 118.0
    wanted = (2 + stim["img"] * 98).ravel()
    theirs = calibTools.gammaInvFun((wanted - lo) / (hi - lo), lo, hi, 2.2, b=0.1, eq=4) * 255
    ours = stim["codes"].ravel().astype(float)
    # The nearest code in luminance is within half a code of PsychoPy's continuous code, up to
    # the curvature of the response over one code (below 0.01 code here).
    assert np.abs(ours - theirs).max() <= 0.51, np.abs(ours - theirs).max()
    assert len(np.unique(stim["codes"])) > 100


def test_the_calibration_taken_is_the_one_psychopys_monitor_loads(tmp_path, monkeypatch):
    # PsychoPy writes a monitor file with two calibrations (Monitor.newCalib, setGammaGrid,
    # save), the newer by calibDate first by name; Monitor(name) loads one, and shadelab takes
    # the same from the file (white 150, not the newer calibration's 100 cd/m²).
    try:
        from psychopy import monitors
        from psychopy.monitors import calibTools
    except ImportError as e:
        _unavailable(f"PsychoPy is not installed ({e})")
    monkeypatch.setattr(calibTools, "monitorFolder", str(tmp_path))
    mon = monitors.Monitor("twocal", autoLog=False)
    temporary = mon.currentCalibName
    for name, date, white in [
        ("2026_11_28 09:03", 1767607200.0, 150.0),
        ("2026_11_20 lab", 1795600000.0, 100.0),
    ]:
        mon.newCalib(name)
        mon.setGammaGrid([[0.5, white, 2.2, 0, 0, 0], [0.5, white * 0.2, 2.1, 0, 0, 0],
                          [0.5, white * 0.7, 2.2, 0, 0, 0], [0.5, white * 0.1, 2.3, 0, 0, 0]])
        mon.setLineariseMethod(1)
        mon.setCalibDate(date)
    mon.delCalib(temporary)
    mon.save()
    loaded = monitors.Monitor("twocal", autoLog=False)
    theirs = loaded.currentCalibName, float(loaded.getGammaGrid()[0][1])
    assert theirs == ("2026_11_28 09:03", 150.0), theirs
    stim = shadelab.render("sphere", shape=(16, 16), display=str(tmp_path / "twocal.json"))
    record = stim["display"]
    assert (record["psychopy_calibration"]["name"], record["white_cd_m2"]) == theirs
    assert record["psychopy_calibration"]["calibrations"] == sorted(loaded.calibNames)
    # Named, the other one.
    named = {"psychopy_monitor": str(tmp_path / "twocal.json"), "calibration": "2026_11_20 lab"}
    assert shadelab.render("sphere", shape=(16, 16), display=named)["display"]["white_cd_m2"] == 100.0


@pytest.mark.parametrize(
    "bad, units, match",
    [
        (np.full((4, 4), 1.5), "pix", r"reaches 1\.5"),
        (np.full((4, 4), np.nan), "pix", "NaN"),
        (np.zeros((4, 4, 2)), "pix", "H×W or H×W×3"),
        (np.zeros((0, 4)), "pix", "empty"),
        (np.zeros((4, 4)), "cm", "unknown units 'cm'"),
        (np.zeros((4, 4)), "deg", "needs a render dict"),
        (np.zeros((4, 4), dtype=np.int32), "pix", "int32 pictures are not read"),
    ],
)
def test_to_psychopy_refuses_what_it_cannot_show(bad, units, match):
    with pytest.raises(ValueError, match=match):
        shadelab.to_psychopy(bad, units=units)


def test_to_psychopy_sizes_in_degrees_are_width_then_height():
    stim = shadelab.render("checkerboard", visual_size=(2, 3), ppd=10)
    kw = shadelab.to_psychopy(stim, units="deg")
    assert kw["size"] == (3.0, 2.0) and kw["units"] == "deg"
    assert kw["image"].dtype == np.float32
    assert (kw["image"] == np.flipud(np.float32(stim["img"] * 2 - 1))).all()


def test_to_psychopy_reads_integer_codes_as_the_command_line_does():
    codes = np.array([[0, 255], [51, 102]], dtype=np.uint8)
    kw = shadelab.to_psychopy(codes)
    assert (kw["image"] == np.flipud(np.float32(codes / 255.0 * 2 - 1))).all()
    wide = np.array([[0, 65535]], dtype=np.uint16)
    assert (shadelab.to_psychopy(wide)["image"] == np.float32([[-1.0, 1.0]])).all()


def test_to_psychopy_for_a_display_needs_a_render_dict():
    with pytest.raises(ValueError, match="display= needs a dict"):
        shadelab.to_psychopy(np.zeros((4, 4)), display=LAB)
    with pytest.raises(ValueError, match="luminance= needs display="):
        shadelab.to_psychopy(shadelab.render("sphere", shape=(8, 8)), luminance=(5, 100))
    with pytest.raises(ValueError, match="codes=True needs"):
        shadelab.to_psychopy(shadelab.render("sphere", shape=(8, 8)), codes=True)
