"""The documentation a Python user sees: the .pyi stub names exactly what the module holds (top
level and class members), every class, function, method and property has a docstring, and
help(knnocc.Mapper) tells the models and their parameters."""

import ast
import pathlib
import pydoc

import pytest

STUB = pathlib.Path(__file__).resolve().parents[2] / "examples" / "python" / "module" / "knnocc.pyi"
UNDOCUMENTED = {"__repr__", "__getstate__", "__setstate__", "__module__", "__doc__", "__hash__",
                "__dict__", "__weakref__"}


def stub_names():
    """{name: None for a function or variable, {member names} for a class} of the stub."""
    names = {}
    for node in ast.parse(STUB.read_text()).body:
        if isinstance(node, ast.ClassDef):
            names[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = None
        elif isinstance(node, ast.AnnAssign):
            names[node.target.id] = None
    return names


def module_members(cls):
    return {n for n in vars(cls) if n not in UNDOCUMENTED}


def test_stub_names_match_the_module(knnocc):
    stub = stub_names()
    module = {n for n in dir(knnocc) if not n.startswith("__")} | {"__version__"}
    assert set(stub) == module
    for name, members in stub.items():
        if name == "Error":
            assert issubclass(knnocc.Error, OSError)
        elif isinstance(members, set):
            cls = getattr(knnocc, name)
            if "__init__" not in members:  # made by a function only: pybind11's __init__ refuses
                with pytest.raises(TypeError):
                    cls()
                members = members | {"__init__"}
            assert members - UNDOCUMENTED == module_members(cls), name


def docstring(obj):
    """The text of a docstring without pybind11's signature line."""
    doc = (obj.__doc__ or "").strip()
    if doc.startswith(getattr(obj, "__name__", "\0") + "("):
        doc = doc.split("\n", 1)[1].strip() if "\n" in doc else ""
    return doc


def test_everything_has_a_docstring(knnocc):
    assert len(knnocc.__doc__) > 200
    for name in dir(knnocc):
        if name.startswith("__"):
            continue
        obj = getattr(knnocc, name)
        assert docstring(obj), name
        if isinstance(obj, type) and name != "Error":
            for member in module_members(obj):
                if name == "Sequence" and member == "__init__":
                    continue  # pybind11's: Sequence is made by read_sequence only
                assert docstring(getattr(obj, member)), f"{name}.{member}"


@pytest.mark.parametrize("needle", ["model=\"octomap\"", "'knn'", "k [8]", "margin_scale [2]",
                                    "'knn2022'", "inner_range [4]", "Knn2022FirstPass",
                                    "insert_keyframe", "statistics", "max_range"])
def test_help_of_mapper_is_useful(knnocc, needle):
    assert needle in pydoc.render_doc(knnocc.Mapper, renderer=pydoc.plaintext)
