"""The examples of docs/python.md and of the module's docstrings run as written."""

import doctest
import pathlib

import shadelab

# Beside python/ in the repository and in the sdist (Cargo.toml's `include` ships it).
DOCS = pathlib.Path(__file__).resolve().parents[2] / "docs" / "python.md"
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def test_docs_python_md_examples_run():
    result = doctest.testfile(str(DOCS), module_relative=False, optionflags=FLAGS, verbose=False)
    assert result.attempted > 10
    assert result.failed == 0


def test_module_docstrings_run():
    # The package's own docstring, and its functions' (defined in its private module).
    result = doctest.testmod(shadelab, optionflags=FLAGS, verbose=False)
    assert result.attempted >= 2
    assert result.failed == 0
    api = doctest.testmod(
        shadelab._api, extraglobs={"shadelab": shadelab}, optionflags=FLAGS, verbose=False
    )
    assert api.attempted > 5
    assert api.failed == 0
    # Functions defined in the package's private modules and exported by name.
    display = doctest.testmod(
        shadelab._display, extraglobs={"shadelab": shadelab}, optionflags=FLAGS, verbose=False
    )
    assert display.attempted >= 3
    assert display.failed == 0


def test_readme_python_example_runs(capsys):
    readme = DOCS.parents[1] / "README.md"
    text = readme.read_text(encoding="utf-8")
    blocks = [b.split("```", 1)[0] for b in text.split("```python\n")[1:]]
    assert blocks, "README.md has a Python example"
    for block in blocks:
        exec(compile(block, str(readme), "exec"), {})
    printed = capsys.readouterr().out
    assert "(128, 128) (4.0, 4.0) True (128, 128, 3)" in printed


def test_the_namespace_is_the_api():
    # What a user sees with dir() and tab completion: the functions, no imports or helpers.
    public = sorted(n for n in dir(shadelab) if not n.startswith("_"))
    assert public == sorted(shadelab.__all__), public
    assert isinstance(shadelab.__version__, str)


def test_the_type_stubs_describe_the_api():
    # __init__.pyi (what editors and type checkers read) names every public function with
    # the parameters the function really takes, and every public class.
    import ast
    import inspect
    import pathlib

    stub = ast.parse((pathlib.Path(shadelab.__file__).parent / "__init__.pyi").read_text())
    defs = {n.name: n for n in stub.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    assigned = {t.id for n in stub.body if isinstance(n, ast.AnnAssign) for t in [n.target]}
    for name in shadelab.__all__:
        obj = getattr(shadelab, name)
        assert name in defs or name in assigned, f"{name} has no stub"
        if inspect.isfunction(obj):
            node = defs[name]
            stubbed = [a.arg for a in node.args.posonlyargs + node.args.args + node.args.kwonlyargs]
            if node.args.kwarg:
                stubbed.append(node.args.kwarg.arg)
            real = list(inspect.signature(obj).parameters)
            assert stubbed == real, (name, stubbed, real)
