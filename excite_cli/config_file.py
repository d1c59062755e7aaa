"""Config files read: YAML read safely and validated against the schema of :mod:`excite_cli.config`,
command-line overrides validated the same way.

YAML is read with PyYAML's safe loader (no Python tags), keys given twice refused, merge keys
(``<<: *defaults``) accepted, and hostile files refused with one line instead of a crash or a
memory blow-up: bigger than :data:`MAX_BYTES`, nested deeper than :data:`MAX_DEPTH`, or aliases
that expand to more than :data:`MAX_VALUES` values (a "billion laughs" file)."""

from __future__ import annotations

import functools
import reprlib
from enum import StrEnum
from pathlib import Path

import yaml
from pydantic import BaseModel, ValidationError

from excite_cli.config import ConfigFile, FieldProblem, Problem
from excite_cli.errors import NO_VALUE, ExciteError
from excite_cli.h5 import open_h5
from excite_cli.inputs import input_file

#: Largest YAML file read [bytes]; a config or an effects file is a few kB.
MAX_BYTES = 10_000_000
#: Deepest nesting of mappings and lists.
MAX_DEPTH = 64
#: Most values (scalars, mappings, lists) once every alias is expanded.
MAX_VALUES = 1_000_000

_MERGE = "tag:yaml.org,2002:merge"


class _Loader(yaml.SafeLoader):
    """The safe loader with a nesting bound and duplicate keys refused (YAML lets the last one win)."""

    depth = 0

    def compose_node(self, parent, index):
        self.depth += 1
        try:
            if self.depth > MAX_DEPTH:
                mark = self.peek_event().start_mark
                raise yaml.composer.ComposerError(None, None, f"nested more than {MAX_DEPTH} levels deep", mark)
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            if key_node.tag == _MERGE:
                continue
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(None, None, f"duplicate key '{key}'", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


def _expanded_size(node: yaml.Node, sizes: dict[int, int]) -> int:
    """Values in ``node`` with every alias expanded (aliases share their node: each is counted once
    and reused), stopping early above :data:`MAX_VALUES`; a node that contains itself counts as
    more."""
    if id(node) in sizes:
        return sizes[id(node)]
    sizes[id(node)] = MAX_VALUES + 1  # a node that contains itself expands without end
    total = 1
    if isinstance(node, yaml.SequenceNode):
        children = node.value
    elif isinstance(node, yaml.MappingNode):
        children = [child for pair in node.value for child in pair]
    else:
        children = []
    for child in children:
        total += _expanded_size(child, sizes)
        if total > MAX_VALUES:
            break
    sizes[id(node)] = total
    return total


def parse_yaml(text: str, where: str, field: str = "config") -> object:
    """The value of the YAML document ``text`` (``where``: its file, for the message).

    Raises:
        ExciteError: malformed YAML or a character YAML does not allow (with its line and column), nesting deeper than
            :data:`MAX_DEPTH`, aliases expanding beyond :data:`MAX_VALUES` values.
    """
    loader = None
    try:
        loader = _Loader(text)  # its reader refuses characters YAML does not allow (a NUL byte) here
        node = loader.get_single_node()
        if node is not None and _expanded_size(node, {}) > MAX_VALUES:
            raise ExciteError(
                field, f"{where}: its aliases expand to more than {MAX_VALUES:,} values", where, "a config file"
            )
        return None if node is None else loader.construct_document(node)
    except yaml.reader.ReaderError as exc:
        line = text.count("\n", 0, exc.position) + 1
        column = exc.position - (text.rfind("\n", 0, exc.position) + 1) + 1
        code = exc.character if isinstance(exc.character, int) else ord(exc.character)
        raise ExciteError(
            field,
            f"{where}: malformed YAML at line {line}, column {column}: character #x{code:04x} is not allowed",
            where,
        ) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ExciteError(field, f"{where}: malformed YAML{at}: {getattr(exc, 'problem', exc)}", where) from None
    finally:
        if loader is not None:
            loader.dispose()


def read_yaml(path: Path, field: str = "config") -> tuple[object, str]:
    """The value and the text of the YAML file ``path``.

    Raises:
        FileNotFound: no file at ``path``.
        ExciteError: a folder, FIFO or device (:func:`~excite_cli.inputs.input_file`), not a UTF-8
            text file, bigger than :data:`MAX_BYTES`, unreadable, or refused by :func:`parse_yaml`.
    """
    path = input_file(path, field, f"{field} file")
    try:
        if path.stat().st_size > MAX_BYTES:
            raise ExciteError(field, f"{path} is larger than {MAX_BYTES // 1_000_000} MB", path, "a YAML config")
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ExciteError(field, f"{path} is not a text (UTF-8) file", path, "a YAML config") from None
    except OSError as exc:
        raise ExciteError(field, f"cannot read {path}: {exc.strerror}", path) from None
    return parse_yaml(text, str(path), field), text


def _validation_error(path: Path | None, error: ValidationError) -> ExciteError:
    first = error.errors()[0]
    field = ".".join(str(part) for part in first["loc"]) or "(top level)"
    message = first["msg"].removeprefix("Value error, ")
    value, cause = first.get("input"), first.get("ctx", {}).get("error")
    if isinstance(cause, FieldProblem):
        field, message, value = cause.field, cause.problem, NO_VALUE
    elif first["type"] == "missing":
        message = "is required but missing"
    elif first["type"] == "extra_forbidden":
        message = "is not a known field (check its spelling; see docs/config-reference.md or excite schema)"
    else:
        message = f"{message} (got {reprlib.repr(first.get('input'))})"
    more = len(error.errors()) - 1
    suffix = f" (+{more} more problem{'s' if more > 1 else ''})" if more else ""
    return ExciteError(field, f"{message}{suffix}", value, source=path)


def load_problem(path: str | Path, kind: type[BaseModel] = Problem, field: str = "config") -> BaseModel:
    """Read and validate a YAML file as a :class:`Problem` (or another config ``kind``).

    Args:
        path: the YAML file.
        kind: :class:`Problem`, :class:`IdentifyProblem` or :class:`SimulationConfig`.
        field: the argument that named the file (``config``, ``effects``), for the messages.

    Returns:
        The validated config, with ``source_path`` and ``source_text`` set where it has them.

    Raises:
        ExciteError: missing file, malformed YAML or an invalid field; the message names the field.
    """
    path = Path(path)
    raw, text = read_yaml(path, field)
    if not isinstance(raw, dict):
        raise ExciteError(
            field,
            f"{path}: {'empty file' if raw is None else 'not a mapping'}",
            path,
            "a mapping of sections (see docs/config-reference.md or excite schema)",
        )
    try:
        problem = kind.model_validate(raw)
    except ValidationError as exc:
        raise _validation_error(path, exc) from None
    if hasattr(problem, "source_path"):
        problem.source_path = path.resolve()
        problem.source_text = text
    return problem


def with_overrides(config: BaseModel, overrides: dict[str, object]) -> BaseModel:
    """A validated copy of ``config`` with dotted fields replaced (command-line options), e.g.
    ``{"sequence.iterations": 2, "optimizer.seed": 5}``; None values are left out. The original is
    not changed, so what ran is the copy (stored as the effective config).

    Raises:
        ExciteError: an override is not valid for its field (the error's field is the dotted field,
            which the command line words as the option that set it).
    """
    data = config.model_dump()
    for dotted, value in overrides.items():
        if value is None:
            continue
        *parents, last = dotted.split(".")
        functools.reduce(dict.__getitem__, parents, data)[last] = value
    try:
        copy = type(config).model_validate(data)
    except ValidationError as error:
        raise _validation_error(None, error) from None
    if isinstance(config, ConfigFile):
        copy.source_path, copy.source_text = config.source_path, config.source_text
    return copy


def result_problem(path: Path) -> Problem:
    """The optimize config an excite result stores (its attribute ``config``), relative paths resolved
    from the config's original place (the attribute ``config_path``).

    Raises:
        ExciteError: missing or unreadable file, or no valid stored config (not an excite result).
    """
    with open_h5(path) as f:
        if "config" not in f.attrs or "iterations" not in f:
            raise ExciteError(
                "result", f"{path} is not an excite optimize result (no stored config or /iterations)", path
            )
        text, origin = str(f.attrs["config"]), str(f.attrs.get("config_path", ""))
    try:
        problem = Problem.model_validate(parse_yaml(text, str(path), "result"))
    except (ExciteError, ValidationError):
        raise ExciteError(
            "result",
            f"the stored config of {path} is not a valid optimize problem (not an excite optimize result?)",
            path,
        ) from None
    problem.source_path = Path(origin) if origin else None
    problem.source_text = text
    return problem


def drafted_problem(config: dict, target: Path) -> Problem:
    """A drafted optimize config ``config`` (as YAML would give it) validated as the file ``target``
    it will be written to (relative paths are beside it).

    Raises:
        pydantic.ValidationError: a draft that is not a valid config (a drafting bug, not the user's).
    """
    problem = Problem.model_validate(config)
    problem.source_path = Path(target).resolve()
    return problem


class ConfigKind(StrEnum):
    """The configs the commands read, each validated by its own schema."""

    OPTIMIZE = "optimize"
    IDENTIFY = "identify"
    EFFECTS = "effects"

    def schema(self) -> type[BaseModel]:
        """:class:`Problem`, :class:`~excite_cli.identification.config.IdentifyProblem` or
        :class:`~excite_cli.identification.simulation_config.SimulationConfig`."""
        from excite_cli.identification.config import IdentifyProblem
        from excite_cli.identification.simulation_config import SimulationConfig

        return {
            ConfigKind.OPTIMIZE: Problem,
            ConfigKind.IDENTIFY: IdentifyProblem,
            ConfigKind.EFFECTS: SimulationConfig,
        }[self]

    @property
    def field(self) -> str:
        """The argument that names such a file, for the messages: ``effects`` or ``config``."""
        return "effects" if self is ConfigKind.EFFECTS else "config"


def load_config(
    path: str | Path, overrides: dict[str, object] | None = None, kind: ConfigKind = ConfigKind.OPTIMIZE
) -> BaseModel:
    """The config of ``kind`` at ``path`` (:meth:`ConfigKind.schema`), validated, with the command
    line's ``overrides`` (:func:`with_overrides`; none: the file as read).

    Raises:
        ExciteError: as :func:`load_problem` and :func:`with_overrides`.
    """
    problem = load_problem(path, kind.schema(), kind.field)
    return with_overrides(problem, overrides) if overrides else problem
