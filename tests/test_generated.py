"""The generated files (`python -m linkwork._generate`): each is as its source makes it, a stale
one is found, the generator reads a schema in any of the shapes JSON Schema allows, and what it
writes says what the code does."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest

import linkwork
from linkwork import _generate, _linkwork

from conftest import EXAMPLES, ROOT


def test_the_generated_files_are_current() -> None:
    """Run `python -m linkwork._generate` after changing the schema or the exceptions."""
    # The repository's files: with the package installed (not editable), _generate's own default
    # is the current folder.
    diffs = _generate.stale(ROOT)
    assert not diffs, "stale generated files (run `python -m linkwork._generate`):\n" + "".join(diffs)


def copy_of_the_generated_files(tmp_path: Path) -> Path:
    for relative, _, _ in _generate.TARGETS:
        (tmp_path / relative).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / relative, tmp_path / relative)
    return tmp_path


@pytest.mark.parametrize(
    ("relative", "old", "new"),
    [
        ("python/linkwork/_entries.py", "    def gear(", "    def gears("),
        ("python/linkwork/_linkwork.pyi", "    hint: str\n", ""),
        ("python/linkwork/errors.py", "'ModelError', ", ""),
        ("README.md", "| `FileError` | `LinkworkError`, `OSError` |", "| `FileError` | `LinkworkError` |"),
    ],
)
def test_a_stale_file_is_found_with_its_diff(tmp_path: Path, relative: str, old: str, new: str) -> None:
    root = copy_of_the_generated_files(tmp_path)
    assert _generate.stale(root) == []
    path = root / relative
    text = path.read_text(encoding="utf-8")
    assert text.count(old) == 1, old
    path.write_text(text.replace(old, new), encoding="utf-8")
    [diff] = _generate.stale(root)
    # The diff takes the file back to what the generator writes: the old text added again.
    assert diff.startswith(f"--- {path}\n")
    assert any(line.startswith("+") and old.strip() in line for line in diff.splitlines())


def test_a_generated_part_without_its_markers_is_refused(tmp_path: Path) -> None:
    root = copy_of_the_generated_files(tmp_path)
    readme = root / "README.md"
    readme.write_text(readme.read_text(encoding="utf-8").replace("<!-- end generated: exceptions -->\n", ""))
    with pytest.raises(ValueError, match="README.md: expected one 'generated: exceptions' line"):
        _generate.stale(root)


def pulleys_schema() -> dict[str, Any]:
    """The engine's schema with a joint type added the way a flattened Rust struct writes it:
    `allOf` of a shared definition (by `$ref`) and the type's own fields, one of them a `$ref`
    with a description of its own, and a nullable number."""
    schema: dict[str, Any] = json.loads(_linkwork.schema())
    schema["$defs"]["TwoPulleys"] = {
        "type": "object",
        "properties": {
            "body_i": {"type": "string", "description": "First pulley."},
            "body_j": {"type": "string", "description": "Second pulley."},
            "point_i": {"$ref": "#/$defs/PointRef", "description": "Centre of the first pulley."},
        },
        "required": ["body_i", "body_j"],
    }
    schema["$defs"]["JointSpec"]["oneOf"].append({
        "description": "Pulleys: they turn as their radii say.",
        "allOf": [
            {"$ref": "#/$defs/TwoPulleys"},
            {
                "type": "object",
                "properties": {
                    "type": {"enum": ["pulleys"]},
                    "radius_i": {"type": ["number", "string"], "description": "Radius of the first pulley, m."},
                    "crossed": {"type": ["boolean", "null"], "default": None, "description": "Crossed."},
                    "slip": {"type": ["number", "null", "string"], "default": None, "description": "Slip."},
                },
                "required": ["type", "radius_i"],
            },
        ],
    })
    return schema


def test_a_new_joint_type_gets_its_builder_method_from_the_schema() -> None:
    """A joint type written with `allOf` and `$ref`: its method takes the required fields by
    position, in the schema's order, the others by keyword, typed from the schema, and adds the
    entry the file would hold."""
    text = _generate.builder_entries(pulleys_schema())
    assert (
        "    def pulleys(self: _Adds, name: str, body_i: str, body_j: str, radius_i: Number, *, "
        "point_i: Point | str | None = None, crossed: bool | None = None, slip: Number | None = None) -> str:\n"
    ) in text
    words = " ".join(text.split())
    assert "Pulleys: they turn as their radii say." in words and "``point_i``: Centre of the first pulley." in words
    namespace: dict[str, Any] = {"__name__": "pulleys_entries"}
    exec(compile(text, "_entries.py", "exec"), namespace)

    entries: type = namespace["Entries"]

    class Built(entries):  # type: ignore[misc]
        def joint(self, name: str, type: str, **fields: Any) -> str:
            self.added = (name, type, {k: v for k, v in fields.items() if v is not None})
            return name

    built = Built()
    assert built.pulleys("drive", "a", "b", 0.05, crossed=True) == "drive"
    assert built.added == ("drive", "pulleys", {"body_i": "a", "body_j": "b", "radius_i": 0.05, "crossed": True})


def test_the_typed_methods_cover_every_type_of_the_schema() -> None:
    """Each joint, driver and force type of the engine's schema has its method on `Mechanism`,
    and the method writes an entry of that type."""
    schema = _generate.Schema(linkwork.schema())
    for section, _, definition, pattern, fallback in _generate.SECTIONS:
        for kind, _ in schema.entries(definition):
            name = pattern.format(type=kind)
            method = getattr(linkwork.Mechanism, name if name not in _generate.HAND_WRITTEN else fallback.format(type=kind))
            m = linkwork.Mechanism()
            required = [p for p in method.__code__.co_varnames[2 : method.__code__.co_argcount]]
            method(m, "e", *(f"{kind}_{field}" for field in required))
            assert m.to_dict()[section]["e"] == {"type": kind, **{f: f"{kind}_{f}" for f in required}}


# The exit statuses of docs/DESIGN's contract: 2 a model or file error, 3 a solver failure, 1 an
# internal error (and a kind of error the command line does not know).
CONTRACT = {
    "LinkworkError": 1, "ModelError": 2, "AssemblyError": 3, "SolverError": 3, "SingularError": 3,
    "ConvergenceError": 3, "EquilibriumError": 3, "IntegrationError": 3, "NonFiniteError": 3, "AccuracyError": 3,
    "OutOfMemoryError": 3, "FileError": 2, "InternalError": 1,
}


def readme_table() -> dict[str, list[str]]:
    """The README's exception table, by class: its cells."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    rows = text.split("<!-- generated: exceptions -->\n", 1)[1].split("<!-- end generated", 1)[0].splitlines()[2:]
    cells = [[c.strip() for c in row.strip("|").split("|")] for row in rows]
    return {row[0].strip("`"): row for row in cells}


def test_the_readme_lists_every_exception_with_its_exit_status() -> None:
    table = readme_table()
    assert list(table) == [cls.__name__ for cls, _ in _generate.exception_classes()]
    assert set(table) == set(linkwork.errors.__all__) == set(CONTRACT)
    for name, (_, bases, _, attributes, status) in table.items():
        cls = getattr(linkwork, name)
        assert bases == ", ".join(f"`{b.__name__}`" for b in cls.__bases__), name
        assert int(status) == CONTRACT[name], name
    # The stub declares every attribute the table lists, on the class or a base.
    assert "`hint`" in table["AssemblyError"][3] and "`path`" in table["FileError"][3]


def test_the_attributes_listed_are_those_the_engine_sets() -> None:
    """A model error and a lock-up, raised by the engine: each carries exactly the attributes
    `ERROR_ATTRIBUTES` gives its class and its bases."""
    added = dict(_linkwork.ERROR_ATTRIBUTES)

    def listed(cls: type) -> set[str]:
        return {a for base in cls.__mro__ for a, _ in added.get(base.__name__, [])}

    with pytest.raises(linkwork.ModelError) as model_error:
        linkwork.from_yaml("bodies: {bar: {mass: 1}}")
    with pytest.raises(linkwork.SingularError) as singular:
        linkwork.load(EXAMPLES / "slider_crank_lockup.yaml").run()
    for caught in (model_error, singular):
        assert set(vars(caught.value)) == listed(type(caught.value)), type(caught.value).__name__
