"""Every field of every config kind carries its description in the model itself (what the JSON
Schema and the config reference show), with a unit in brackets wherever it holds a number ([1] for a
ratio)."""

import typing

import pytest
from pydantic import BaseModel

from excite_cli.config.base import Section
from excite_cli.config.constraints import ConstraintsConfig
from excite_cli.config.problem import Problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.simulation_config import SimulationConfig

KINDS = {"optimize": Problem, "identify": IdentifyProblem, "effects": SimulationConfig}


def _sections(model: type[BaseModel], seen: dict) -> dict:
    """{name: model} of ``model`` and every section it holds, however nested (lists, dicts, unions)."""
    seen[model.__name__] = model
    for info in model.model_fields.values():
        todo = [info.annotation]
        while todo:
            t = todo.pop()
            if isinstance(t, type) and issubclass(t, BaseModel) and t.__name__ not in seen:
                _sections(t, seen)
            todo.extend(typing.get_args(t))
    return seen


def _holds_a_number(annotation) -> bool:
    todo, found = [annotation], False
    while todo:
        t = todo.pop()
        found |= t is float
        todo.extend(typing.get_args(t))
    return found


@pytest.mark.parametrize("kind", list(KINDS))
def test_every_field_has_a_description_and_numbers_a_unit(kind):
    sections = _sections(KINDS[kind], {})
    assert ConstraintsConfig.__name__ in sections or kind != "optimize"
    missing, unitless = [], []
    for name, model in sections.items():
        assert issubclass(model, Section), name  # strict, with attribute docstrings
        for field, info in model.model_fields.items():
            if info.exclude:  # set by the loader, not in the file
                continue
            if not (info.description or "").strip():
                missing.append(f"{name}.{field}")
            elif _holds_a_number(info.annotation) and "[" not in info.description:
                unitless.append(f"{name}.{field}")
    assert missing == [] and unitless == []


def test_a_field_without_a_description_would_be_found():
    class Bare(Section):
        speed: float = 1.0

    class Unitless(Section):
        speed: float = 1.0
        """How fast."""

    class Holder(Section):
        bare: Bare
        unitless: Unitless

    sections = _sections(Holder, {})
    assert not sections["Bare"].model_fields["speed"].description
    assert _holds_a_number(sections["Unitless"].model_fields["speed"].annotation)
    assert _holds_a_number(Problem.model_fields["limits"].annotation.model_fields["velocity"].annotation)
