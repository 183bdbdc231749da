"""What a release promises a notebook user: the package's version is the wheel's, a stimulus
and every analysis's result show their pictures in Jupyter (the PNG files ``save`` writes,
byte for byte), and the tutorial notebook runs top to bottom."""

import base64
import importlib.metadata
import pathlib
import struct
import tempfile

import numpy as np
import pytest

import shadelab

NOTEBOOK = pathlib.Path(__file__).resolve().parents[1] / "examples" / "tutorial.ipynb"


def chunks(png):
    """The PNG's chunks as (type, data), checking its signature."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n", png[:8]
    at, out = 8, []
    while at < len(png):
        (length,) = struct.unpack(">I", png[at : at + 4])
        kind = png[at + 4 : at + 8].decode("ascii")
        out.append((kind, png[at + 8 : at + 8 + length]))
        at += 12 + length
    return out


def header(png):
    """(height, width, bit depth, colour type) from the PNG's IHDR."""
    kind, data = chunks(png)[0]
    assert kind == "IHDR"
    width, height, depth, colour = struct.unpack(">IIBB", data[:10])
    return height, width, depth, colour


def test_the_version_is_the_wheels():
    assert shadelab.__version__ == importlib.metadata.version("shadelab")


def test_a_stimulus_shows_the_png_save_writes():
    s = shadelab.render("bumps", shape=(96, 144), ppd=12)
    assert isinstance(s, dict) and isinstance(s, shadelab.Stimulus)
    png = s._repr_png_()
    # 8 bits, display-encoded with gamma 2.2 (gAMA 1/2.2 = 45455), the stimulus's size.
    assert header(png) == (96, 144, 8, 0)
    gama = dict(chunks(png))["gAMA"]
    assert struct.unpack(">I", gama)[0] == 45455
    with tempfile.TemporaryDirectory() as d:
        path = pathlib.Path(d) / "b.png"
        shadelab.save(s, path, bit_depth=8, gamma=2.2)
        assert png == path.read_bytes()
    page = s._repr_html_()
    assert base64.b64encode(png).decode("ascii") in page
    assert "bumps: 96 × 144 px (height × width), 8 × 12 deg, ppd 12" in page


def test_a_dict_render_did_not_make_keeps_its_text_repr():
    s = shadelab.Stimulus(img=np.zeros((4, 4)))
    assert s._repr_png_() is None and s._repr_html_() is None
    assert repr(s).startswith("{'img'")


def shown(result):
    """The names of the pictures a result shows, checking each is a PNG in the HTML."""
    page = result._repr_html_()
    pictures = result._notebook_pictures()
    assert pictures, type(result).__name__
    for name, png in pictures:
        assert base64.b64encode(png).decode("ascii") in page
        assert f'alt="{name}"' in page
    assert result._repr_png_() == pictures[0][1]
    return [name for name, _ in pictures]


def test_a_solve_shows_its_depth_and_normals_as_save_writes_them(sphere):
    r = shadelab.solve(sphere["img"], light=(0.3, 0.4, 0.866), mask=sphere["target_mask"])
    assert shown(r) == ["depth", "normals", "convergence"]
    with tempfile.TemporaryDirectory() as d:
        r.save(pathlib.Path(d) / "out")
        for name, png in r._notebook_pictures():
            assert png == (pathlib.Path(d) / "out" / f"{name}.png").read_bytes(), name


def test_each_analysis_shows_its_figure():
    bumps = shadelab.render("bumps", shape=(72, 96), ppd=8)
    assert shown(shadelab.prior_sweep(bumps, tilts=[0, 90, 180, 270])) == ["sweep"]
    assert shown(shadelab.observer(bumps, rotations=[0, 180])) == ["p_convex"]
    assert shown(shadelab.lightness("checker-shadow", ppd=8, model="odog")) == [
        "lightness_figure"
    ]


def test_the_tutorial_notebook_is_committed_without_outputs():
    nbformat = pytest.importorskip("nbformat", reason="nbformat is not installed")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [] and cell.execution_count is None, cell.source[:60]


def test_the_tutorial_notebook_runs_top_to_bottom(tmp_path):
    nbformat = pytest.importorskip("nbformat", reason="nbformat is not installed")
    nbclient = pytest.importorskip("nbclient", reason="nbclient is not installed")
    pytest.importorskip("ipykernel", reason="ipykernel is not installed")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = nbclient.NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()
    # Every section's last line shows its picture: the stimulus, the sweep and the model.
    pictures = [
        out
        for cell in nb.cells
        if cell.cell_type == "code"
        for out in cell.outputs
        if "image/png" in out.get("data", {})
    ]
    assert len(pictures) == 3, [c.outputs for c in nb.cells if c.cell_type == "code"]
    for out in pictures:
        assert "<img src=\"data:image/png;base64," in out["data"]["text/html"]
