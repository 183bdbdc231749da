"""shadelab.benchmark: the lightness models scored against stimupy's human data, with the
same numbers as the command line's ``benchmark --json`` (needs stimupy; skips without it)."""

import json
import os
import subprocess
import sys

import pytest

import shadelab

stimupy = pytest.importorskip("stimupy")

SUBSET = ["murray2020/white", "simcon", "snake"]
RUN_FIELDS = {"seconds", "command"}


def test_the_benchmark_scores_stimupys_stimuli_and_matches_the_command_line(tmp_path):
    result = shadelab.benchmark(models="odog,highpass", stimuli=SUBSET, out=tmp_path / "py")
    assert result["stimupy_version"] == stimupy.__version__
    assert [r["stimulus"] for r in result.rows[::2]] == ["snake", "simcon", "white"]
    odog = [r for r in result.rows if r["model"] == "odog"]
    # ODOG predicts the direction people see on White's effect, simultaneous contrast and
    # the snake.
    assert all(r["verdict"] == "agrees" for r in odog), odog
    assert {(s["set"], s["model"]) for s in result.scores} == {
        ("murray2020", "odog"),
        ("murray2020", "highpass"),
    }
    # Which target looks lighter, per stimulus, from Murray (2020): the leftmost, stimupy's
    # target 2, the green dot of the paper's Figure 1.
    directions = {d["stimulus"]: d for d in result.directions}
    assert directions["simcon"]["expected_lighter"] == 2
    assert directions["simcon"]["human_lighter_target"] == 2
    assert "Fig. 1k" in directions["simcon"]["direction_source"]
    assert "| odog |" in result.table
    assert (tmp_path / "py" / "benchmark.csv").is_file()

    cli = os.environ.get("SHADELAB_BIN")
    if not cli:
        pytest.skip("SHADELAB_BIN is not set: no command line to compare with")
    out = subprocess.run(
        [cli, "--json", "--quiet", "benchmark", "--python", sys.executable,
         "--models", "odog,highpass", "--stimuli", ",".join(SUBSET)],
        capture_output=True, text=True,
    )
    assert out.returncode == 0, out.stderr
    report = json.loads(out.stdout)
    strip = lambda d: {k: v for k, v in d.items() if k not in RUN_FIELDS}
    assert strip(report) == strip(result.to_dict())
    csv = (tmp_path / "py" / "benchmark.csv").read_text()
    assert csv.splitlines()[0] == (
        "set,stimulus,model,human,human_ci95,human_direction,"
        "human_lighter_target,direction_source,effect,verdict"
    )


def test_an_unknown_stimulus_is_a_value_error():
    with pytest.raises(ValueError, match="nope"):
        shadelab.benchmark(stimuli=["nope"])
