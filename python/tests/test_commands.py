"""Every command of the command line has its Python twin, and the two give the same numbers
and write the same files (the command line's binary is SHADELAB_BIN, set by tests/python.rs)."""

import csv
import io
import json
import os
import pathlib
import re
import struct
import subprocess

import numpy as np
import pytest

import shadelab

# The data folder of the evaluation (../shared/data beside the repository), when present.
DATA = pathlib.Path(__file__).resolve().parents[2].parent / "shared" / "data"

# Fields that say when or how a run happened rather than what it found.
RUN_FIELDS = {"seconds", "command", "commit", "input"}


def cli_binary():
    cli = os.environ.get("SHADELAB_BIN")
    if not cli:
        pytest.skip("SHADELAB_BIN is not set (cargo test sets it to the shadelab binary)")
    return cli


def run_cli(*args):
    """The command line's --json report of `args`."""
    out = subprocess.run(
        [cli_binary(), "--json", "--quiet", *map(str, args)],
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def commands_of(cli, *path):
    """The subcommands `shadelab PATH --help` lists (without `help`)."""
    text = subprocess.run([cli, *path, "--help"], capture_output=True, text=True).stdout
    block = text.split("Commands:")[1].split("Options:")[0]
    names = [m.group(1) for m in re.finditer(r"^  (\S+)", block, re.M)]
    return [n for n in names if n != "help"]


def without_run_fields(value):
    if isinstance(value, dict):
        return {k: without_run_fields(v) for k, v in value.items() if k not in RUN_FIELDS}
    if isinstance(value, list):
        return [without_run_fields(v) for v in value]
    return value


def test_every_command_has_its_python_twin():
    # The command tree read from the program itself: a command added to the command line
    # without a Python function (or the other way round) fails here.
    cli = cli_binary()
    found = []
    for command in commands_of(cli):
        text = subprocess.run([cli, command, "--help"], capture_output=True, text=True).stdout
        if "Commands:" in text:
            found += [f"{command} {sub}" for sub in commands_of(cli, command)]
        # A command that runs by itself as well (`experiment --out DIR` beside `experiment
        # pilot`) has a usage line of its own without a subcommand.
        usages = [l for l in text.split("Commands:")[0].splitlines() if f"shadelab {command}" in l]
        if "Commands:" not in text or any("<COMMAND>" not in l for l in usages):
            found.append(command)
    assert sorted(found) == sorted(shadelab.COMMANDS), sorted(set(found) ^ set(shadelab.COMMANDS))
    for command, function in shadelab.COMMANDS.items():
        assert callable(function) and function.__doc__, command
        assert function.__name__ in shadelab.__all__, command


def folder_files(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*") if p.is_file())


def assert_same_folder(py_dir, cli_dir):
    """The same files; byte for byte except the JSON reports' run fields (time, command)."""
    assert folder_files(py_dir) == folder_files(cli_dir)
    for name in folder_files(py_dir):
        a, b = (py_dir / name).read_bytes(), (cli_dir / name).read_bytes()
        if name.endswith(".json"):
            assert without_run_fields(json.loads(a)) == without_run_fields(json.loads(b)), name
        else:
            assert a == b, name


def png_size(path):
    """(height, width, channels) from a PNG's header."""
    head = path.read_bytes()[:26]
    width, height, depth, colour = struct.unpack(">IIBB", head[16:26])
    return height, width, {2: 3, 6: 4}.get(colour), depth


def assert_figures_are_the_pngs(result, folder):
    # figures() decodes exactly the 8-bit colour PNGs save() writes.
    figures = result.figures()
    pngs = {}
    for p in folder.rglob("*.png"):
        h, w, c, depth = png_size(p)
        if c and depth == 8:
            pngs[str(p.relative_to(folder).with_suffix(""))] = (h, w, c)
    assert pngs, "the folder has figures"
    assert {k: v.shape for k, v in figures.items()} == pngs
    for v in figures.values():
        assert v.dtype == np.uint8 and v.max() > v.min()


def test_fading_matches_the_command_line(tmp_path):
    r = shadelab.fading(ppd=16, duration=2.0, jitter_seed=3)
    cli = run_cli("analyze", "fading", "--stimulus", "fading-disk", "--ppd", 16, "--duration", 2,
                  "--jitter-seed", 3, "--out", tmp_path / "cli")
    assert without_run_fields(r.report) == without_run_fields(cli)
    # The arrays are the time course of the CSV the command line writes.
    rows = np.loadtxt(tmp_path / "cli" / "time_course.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(rows[:, 0], r.times)
    np.testing.assert_array_equal(rows[:, 1], r.blurred)
    np.testing.assert_array_equal(rows[:, 3:], r["eye"])
    assert r.frames.shape[0] == cli["animation"]["frames"] and r.frames.shape[3] == 3
    # The blurred disk fades, the sharp one holds.
    assert r.blurred[-1] < 0.5 * r.blurred[0] and r.sharp[-1] > r.blurred[-1]
    assert_same_folder(pathlib.Path(r.save(tmp_path / "py")), tmp_path / "cli")
    assert_figures_are_the_pngs(r, tmp_path / "py")


def test_outline_matches_the_command_line(tmp_path):
    r = shadelab.outline("boundary-strips", ppd=12)
    cli = run_cli("analyze", "outline", "--stimulus", "boundary-strips", "--ppd", 12,
                  "--out", tmp_path / "cli")
    assert without_run_fields(r.report) == without_run_fields(cli)
    names = [t["name"] for t in r.targets]
    assert sorted(r.layers) == sorted(names) and len(names) == 4
    for t in r.targets:
        layers = r.layers[t["name"]]
        assert layers["shape"].shape == layers["inside"].shape == layers["paint"].shape
        assert layers["inside"].dtype == np.bool_ and layers["inside"].any()
    assert_same_folder(pathlib.Path(r.save(tmp_path / "py")), tmp_path / "cli")
    assert_figures_are_the_pngs(r, tmp_path / "py")


def test_the_perception_analyses_match_the_command_line(tmp_path):
    p = shadelab.prior_sweep("bumps", shape=(64, 96), ppd=8, tilts=np.arange(0, 360, 30))
    cli = run_cli("analyze", "prior-sweep", "--stimulus", "bumps", "--size", "96x64", "--ppd", 8,
                  "--tilts", "0:360:30", "--out", tmp_path / "cli")
    assert without_run_fields(p.report) == without_run_fields(cli)
    assert p.convexities.shape == (len(p.tokens), 12)
    assert_same_folder(pathlib.Path(p.save(tmp_path / "py")), tmp_path / "cli")
    assert_figures_are_the_pngs(p, tmp_path / "py")
    o = shadelab.observer("bumps", shape=(64, 96), ppd=8)
    cli = run_cli("analyze", "observer", "--stimulus", "bumps", "--size", "96x64", "--ppd", 8,
                  "--out", tmp_path / "cli-observer")
    assert without_run_fields(o.to_dict()) == without_run_fields(cli)
    assert_same_folder(pathlib.Path(o.save(tmp_path / "py-observer")), tmp_path / "cli-observer")


def test_lightness_matches_the_command_line(tmp_path):
    r = shadelab.lightness("checker-shadow", ppd=16, model="odog")
    cli = run_cli("analyze", "lightness", "--stimulus", "checker-shadow", "--ppd", 16,
                  "--model", "odog", "--out", tmp_path / "cli")
    assert without_run_fields(r.report) == without_run_fields(cli)
    written = np.load(tmp_path / "cli" / "lightness.npy")
    np.testing.assert_array_equal(written, r.output.astype(written.dtype))
    assert [t["name"] for t in r.targets] == ["A", "B"]
    assert_same_folder(pathlib.Path(r.save(tmp_path / "py")), tmp_path / "cli")


SPEC = {
    "stimuli": [
        {"stimulus": "bumps", "params": {"rows": 1, "columns": 1, "pattern": ["bumps", "dimples"]},
         "shape": [32, 32], "ppd": 16, "seed": 0}
    ],
    "tilts": "0:360:30",
    "slants": [45],
    "priors": {"tilt": [26], "kappa": [1, 4], "convexity_bias": [0]},
    "rotations": "0:360:90",
    "noise": 0.05,
    "boundary": "flat",
    "domain": "image",
}


def test_study_run_and_merge_match_the_command_line(tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps(SPEC))
    whole = shadelab.study_run(SPEC)
    run_cli("study", "run", spec, "--out", tmp_path / "cli")
    assert (tmp_path / "cli" / "results.csv").read_text() == whole.results_csv
    assert (tmp_path / "cli" / "sweep.csv").read_text() == whole.sweep_csv
    # The columns are the CSV's, numbers as numbers.
    assert len(whole.results["p_convex"]) == len(whole.results_csv.splitlines()) - 1
    assert np.all((whole.results["p_convex"] >= 0) & (whole.results["p_convex"] <= 1))
    # Shards saved by Python, merged by Python and by the command line: the unsharded run.
    shards = [shadelab.study_run(spec, shard=f"{i}/2").save(tmp_path / f"s{i}") for i in range(2)]
    merged = shadelab.study_merge(shards, tmp_path / "merged")
    run_cli("study", "merge", *shards, "--out", tmp_path / "cli-merged")
    assert merged.results_csv == whole.results_csv and merged.sweep_csv == whole.sweep_csv
    assert merged.folder == str(tmp_path / "merged")
    assert (tmp_path / "cli-merged" / "results.csv").read_text() == whole.results_csv
    with pytest.raises(ValueError, match="shard"):
        shadelab.study_run(SPEC, shard="2/2")
    with pytest.raises(ValueError, match="no stimuli"):
        shadelab.study_run(dict(SPEC, stimuli=[]))
    with pytest.raises(FileNotFoundError):
        shadelab.study_run(tmp_path / "missing.json")


def test_evaluate_matches_the_command_line(tmp_path):
    if not (DATA / "bunny").is_dir():
        pytest.skip(f"the evaluation data are not at {DATA} (a fresh clone without ../shared)")
    r = shadelab.evaluate(DATA, only="bunny", bunny_size=64, methods="multigrid", out=tmp_path / "py")
    cli = run_cli("eval", "--data", DATA, "--only", "bunny", "--bunny-size", 64,
                  "--method", "multigrid", "--out", tmp_path / "cli")
    assert without_run_fields(r.cases) == without_run_fields(cli)
    errors = r.mean_errors_deg()
    assert len(errors) == len(cli) and np.all((errors > 1) & (errors < 60))
    assert r.folder == str(tmp_path / "py")
    assert folder_files(tmp_path / "py") == folder_files(tmp_path / "cli")
    for name in folder_files(tmp_path / "py"):
        if name.endswith(".png"):
            assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()


def test_gallery_matches_the_command_line(tmp_path):
    g = shadelab.gallery(tmp_path / "py")
    cli = run_cli("gallery", "--out", tmp_path / "cli")
    assert len(g.presets) == len(cli["presets"]) > 10
    assert [p["name"] for p in g.presets] == [p["name"] for p in cli["presets"]]
    for p in g.presets:
        for f in p["files"]:
            if f.endswith((".png", ".npy")):
                assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f


def test_bench_runs_the_command_lines_benchmark():
    b = shadelab.bench(sizes=[32, 64], repeat=1, reference="/nonexistent")
    cli = run_cli("bench", "--sizes", "32,64", "--repeat", 1, "--reference", "/nonexistent")
    # Timings differ run to run; the work does not.
    assert [r["size"] for r in b.rows] == [32, 64]
    for mine, theirs in zip(b.rows, cli["rows"]):
        assert mine["multigrid"]["iterations"] == theirs["multigrid"]["iterations"]
        assert mine["multigrid"]["converged"] and theirs["multigrid"]["converged"]
        assert mine["jacobi_difference_deg"] == theirs["jacobi_difference_deg"]
    assert "multigrid" in b.table
    with pytest.raises(ValueError, match="at least 8"):
        shadelab.bench(sizes=[4])


def test_solve_saves_what_the_command_line_writes(tmp_path):
    # The same picture for both: the float32 .npy the command line reads, and its mask.
    s = shadelab.render("sphere", shape=64, ppd=16, light="tilt=30,slant=40")
    shadelab.save(s, tmp_path / "sphere.npy")
    img = np.load(tmp_path / "sphere.npy")
    r = shadelab.solve(img, light="tilt=30,slant=40", mask=s["target_mask"])
    run_cli("solve", tmp_path / "sphere.npy", "--light", "tilt=30,slant=40", "--out", tmp_path / "cli")
    folder = pathlib.Path(r.save(tmp_path / "py"))
    assert folder_files(folder) == folder_files(tmp_path / "cli")
    # The numbers the folder holds are the arrays Python has.
    np.testing.assert_array_equal(np.load(folder / "depth.npy"), r.depth.astype(np.float32))
    for name in folder_files(folder):
        if name.endswith(".npy") or name.endswith(".png"):
            assert (folder / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert_figures_are_the_pngs(r, folder)
    assert set(r.to_dict()) >= {"normals", "depth", "f", "g", "solver"}


def test_a_result_is_typed_and_a_dict_too():
    r = shadelab.prior_sweep("bumps", shape=(64, 96), ppd=8, tilts=[0, 180])
    d = r.to_dict()
    assert d["tilts"] is r.tilts and d["tokens"] == r.tokens == r["tokens"]
    assert set(d) == set(r.report) | {"tilts", "convexities"}
    assert "convexities" in r and "nothing" not in r


def test_save_keeps_what_shadelab_did_not_write(tmp_path):
    # An output folder is the user's too: their file stays, and a folder shadelab did not
    # write is written into only with force=True.
    r = shadelab.fading(ppd=16, duration=1.0)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("my notes")
    with pytest.raises(OSError, match="not written by shadelab .*pass force=True"):
        r.save(mine)
    assert sorted(os.listdir(mine)) == ["notes.txt"]
    r.save(mine, force=True)
    assert (mine / "notes.txt").read_text() == "my notes" and (mine / "fading.json").is_file()


def test_bad_values_are_value_errors():
    with pytest.raises(ValueError, match="τ -1 s"):
        shadelab.fading(ppd=16, tau=-1)
    with pytest.raises(ValueError, match="light"):
        shadelab.outline("boundary-strips", ppd=12, light="tilt=0,slant=95")
    with pytest.raises(ValueError):
        shadelab.fading(np.ones((32, 32)), ppd=16)  # no disk labels


def test_experiment_matches_the_command_line(tmp_path):
    e = shadelab.experiment(tmp_path / "py", rotations=[0, 90, 180, 270], repeats=2,
                            practice=2, seed=3, keys="fj")
    cli = run_cli("experiment", "--out", tmp_path / "cli", "--rotations", "0,90,180,270",
                  "--repeats", 2, "--practice", 2, "--seed", 3, "--keys", "fj", "--no-install")
    assert without_run_fields(e.report) == without_run_fields(cli)
    assert e.folder == str(tmp_path / "py") and e.kept == [] and e.install_error is None
    assert len(e.design["trials"]) == 4 * 2 + 2
    assert_same_folder(tmp_path / "py", tmp_path / "cli")
    # The user's own file stays; a folder shadelab did not write needs force=True.
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "responses-p1.csv").write_text("collected")
    with pytest.raises(OSError, match="force=True"):
        shadelab.experiment(mine)
    shadelab.experiment(mine, force=True, repeats=1)
    assert (mine / "responses-p1.csv").read_text() == "collected"
    with pytest.raises(ValueError, match="keys"):
        shadelab.experiment(tmp_path / "bad", keys="f")
    with pytest.raises(ValueError, match="save_format"):
        shadelab.experiment(tmp_path / "bad", save_format="xml")


def test_experiment_pilot_gives_the_command_lines_rows(tmp_path):
    # The simulated participant's rows without a browser: the CSV the command line writes,
    # byte for byte, with the simulated column set, and fit_observer leaves them out unless
    # asked.
    shadelab.experiment(tmp_path / "study", rotations=[0, 90, 180, 270], repeats=2, practice=2, seed=3)
    model = "tilt:20,kappa:2,convex:0.6,lapse:0.02,seed:5"
    text = shadelab.experiment_pilot(tmp_path / "study", model, participant="P1", out=tmp_path / "py.csv")
    run_cli("experiment", "pilot", tmp_path / "study", "--simulate", model, "--participant", "P1",
            "--out", tmp_path / "cli.csv")
    assert (tmp_path / "py.csv").read_text() == text == (tmp_path / "cli.csv").read_text()
    rows = list(csv.DictReader(io.StringIO(text)))
    assert len(rows) == 4 * 2 + 2  # the test trials and the practice
    assert {r["simulated"] for r in rows} == {model}
    with pytest.raises(ValueError, match="include_simulated"):
        shadelab.fit_observer(tmp_path / "py.csv")
    with pytest.raises(ValueError, match="simulate"):
        shadelab.experiment_pilot(tmp_path / "study", "tilt:20")
    with pytest.raises(ValueError, match="participant 'P 1': use letters"):
        shadelab.experiment_pilot(tmp_path / "study", model, participant="P 1")


def simulated_judgements(seed=7, mu=26.0, trials=24):
    """Bump/dimple answers whose P(convex) peaks where the bright side faces mu."""
    rng = np.random.default_rng(seed)
    rotations = np.repeat(np.arange(0, 360, 30.0), trials)
    p = 0.5 + 0.45 * np.cos(np.radians(rotations - mu))
    return rotations, rng.random(rotations.size) < p


class TableLike:
    """What fit_observer asks of a DataFrame: to_csv(index=False)."""

    def __init__(self, columns):
        self.columns = columns

    def to_csv(self, index=True):
        assert index is False
        names = list(self.columns)
        rows = zip(*(self.columns[n] for n in names))
        return ",".join(names) + "\n" + "".join(",".join(map(str, r)) + "\n" for r in rows)


def test_fit_observer_matches_the_command_line(tmp_path):
    rotations, convex = simulated_judgements()
    words = np.where(convex, "convex", "concave")
    csv_path = tmp_path / "responses.csv"
    csv_path.write_text("rotation_deg,response\n" + "".join(
        f"{r},{w}\n" for r, w in zip(rotations, words)))
    cli = run_cli("fit", "observer", csv_path, "--bootstrap", 0, "--out", tmp_path / "cli")
    by_path = shadelab.fit_observer(csv_path, bootstrap=0)
    assert without_run_fields(by_path.report) == without_run_fields(cli)
    # The same trials handed over in memory: a dict of arrays, a DataFrame-like table, and
    # key presses with their mapping, all give the same fit.
    by_dict = shadelab.fit_observer({"rotation_deg": rotations, "response": convex}, bootstrap=0)
    by_table = shadelab.fit_observer(
        TableLike({"rotation_deg": list(rotations), "response": list(words)}), bootstrap=0)
    keys = np.where(convex, "f", "j")
    by_keys = shadelab.fit_observer({"rotation_deg": rotations, "response": keys}, keys="fj",
                                    bootstrap=0)
    for r in (by_dict, by_table, by_keys):
        assert r.pooled == by_path.pooled
    # The bright side's preferred direction is recovered near the simulated 26°.
    mu = by_path.pooled["prior_tilt_deg"]
    assert mu["ci95"][0] < mu["value"] < mu["ci95"][1] and abs(mu["value"] - 26.0) < 15.0, mu
    assert_same_folder(pathlib.Path(by_path.save(tmp_path / "py")), tmp_path / "cli")
    assert (tmp_path / "py" / "methods.md").is_file()
    assert_figures_are_the_pngs(by_path, tmp_path / "py")
    with pytest.raises(ValueError, match="keys"):
        shadelab.fit_observer({"rotation_deg": rotations, "response": keys}, bootstrap=0)
    with pytest.raises(ValueError, match="different lengths"):
        shadelab.fit_observer({"rotation_deg": rotations, "response": convex[:-1]})
    with pytest.raises(FileNotFoundError):
        shadelab.fit_observer(tmp_path / "missing.csv")
