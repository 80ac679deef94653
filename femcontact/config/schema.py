"""Declarative schemas: typed fields with defaults, ranges and docs, and their validation.

A schema is a dict mapping keys to `Field`s, to nested schemas (sub-tables) or to
`TableList`s (arrays of tables). `validate(data, schema)` returns a fully resolved
copy (defaults filled in) or raises one `InputError` listing every problem, each
naming the dotted key, the bad value and what is allowed.
"""
import math
from dataclasses import dataclass
from typing import Any, Callable

from femcontact.errors import InputError

REQUIRED = object()


@dataclass(frozen=True)
class Field:
    """One scene value. `kind` is 'float', 'int', 'str', 'bool', 'floats' (list of numbers),
    'strs' (list of strings) or 'any'. Units go in `doc`. Numbers must be finite (no NaN,
    no infinity) unless `finite` is False."""
    kind: str
    default: Any = REQUIRED
    doc: str = ""
    choices: tuple = ()
    min: float | None = None
    max: float | None = None
    positive: bool = False
    length: int | None = None
    finite: bool = True
    check: Callable[[Any], str | None] | None = None  # returns a complaint or None

    def allowed(self) -> str:
        parts = []
        if self.choices:
            parts.append("one of " + ", ".join(map(repr, self.choices)))
        elif self.kind in ("float", "int", "floats"):
            parts.append({"float": "a number", "int": "an integer", "floats": "a list of numbers"}[self.kind])
        else:
            parts.append({"str": "a string", "bool": "true or false", "strs": "a list of strings",
                          "any": "any value"}[self.kind])
        if self.length is not None:
            parts.append(f"of length {self.length}")
        if self.positive:
            parts.append("> 0")
        if self.min is not None:
            parts.append(f">= {self.min}")
        if self.max is not None:
            parts.append(f"<= {self.max}")
        return " ".join(parts)


@dataclass(frozen=True)
class TableList:
    """An array of tables, each validated against `schema` (e.g. [[steps]])."""
    schema: dict
    doc: str = ""
    default: Any = REQUIRED


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _coerce(value, field: Field):
    """Return the value converted to the field's kind, or raise TypeError."""
    kind = field.kind
    if kind == "any":
        return value
    if kind == "float" and _is_number(value):
        return float(value)
    if kind == "int" and isinstance(value, int) and not isinstance(value, bool):
        return value
    if kind == "str" and isinstance(value, str):
        return value
    if kind == "bool" and isinstance(value, bool):
        return value
    if kind == "floats" and _is_number(value):
        return [float(value)]
    if kind == "floats" and isinstance(value, (list, tuple)) and all(map(_is_number, value)):
        return [float(v) for v in value]
    if kind == "strs" and isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
        return list(value)
    raise TypeError


def _field_errors(value, field: Field) -> str | None:
    if field.choices:
        items = value if isinstance(value, list) else [value]
        if any(item not in field.choices for item in items):
            return "not allowed"
    if field.length is not None and len(value) != field.length:
        return f"has length {len(value)}"
    numbers = value if field.kind == "floats" else [value] if field.kind in ("float", "int") else []
    for number in numbers:
        if field.finite and not math.isfinite(number):
            return "not a finite number"
        if field.positive and not number > 0:
            return "out of range"
        if field.min is not None and number < field.min:
            return "out of range"
        if field.max is not None and number > field.max:
            return "out of range"
    return field.check(value) if field.check else None


def validate(data: dict, schema: dict, prefix: str = "") -> dict:
    """Resolved copy of `data` against `schema`; raises InputError listing all problems."""
    errors: list[str] = []
    resolved = _validate(data, schema, prefix, errors)
    if errors:
        raise InputError("invalid scene:\n  " + "\n  ".join(errors) if len(errors) > 1 else errors[0])
    return resolved


def _validate(data, schema, prefix, errors) -> dict:
    if not isinstance(data, dict):
        errors.append(f"{prefix.rstrip('.') or 'scene'} = {data!r}: expected a table")
        return {}
    out = {}
    for key in data:
        if key not in schema:
            known = ", ".join(sorted(schema))
            errors.append(f"{prefix}{key}: unknown key (allowed here: {known})")
    for key, spec in schema.items():
        name = prefix + key
        if isinstance(spec, dict):
            out[key] = _validate(data.get(key, {}), spec, name + ".", errors)
        elif isinstance(spec, TableList):
            if key not in data:
                if spec.default is REQUIRED:
                    errors.append(f"{name}: missing (required)")
                out[key] = [] if spec.default is REQUIRED else list(spec.default)
                continue
            if not isinstance(data[key], list):
                errors.append(f"{name} = {data[key]!r}: expected an array of tables")
                continue
            out[key] = [_validate(item, spec.schema, f"{name}[{i}].", errors) for i, item in enumerate(data[key])]
        elif key in data:
            try:
                value = _coerce(data[key], spec)
            except TypeError:
                errors.append(f"{name} = {data[key]!r}: wrong type, expected {spec.allowed()}")
                continue
            problem = _field_errors(value, spec)
            if problem:
                errors.append(f"{name} = {data[key]!r}: {problem}, expected {spec.allowed()}")
            out[key] = value
        elif spec.default is REQUIRED:
            errors.append(f"{name}: missing (required; {spec.allowed()}{', ' + spec.doc if spec.doc else ''})")
        else:
            out[key] = spec.default
    return out


def parse_assignment(text: str) -> tuple[str, Any]:
    """'peg.insertion_depth=5' -> ('peg.insertion_depth', 5); the value is read as TOML."""
    import tomllib

    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise InputError(f"--set {text!r}: expected KEY=VALUE, e.g. peg.insertion_depth=5")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()  # a bare word such as nitsche
    return key, value


def set_key(data: dict, dotted: str, value) -> None:
    """Set data['a']['b'] = value for dotted = 'a.b', creating tables as needed.

    An integer part indexes an existing array: 'steps.1.force' sets data['steps'][1]['force'].
    """
    *parts, last = dotted.split(".")
    node = data
    for part in parts:
        node = _child(node, part, dotted)
    if isinstance(node, list):
        _child(node, last, dotted)  # checks the index
        node[int(last)] = value
    else:
        node[last] = value


def get_key(scene: dict, dotted: str):
    """scene['a'][1]['b'] for 'a.1.b'; None when absent."""
    node = scene
    for part in dotted.split("."):
        if isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        elif isinstance(node, dict) and part in node:
            node = node[part]
        else:
            return None
    return node


def _child(node, part: str, dotted: str):
    """The table or array `node[part]` on the way to `dotted` (tables are created as needed)."""
    if isinstance(node, list):
        if not part.isdigit() or int(part) >= len(node):
            raise InputError(f"{dotted}: {part!r} is not an index of an array of length {len(node)}")
        child = node[int(part)]
    elif isinstance(node, dict):
        child = node.setdefault(part, {})
    else:
        raise InputError(f"{dotted}: {part!r} is inside a value that is not a table or an array")
    if not isinstance(child, (dict, list)):
        raise InputError(f"{dotted}: {part!r} is not a table")
    return child


DESCRIPTION = ("key", "allowed", "default", "meaning")
"""The columns of `describe`'s rows."""


def describe(schema: dict, prefix: str = "") -> list[tuple[str, str, str, str]]:
    """A row per key documenting a schema (docs/scenes.md): its dotted name, what is allowed, its
    default and its meaning, as Markdown cell texts (columns `DESCRIPTION`)."""
    rows = []
    for key, spec in schema.items():
        name = prefix + key
        if isinstance(spec, dict):
            rows += describe(spec, name + ".")
        elif isinstance(spec, TableList):
            rows.append((f"`{name}`", "array of tables", "", spec.doc))
            rows += describe(spec.schema, name + "[].")
        else:
            default = "required" if spec.default is REQUIRED else f"`{spec.default!r}`"
            rows.append((f"`{name}`", spec.allowed(), default, spec.doc))
    return rows
