"""The benchmark exporter's per-stimulus sources (which target the data's source expects to
look lighter, and where it was read): checked on the table itself, without stimupy. The
recorded positions are checked against stimupy's own target masks by tests/benchmark.rs."""

import pytest

# The installed package's module (the exporter `shadelab.benchmark` runs); it imports stimupy
# only when it exports.
from shadelab import _benchmark_data as bd


def test_every_stimulus_cites_its_primary_source():
    assert len(bd.SOURCES["RHS2007"]) == 18 and len(bd.SOURCES["murray2020"]) == 12
    for set_name, entries in bd.SOURCES.items():
        for name, entry in entries.items():
            assert entry["lighter"] in (1, 2), name
            source = entry["source"]
            # A CSV field: one line, no comma, no quote.
            assert not any(c in source for c in ',"\n'), source
            if set_name == "RHS2007":
                # Repository, commit, file and the source's own region label.
                assert source.startswith(bd.FLODOG_MODELS + " testpatterns/make_"), source
                assert "region.hi=" in source, source
            else:
                assert source.startswith(bd.MURRAY_2020) and "Fig. 1" in source, source


def test_murrays_green_dot_cells_become_positions_in_degrees():
    # Figure 1a's green dot lies on cell (5, 9) of the 16 x 16 grid: 0.5 degree cells at
    # stimupy's 16 ppd, so 1.25 degrees left of and 0.75 below the picture's centre.
    lighter, darker, source, at, none = bd.direction("murray2020", "argyle", (128, 128), 16)
    assert (lighter, darker, none) == (2, 1, None)
    assert at == pytest.approx((-1.25, -0.75))
    # The long-range argyle is 24 cells wide.
    assert bd.direction("murray2020", "argyle_long", (128, 192), 16)[3] == pytest.approx(
        (-2.25, -0.75)
    )
    # The same cell at another resolution is the same place.
    assert bd.direction("murray2020", "argyle", (32, 32), 4)[3] == pytest.approx((-1.25, -0.75))


def test_the_controls_murray_calls_ineffective_have_no_direction():
    for name in ("argyle_control", "koffka_connected"):
        assert "control figure" in bd.direction("murray2020", name, (128, 128), 16)[4]
    assert bd.direction("murray2020", "snake_control", (128, 128), 16)[4] is None


def test_rhs2007_targets_come_from_the_authors_region_hi():
    lighter, darker, source, at, none = bd.direction("RHS2007", "checkerboard_094", (1024, 1024), 32)
    assert (lighter, darker, none) == (1, 2, None)
    assert source.endswith("testpatterns/make_check_30.m region.hi=2")
    assert bd.direction("RHS2007", "WE_anderson", (1024, 1024), 32)[0] == 2


def test_a_stimulus_without_a_source_is_an_error():
    with pytest.raises(ValueError, match="no source"):
        bd.direction("RHS2007", "WE_dual", (1024, 1024), 32)
