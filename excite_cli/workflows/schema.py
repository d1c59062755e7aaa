"""``schema``: the JSON Schema of each config kind, generated from the pydantic models (every field's
type, default, bounds and description with its unit), for editors that validate and complete YAML
(a ``# yaml-language-server: $schema=...`` line in the file) and for the config reference."""

from __future__ import annotations

import json
from pathlib import Path

from pydantic import BaseModel

from excite_cli.atomic import atomic_paths
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
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", **schema, "title": TITLES[kind]}


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
