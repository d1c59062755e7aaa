"""``schema``: the JSON Schema of each config kind, generated from the pydantic models (every field's
type, default, bounds and description with its unit), for editors that validate and complete YAML
(a ``# yaml-language-server: $schema=...`` line in the file) and for the config reference."""

from __future__ import annotations

import json
from pathlib import Path

from pydantic import BaseModel

from excite_cli.atomic import MARK_PREFIX, atomic_paths
from excite_cli.config import Problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.simulation_config import SimulationConfig
from excite_cli.storage.paths import check_target

#: Config kinds: the file a command reads → its model.
KINDS: dict[str, type[BaseModel]] = {"optimize": Problem, "identify": IdentifyProblem, "effects": SimulationConfig}
TITLES = {
    "optimize": "excite optimize / check / compare-random config",
    "identify": "excite identify / validate config",
    "effects": "excite simulate effects file",
}


def config_schema(kind: str) -> dict:
    """The JSON Schema (draft 2020-12) of config ``kind`` (a key of :data:`KINDS`).

    Raises:
        KeyError: an unknown kind.
    """
    schema = KINDS[kind].model_json_schema()
    schema = {"$schema": "https://json-schema.org/draft/2020-12/schema", **schema, "title": TITLES[kind]}
    return {**schema, "$comment": f"{MARK_PREFIX} schema"}


def run_schema(folder: Path, force: bool = False) -> list[Path]:
    """Write ``<folder>/<kind>.schema.json`` for every config kind (atomically, all or none).

    Raises:
        ExciteError: a file exists (without ``force``) or cannot be written.
    """
    targets = [check_target(Path(folder) / f"{kind}.schema.json", "output_dir", force) for kind in KINDS]
    with atomic_paths(targets, "output_dir") as temporary:
        for kind, path in zip(KINDS, temporary):
            text = json.dumps(config_schema(kind), indent=2, ensure_ascii=False) + "\n"
            Path(path).write_text(text, encoding="utf-8")
    return targets


def _type(prop: dict) -> str:
    """A property's type in words, from its JSON Schema."""
    if "$ref" in prop:
        return f"`{prop['$ref'].rsplit('/', 1)[-1]}`"
    if "enum" in prop:
        return " \\| ".join(f"`{v}`" for v in prop["enum"])
    if "const" in prop:
        return f"`{prop['const']}`"
    if "anyOf" in prop:
        return " or ".join(_type(p) for p in prop["anyOf"])
    kind = prop.get("type", "any")
    if kind == "array" and "prefixItems" in prop:
        return "[" + ", ".join(_type(p) for p in prop["prefixItems"]) + "]"
    if kind == "array":
        return f"list of {_type(prop.get('items') or {})}"
    if kind == "object":
        return f"{{name: {_type(prop.get('additionalProperties') or {})}}}"
    words = {"number": "number", "integer": "integer", "string": "text", "boolean": "bool", "null": "none"}
    return words.get(kind, kind)


def _bounds(prop: dict) -> str:
    """A property's bounds (and those of its alternatives) in words."""
    words = {"minimum": "≥", "exclusiveMinimum": ">", "maximum": "≤", "exclusiveMaximum": "<"}
    found = []
    for p in [prop, *prop.get("anyOf", []), *([prop["items"]] if isinstance(prop.get("items"), dict) else [])]:
        found += [f"{sign} {p[key]:g}" for key, sign in words.items() if key in p]
        if "minItems" in p and "prefixItems" not in p:
            found.append(f"at least {p['minItems']} item(s)")
    return ", ".join(found)


def _refs(prop: dict) -> list[str]:
    """The sections a property holds (its ``$ref`` s, however nested)."""
    if "$ref" in prop:
        return [prop["$ref"].rsplit("/", 1)[-1]]
    nested = [*prop.get("anyOf", []), *prop.get("prefixItems", [])]
    nested += [prop[key] for key in ("items", "additionalProperties") if isinstance(prop.get(key), dict)]
    return [name for p in nested for name in _refs(p)]


def _sections(schema: dict) -> list[tuple[str, dict]]:
    """(path in the file, section schema) from the top level down, in the file's order."""
    definitions, out, seen = schema.get("$defs", {}), [("(top level)", schema)], set()
    for path, section in out:
        for field, prop in section.get("properties", {}).items():
            for name in _refs(prop):
                if name not in seen:
                    seen.add(name)
                    where = field if path == "(top level)" else f"{path}.{field}"
                    out.append((where + ("[]" if prop.get("type") == "array" else ""), definitions[name]))
    return out


def _default(prop: dict, required: bool) -> str:
    if required:
        return "required"
    if "default" not in prop:
        return "empty"
    if isinstance(prop["default"], dict) and prop["default"] and "$ref" in json.dumps(prop):
        return "its fields' defaults"
    return f"`{json.dumps(prop['default'], ensure_ascii=False)}`"


def reference_markdown(kind: str) -> str:
    """The config reference of ``kind`` in Markdown, from its JSON Schema: one table per section (by its
    path in the file), a row per field (type, default, bounds, description with unit).

    Raises:
        KeyError: an unknown kind.
    """
    out = []
    for path, section in _sections(config_schema(kind)):
        out += [f"### `{path}`" if path != "(top level)" else "### The file", ""]
        out += [section.get("description", "").replace("\n", " "), ""]
        out += ["| field | type | default | bounds | meaning |", "|---|---|---|---|---|"]
        required = set(section.get("required", []))
        for field, prop in section.get("properties", {}).items():
            text = prop.get("description", "").replace("|", "\\|").replace("\n", " ")
            default = _default(prop, field in required)
            out.append(f"| `{field}` | {_type(prop)} | {default} | {_bounds(prop)} | {text} |")
        out.append("")
    return "\n".join(out)
