"""What every config section shares: strict sections (unknown fields refused, no NaN or inf), the
field-level problems validators report, per-joint values, the bounds of sizes and seeds, and how
paths in a config are resolved and a config is written back."""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Annotated, Optional, Union

import yaml
from pydantic import BaseModel, ConfigDict, Field
from pydantic.json_schema import SkipJsonSchema

PerJoint = Union[float, dict[str, float]]
#: A fraction in (0, 1).
Fraction = Annotated[float, Field(gt=0.0, lt=1.0)]

#: Largest number of harmonics N (the paper uses 5-10; the memory grows with N × grid instants).
MAX_HARMONICS = 100
#: Largest number of cost samples and of constraint-grid instants.
MAX_GRID = 20000
#: Largest number of instants of the fine re-check (constraint grid × check_refinement).
MAX_FINE = 1_000_000
#: Largest seed (numpy's generators take any; 32 bits is what other tools can repeat).
MAX_SEED = 2**32 - 1
#: A Dask scheduler address: ``[tcp:// or tls://]host:port`` (an IPv6 host in brackets).
SCHEDULER_ADDRESS = re.compile(r"^((tcp|tls)://)?(\[[0-9a-fA-F:]+\]|[\w.-]+):\d{1,5}$")
#: Largest number of local worker processes.
MAX_WORKERS = 256
#: v_c [rad/s] of the smooth sign tanh(q̇/v_c) of Coulomb friction, by default in every config that has
#: one (identify, simulate, the design's effect columns) and in a report that does not store its own.
COULOMB_VELOCITY = 0.01


class FieldProblem(ValueError):
    """A problem a validator finds with one field of a section or of another (``field`` dotted from
    the top of the file), reported under that field instead of the section's."""

    def __init__(self, field: str, problem: str):
        super().__init__(problem)
        self.field, self.problem = field, problem


class Section(BaseModel):
    """A config section: unknown fields are refused, numbers must be finite, and each field's
    docstring is its description in the JSON Schema and the generated config reference."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, use_attribute_docstrings=True)


class ConfigFile(Section):
    """A whole config file (optimize, identify): the file it was read from and its text, which the
    loader sets (neither is in the file)."""

    source_path: SkipJsonSchema[Optional[Path]] = Field(None, exclude=True)
    """The file it was read from (set by the loader, not in the file)."""
    source_text: SkipJsonSchema[str] = Field("", exclude=True)
    """The file's text (set by the loader)."""

    @property
    def folder(self) -> Optional[Path]:
        """The config file's folder, which relative paths in it are relative to (None without a file)."""
        return None if self.source_path is None else self.source_path.parent


def resolve_path(path: str, folder: Optional[Path]) -> Path:
    """``path`` relative to ``folder`` (absolute paths, and any path without a folder, kept as given);
    ``..`` is taken lexically while the folder does not exist yet (a config ``init`` is about to write)."""
    p = Path(path).expanduser()
    if p.is_absolute() or folder is None:
        return p
    return folder / p if folder.exists() else Path(os.path.normpath(folder / p))


def effective_yaml(config: BaseModel) -> str:
    """The validated config as YAML, every default filled in: what a run actually used."""
    return yaml.safe_dump(config.model_dump(mode="json"), sort_keys=False, allow_unicode=True)
