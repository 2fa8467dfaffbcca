"""The documentation runs: every docstring example, the Python guide's example
(docs/python.md) as written, and type stubs that state the runtime's parameters."""

import ast
import doctest
import inspect
import os
import pathlib
import re

import pytest

import surfmap
import surfmap.distributed
from conftest import REPO

STUB = pathlib.Path(surfmap.__file__).with_name("_surfmap.pyi")


def public_objects():
    yield "surfmap", surfmap
    for name in surfmap.__all__:
        obj = getattr(surfmap, name)
        if callable(obj):
            yield f"surfmap.{name}", obj


@pytest.mark.parametrize("name,obj", list(public_objects()), ids=lambda x: x if isinstance(x, str) else "")
def test_docstring_examples_run(name, obj, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert obj.__doc__, f"{name} has no docstring"
    tests = doctest.DocTestFinder(recurse=False).find(obj, name, globs={})
    examples = sum(len(t.examples) for t in tests)
    is_exception = isinstance(obj, type) and issubclass(obj, BaseException)
    if not is_exception and not name.endswith("__version__") and name != "surfmap.BATCH_COLUMNS":
        assert examples > 0, f"{name}'s docstring has no example"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for t in tests:
        runner.run(t)
    assert runner.failures == 0, f"{name}: {runner.failures} failing example(s)"


def test_the_python_guide_example_runs_as_written(tmp_path, monkeypatch, capsys):
    guide = (REPO / "docs" / "python.md").read_text()
    section = guide[guide.index("## Flatten arrays") :]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert len([line for line in code.splitlines() if line.strip()]) <= 10
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "docs/python.md", "exec"), {})
    printed = capsys.readouterr().out.split()
    assert printed[0] == "True"
    assert (tmp_path / "bump_flat.obj").is_file()
    assert (tmp_path / "flat" / "summary.csv").is_file()


def test_the_package_readme_cutting_example_runs_as_written(tmp_path, monkeypatch, capsys):
    readme = (REPO / "crates" / "surfmap-py" / "README.md").read_text()
    code = re.search(r"```python\n(.*?)```", readme, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "crates/surfmap-py/README.md", "exec"), {})
    printed = capsys.readouterr().out.split()
    assert " ".join(printed[:7]) == "cut open along seams (closed, genus 1)"
    assert int(printed[7]) > 0 and printed[8] == "bijective"
    text = (tmp_path / "torus_flat.obj").read_text()
    assert "f 1/" in text and text.count("\nvt ") > text.count("\nv ")


def stub_functions():
    tree = ast.parse(STUB.read_text())
    return {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}


def test_stubs_state_the_runtime_parameters():
    stubs = stub_functions()
    runtime = {
        name
        for name in dir(surfmap._surfmap)
        if callable(getattr(surfmap._surfmap, name)) and not isinstance(getattr(surfmap._surfmap, name), type)
    }
    assert set(stubs) == runtime
    for name, node in stubs.items():
        sig = inspect.signature(getattr(surfmap._surfmap, name))
        a = node.args
        stub_params = [(p.arg, "POSITIONAL_OR_KEYWORD") for p in a.args]
        if a.vararg:
            stub_params.append((a.vararg.arg, "VAR_POSITIONAL"))
        stub_params += [(p.arg, "KEYWORD_ONLY") for p in a.kwonlyargs]
        if a.kwarg:
            stub_params.append((a.kwarg.arg, "VAR_KEYWORD"))
        assert stub_params == [(p.name, p.kind.name) for p in sig.parameters.values()], name
        defaults = [ast.literal_eval(d) for d in a.defaults] + [
            ast.literal_eval(d) for d in a.kw_defaults if d is not None
        ]
        runtime_defaults = [p.default for p in sig.parameters.values() if p.default is not p.empty]
        assert defaults == runtime_defaults, name


def test_flatten_many_has_the_documented_keywords():
    """The options flatten_file and flatten_many take by name are flatten's keywords."""
    flatten_keywords = [
        p.name for p in inspect.signature(surfmap.flatten).parameters.values() if p.kind == p.KEYWORD_ONLY
    ]
    stub_comment = STUB.read_text().split("as **options")[0].split("take the keywords of flatten() (")[1]
    assert [w.strip(" #\n)") for w in stub_comment.split(",")] == flatten_keywords
    for name in flatten_keywords:
        surfmap._surfmap._check_flatten_options(**{name: inspect.signature(surfmap.flatten).parameters[name].default})


def test_the_package_is_typed():
    assert (pathlib.Path(surfmap.__file__).parent / "py.typed").is_file()
    assert os.path.getsize(STUB) > 0
