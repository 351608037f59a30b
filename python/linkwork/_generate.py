"""The files of the repository that are generated, and their generator: ``python -m linkwork._generate``
writes them, ``python -m linkwork._generate --check`` lists those that are stale (with a diff) and
exits 1 (``tests/test_generated.py`` runs it).

Each comes from one source the native module gives:

- ``python/linkwork/_entries.py``, the builder's typed methods of joints, drivers and forces and
  the types of their fields, from the JSON schema of model files (``linkwork schema``, made from
  the engine's Rust types);
- the exception classes' lists (the stub ``_linkwork.pyi``, ``errors.py``) and the README's table
  of them (``linkwork/__init__.py`` takes ``errors.py``'s), from the classes ``crates/linkwork-py/src/errors.rs`` defines and its table of their
  attributes (``ERROR_ATTRIBUTES``), with the exit status the command line gives each
  (:func:`linkwork.cli.exit_status`).

A generated part of a hand-written file stands between two marker lines, ``generated: <name>``
and ``end generated: <name>``; a generated file is generated whole.
"""

from __future__ import annotations

import argparse
import difflib
import json
import keyword
import sys
import textwrap
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from . import _linkwork, cli, errors


def _repository() -> Path:
    """The repository whose files are generated: the one this file is ``python/linkwork/`` of (a
    source tree or an editable install), else the current folder (an installed package carries
    no repository)."""
    here = Path(__file__).resolve().parents[2]
    return here if (here / "pyproject.toml").is_file() else Path.cwd()


#: The repository the generated files are in.
ROOT = _repository()

#: Width of the generated text, as the hand-written code around it.
WIDTH = 100

#: The sections of a model file whose entries get a typed builder method each, with the schema
#: definition of an entry and the method's name for a type: a joint by its type (``revolute``),
#: a driver with ``_driver`` (its types name coordinates: ``x``, ``distance``), a force by its
#: type, or ``applied_<type>`` where the type is a name the builder has already (``force``).
SECTIONS = (
    ("joints", "joint", "JointSpec", "{type}", "{type}_joint"),
    ("drivers", "driver", "DriverSpec", "{type}_driver", "{type}_driver"),
    ("forces", "force", "ForceSpec", "{type}", "applied_{type}"),
)

#: Methods of :class:`linkwork.Mechanism` written by hand, which no typed method may take the name of.
HAND_WRITTEN = frozenset({
    "parameter", "ground_point", "body", "joint", "driver", "force", "measure", "summary", "table",
    "transmission_angle", "velocity_ratio", "mechanical_advantage", "pressure_angle", "branch", "paths",
    "display", "analysis", "to_dict", "to_yaml", "build",
})

#: Field types the hand-written builder methods use besides those of the typed ones (``body``'s points).
EXTRA_TYPES = ("ByLengths",)


def _type_name(definition: str) -> str:
    """The Python name of a schema definition: without the Rust side's ``Spec``."""
    return definition.removesuffix("Spec")


class Schema:
    """The JSON schema of model files, read generally: ``$ref`` resolved (its own keys kept over
    the definition's), ``allOf`` merged, ``anyOf``/``oneOf`` as unions; the object definitions a
    field refers to become ``TypedDict`` types (collected in :attr:`types`, in order of use)."""

    def __init__(self, schema: Mapping[str, Any]) -> None:
        self.definitions: Mapping[str, Any] = schema.get("$defs") or schema.get("definitions") or {}
        self.types: dict[str, Mapping[str, Any]] = {}
        self._visiting: set[str] = set()

    def resolve(self, node: Mapping[str, Any]) -> tuple[str | None, dict[str, Any]]:
        """``node`` with its ``$ref`` followed and its ``allOf`` merged; the name of the
        definition it is, if it is one."""
        name = None
        node = dict(node)
        while "$ref" in node:
            name = node.pop("$ref").rsplit("/", 1)[-1]
            node = {**self.definitions[name], **node}
        for part in node.pop("allOf", []):
            _, merged = self.resolve(part)
            node["properties"] = {**node.get("properties", {}), **merged.get("properties", {})}
            node["required"] = [*node.get("required", []), *merged.get("required", [])]
            for key, value in merged.items():
                node.setdefault(key, value)
        return name, node

    def fields(self, node: Mapping[str, Any]) -> tuple[dict[str, Any], list[str]]:
        """An object's fields (name -> schema) and the names of those it requires, in order."""
        _, node = self.resolve(node)
        return dict(node.get("properties", {})), list(dict.fromkeys(node.get("required", [])))

    def annotation(self, node: Mapping[str, Any]) -> tuple[str, bool]:
        """The Python type of a value of ``node``, and whether it may be ``null``."""
        name, node = self.resolve(node)
        alternatives = node.get("anyOf") or node.get("oneOf")
        if alternatives is not None:
            parts = [self.annotation(a) for a in alternatives]
            types = [t for t, _ in parts if t != "None"]
            return _union(types), any(null or t == "None" for t, null in parts)
        if "const" in node:
            return _SCALARS[type(node["const"]).__name__], False
        kinds = node.get("type", [])
        kinds = [kinds] if isinstance(kinds, str) else list(kinds)
        null = "null" in kinds
        kinds = [k for k in kinds if k != "null"]
        if not kinds:
            return "None", True
        if set(kinds) == {"number", "string"}:
            return "Number", null
        types = []
        for kind in kinds:
            if kind == "array":
                types.append(self._array(node))
            elif kind == "object" and name is not None and "properties" in node:
                self._collect(name)
                types.append(_type_name(name))
            elif kind == "object":
                types.append("Mapping[str, Any]")
            else:
                types.append(_SCALARS[kind])
        return _union(types), null

    def _collect(self, name: str) -> None:
        """Add the definition ``name`` to :attr:`types` after the types its fields refer to (a
        ``TypedDict`` is made at run time: what it names must stand before it)."""
        if name in self.types or name in self._visiting:
            return
        self._visiting.add(name)
        properties, _ = self.fields(self.definitions[name])
        for field in properties.values():
            self.annotation(field)
        self.types[name] = self.definitions[name]

    def _array(self, node: Mapping[str, Any]) -> str:
        item, _ = self.annotation(node.get("items", {}))
        if item == "Number" and node.get("minItems") == node.get("maxItems") == 2:
            return "Point"
        return f"Sequence[{item}]"

    def entries(self, definition: str) -> Iterator[tuple[str, Mapping[str, Any]]]:
        """Each type of the entries of ``definition`` (``JointSpec``) with its schema."""
        _, node = self.resolve({"$ref": f"#/$defs/{definition}"})
        for variant in node.get("oneOf") or node.get("anyOf") or []:
            properties, _ = self.fields(variant)
            _, tag = self.resolve(properties["type"])
            values = [tag["const"]] if "const" in tag else tag["enum"]
            for value in values:
                yield value, variant


_SCALARS = {"string": "str", "str": "str", "number": "float", "float": "float", "integer": "int", "int": "int",
            "boolean": "bool", "bool": "bool"}


def _union(types: Sequence[str]) -> str:
    """``a | b`` of ``types``, each once; text is a ``Number`` already."""
    unique = list(dict.fromkeys(types))
    if "Number" in unique:
        unique = [t for t in unique if t not in ("str", "float")]
    return " | ".join(unique) if unique else "Any"


def _doc(text: str, indent: str, lead: str = "") -> list[str]:
    """``text`` as the lines of a docstring at ``indent`` after ``lead`` (``X.__doc__ = ``),
    paragraphs kept, each wrapped."""
    text = text.replace("\\", "\\\\").replace('"""', '\\"\\"\\"')
    lines: list[str] = []
    for paragraph in text.split("\n\n"):
        words = " ".join(paragraph.split())
        first = len(lead) + 3 if not lines else 0
        wrapped = textwrap.wrap(words, WIDTH - len(indent), initial_indent="x" * first, break_on_hyphens=False,
                                break_long_words=False)
        if wrapped:
            wrapped[0] = wrapped[0][first:]
        lines += ([""] if lines else []) + (wrapped or [""])
    lines[0] = lead + '"""' + lines[0]
    lines[-1] += '"""'
    return [indent + line if line else "" for line in lines]


def _field_doc(fields: Mapping[str, Any]) -> str:
    """The fields' descriptions: ``name``: what it is."""
    # Each description on one line: a field's paragraphs would break the docstring's line.
    return " ".join(f"``{name}``: {' '.join(field.get('description', '').split())}" for name, field in fields.items())


def builder_entries(schema: Mapping[str, Any]) -> str:
    """The text of ``_entries.py``: a typed builder method per joint, driver and force type of
    ``schema``, and the ``TypedDict`` of each object its fields take."""
    reader = Schema(schema)
    methods: list[str] = []
    taken = set(HAND_WRITTEN)
    for section, singular, definition, pattern, fallback in SECTIONS:
        for kind, variant in reader.entries(definition):
            name = pattern.format(type=kind)
            name = name if name not in taken else fallback.format(type=kind)
            if name in taken or not name.isidentifier() or keyword.iskeyword(name):
                raise ValueError(f"{section}.{kind}: no free method name for it ({name!r} is taken or not a name)")
            taken.add(name)
            methods.append(_method(reader, singular, name, kind, variant))
    for extra in EXTRA_TYPES:
        reader.annotation({"$ref": f"#/$defs/{extra}"})
    types = [_typed_dict(reader, definition, node) for definition, node in reader.types.items()]
    head = [
        '"""The builder\'s typed methods of joints, drivers and forces, and the types of their fields.',
        "",
        "Generated by ``python -m linkwork._generate`` from the JSON schema of model files (``linkwork",
        "schema``): do not edit; change the engine's types and generate again.",
        '"""',
        "",
        "from __future__ import annotations",
        "",
        "from collections.abc import Mapping, Sequence" if any("Mapping[" in t for t in [*types, *methods])
        else "from collections.abc import Sequence",
        "from typing import Any, Protocol, Required, TypedDict, Union",
        "",
        "import numpy as np",
        "",
        "Number = Union[float, str]",
        '"""A number in SI units, or text: a number with a unit (``"40 mm"``) or an expression of the',
        'parameters (``"r/2"``)."""',
        "",
        'Point = Union[tuple[Number, Number], Sequence[Number], "np.ndarray[Any, Any]"]',
        '"""``(x, y)``, m (or text with a unit); a numpy array of two numbers too."""',
    ]
    adds = [
        "",
        "",
        "class _Adds(Protocol):",
        '    """What the typed methods add entries with: :class:`linkwork.Mechanism`\'s generic methods."""',
        "",
        *[f"    def {singular}(self, name: str, type: str, **fields: Any) -> str: ..."
          for _, singular, *_ in SECTIONS],
        "",
        "",
        "class Entries:",
        '    """The typed methods of :class:`linkwork.Mechanism`: one per joint, driver and force type of the',
        "    model format, each with the type's fields (docs/model-format.md); a field left at ``None`` takes",
        '    its default."""',
    ]
    return "\n".join([*head, *types, *adds, *methods]) + "\n"


def _typed_dict(reader: Schema, definition: str, node: Mapping[str, Any]) -> str:
    """A ``TypedDict`` of an object definition, in the functional syntax (a field may be a
    Python keyword: ``from``)."""
    properties, required = reader.fields(node)
    name = _type_name(definition)
    items = []
    for field, schema in properties.items():
        annotation, _ = reader.annotation(schema)
        items.append(f'    "{field}": {f"Required[{annotation}]" if field in required else annotation},')
    doc = _doc(f"{node.get('description', '').strip()}\n\n{_field_doc(properties)}", "", f"{name}.__doc__ = ")
    return "\n".join(["", "", f'{name} = TypedDict("{name}", {{', *items, "}, total=False)", *doc])


def _method(reader: Schema, singular: str, name: str, kind: str, variant: Mapping[str, Any]) -> str:
    """One typed method: the required fields positional, in the schema's order, then the others
    by keyword, each ``None`` by default."""
    properties, required = reader.fields(variant)
    fields = {f: s for f, s in properties.items() if f != "type"}
    positional = [f for f in required if f in fields]
    keywords = [f for f in fields if f not in positional]
    for field in fields:
        if keyword.iskeyword(field) or field in ("self", "name"):
            raise ValueError(f"{kind}.{field}: a field's name that cannot be a parameter's")
    parameters = ["self: _Adds", "name: str"]
    for field in positional:
        annotation, null = reader.annotation(fields[field])
        parameters.append(f"{field}: {annotation}{' | None' if null else ''}")
    if keywords:
        parameters.append("*")
    for field in keywords:
        annotation, _ = reader.annotation(fields[field])
        parameters.append(f"{field}: {annotation} | None = None")
    call = ", ".join([f'name, "{kind}"', *(f"{f}={f}" for f in [*positional, *keywords])])
    _, resolved = reader.resolve(variant)
    # The signature and the call on a line each, and the fields' descriptions on one line, however
    # long: types of the same fields (`x` and `y`) would otherwise give the same block twice.
    doc = _doc(resolved.get("description", "").strip(), "        ")
    doc[-1] = doc[-1].removesuffix('"""')
    return "\n".join([
        "",
        f"    def {name}({', '.join(parameters)}) -> str:",
        *doc,
        "",
        f'        {_field_doc(fields)}"""'.replace("\\", "\\\\"),
        f"        return self.{singular}({call})",
    ])


# --- exceptions ----------------------------------------------------------------------------------


def exception_classes() -> list[tuple[type[BaseException], list[tuple[str, str]]]]:
    """Every exception class of the native module with the attributes it adds, base classes first."""
    classes = []
    for name, attributes in _linkwork.ERROR_ATTRIBUTES:
        cls = getattr(_linkwork, name)
        if not (isinstance(cls, type) and issubclass(cls, BaseException)):
            raise ValueError(f"ERROR_ATTRIBUTES names {name!r}, no exception class of the native module")
        classes.append((cls, list(attributes)))
    return classes


def _bases(cls: type) -> list[str]:
    return [b.__name__ for b in cls.__bases__]


def _all_attributes(cls: type, added: Mapping[str, list[tuple[str, str]]]) -> list[str]:
    """``cls``'s attributes with those of its bases, base first, each once."""
    inherited = [a for base in cls.__mro__[::-1] for a, _ in added.get(base.__name__, [])]
    return list(dict.fromkeys(inherited))


def stub_exceptions() -> str:
    """The exception classes' part of ``_linkwork.pyi``."""
    lines = []
    for cls, attributes in exception_classes():
        head = f"class {cls.__name__}({', '.join(_bases(cls))}):"
        lines += ["", f"{head} ..." if not attributes else head, *(f"    {a}: {t}" for a, t in attributes)]
    return "\n".join(lines[1:]) + "\n"


def _names(names: Sequence[str], statement: str, quote: bool) -> list[str]:
    """``statement`` of ``names`` (an import, an ``__all__``), several to a line."""
    wrapped = textwrap.wrap(", ".join(repr(n) if quote else n for n in names) + ",", WIDTH - 4)
    return [f"{statement}{'[' if quote else '('}", *(f"    {line}" for line in wrapped), "]" if quote else ")"]


def stub_names() -> str:
    """The stub's ``__all__``: every name the native module exports (its own ``__all__``)."""
    return "\n".join(_names(sorted(_linkwork.__all__), "__all__ = ", True)) + "\n"


def errors_names() -> str:
    """``errors.py``'s imports of the exception classes and its ``__all__``."""
    names = sorted(cls.__name__ for cls, _ in exception_classes())
    return "\n".join([*_names(names, "from ._linkwork import ", False), "", *_names(names, "__all__ = ", True)]) + "\n"


def readme_exceptions() -> str:
    """The README's table of the exceptions: base, when raised, attributes, and the command
    line's exit status for each."""
    classes = exception_classes()
    added = {cls.__name__: attributes for cls, attributes in classes}
    rows = ["| exception | a kind of | raised when | attributes | `linkwork` exits with |", "| --- | --- | --- | --- | --- |"]
    for cls, _ in classes:
        # The docstring's first clause: what happened.
        when = " ".join((cls.__doc__ or "").split()).split(". ")[0].split(": ")[0].rstrip(".")
        attributes = ", ".join(f"`{a}`" for a in _all_attributes(cls, added)) or "none"
        bases = ", ".join(f"`{b}`" for b in _bases(cls))
        status = cli.exit_status(cls("…"))
        rows.append(f"| `{cls.__name__}` | {bases} | {when} | {attributes} | {status} |")
    return "\n".join(rows) + "\n"


# --- the files -----------------------------------------------------------------------------------

#: Each generated file, or part of one (``name`` between its markers), and what makes it.
TARGETS: tuple[tuple[str, str | None, Callable[[], str]], ...] = (
    ("python/linkwork/_entries.py", None, lambda: builder_entries(json.loads(_linkwork.schema()))),
    ("python/linkwork/_linkwork.pyi", "names", stub_names),
    ("python/linkwork/_linkwork.pyi", "exceptions", stub_exceptions),
    ("python/linkwork/errors.py", "exception names", errors_names),
    ("README.md", "exceptions", readme_exceptions),
)


def _replaced(text: str, part: str, content: str, path: str) -> str:
    """``text`` with the lines between the markers of ``part`` made ``content``."""
    lines = text.splitlines(keepends=True)
    # A marker is a comment of its file's language: `# ...`, `<!-- ... -->`.
    marks = [line.strip().removesuffix("-->").strip() for line in lines]
    begin = [k for k, mark in enumerate(marks) if mark.endswith(f" generated: {part}") and not mark.endswith(f"end generated: {part}")]
    end = [k for k, mark in enumerate(marks) if mark.endswith(f"end generated: {part}")]
    if len(begin) != 1 or len(end) != 1 or end[0] < begin[0]:
        raise ValueError(f"{path}: expected one 'generated: {part}' line and one 'end generated: {part}' after it")
    return "".join([*lines[: begin[0] + 1], content, *lines[end[0]:]])


def generated(root: Path = ROOT) -> dict[Path, tuple[str, str]]:
    """Each generated file under ``root``: its text now and as generated."""
    files: dict[Path, tuple[str, str]] = {}
    for relative, part, make in TARGETS:
        path = root / relative
        if not path.is_file():
            raise FileNotFoundError(f"{path}: not found (run `python -m linkwork._generate` in the repository)")
        now = path.read_text(encoding="utf-8")
        before, text = files.get(path, (now, now))
        files[path] = (before, make() if part is None else _replaced(text, part, make(), relative))
    return files


def stale(root: Path = ROOT) -> list[str]:
    """A unified diff for each generated file under ``root`` that is not as generated."""
    return [
        "".join(difflib.unified_diff(now.splitlines(True), new.splitlines(True), str(path), f"{path} (generated)"))
        for path, (now, new) in generated(root).items()
        if now != new
    ]


def main(argv: Sequence[str] | None = None) -> int:
    """Write the generated files (``--check``: only list the stale ones, exit 1 if any)."""
    parser = argparse.ArgumentParser(prog="python -m linkwork._generate", description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="write nothing; show what is stale and exit 1 if anything is")
    args = parser.parse_args(argv)
    if args.check:
        diffs = stale()
        sys.stdout.write("".join(diffs))
        return 1 if diffs else 0
    for path, (now, new) in generated().items():
        if now != new:
            path.write_text(new, encoding="utf-8")
            print(f"wrote {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
