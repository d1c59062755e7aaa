"""`excite schema`: the committed schema files are what it writes (so they cannot drift from the
models), every shipped config names its kind's schema for editors, and existing files are kept."""

import json

from conftest import CONFIGS, TESTS, assert_refused
from typer.testing import CliRunner

from excite_cli.cli import app
from excite_cli.workflows.schema import KINDS, config_schema, reference_markdown


def test_the_committed_schemas_are_the_generated_ones_and_the_configs_name_them():
    for kind in KINDS:
        committed = json.loads((CONFIGS / "schema" / f"{kind}.schema.json").read_text())
        assert committed == config_schema(kind), f"run: excite schema -o configs/schema --force ({kind})"
    for config in CONFIGS.glob("*.yaml"):
        kind = "identify" if "identify" in config.name else "optimize"
        assert config.read_text().splitlines()[0] == f"# yaml-language-server: $schema=schema/{kind}.schema.json"
    effects = TESTS.parent / "data" / "panda_simulated" / "effects.yaml"
    assert effects.read_text().startswith("# yaml-language-server: $schema=../../configs/schema/effects.schema.json")


def test_the_command_writes_one_schema_per_kind_and_keeps_existing_files(tmp_path):
    result = CliRunner().invoke(app, ["schema", "-o", str(tmp_path / "s")])
    assert result.exit_code == 0, result.output
    written = {p.name: json.loads(p.read_text()) for p in (tmp_path / "s").iterdir()}
    assert set(written) == {f"{kind}.schema.json" for kind in KINDS}
    optimize = written["optimize.schema.json"]
    assert optimize["required"] == ["robot", "limits"] and optimize["additionalProperties"] is False
    frequency = optimize["$defs"]["TrajectoryConfig"]["properties"]["base_frequency"]
    assert "[rad/s]" in frequency["description"] and frequency["exclusiveMinimum"] == 0.0
    assert_refused(tmp_path, ["schema", "-o", str(tmp_path / "s")], "optimize.schema.json exists")


def test_the_config_reference_has_a_row_for_every_field_of_every_section():
    for kind in KINDS:
        schema, text = config_schema(kind), reference_markdown(kind)
        for section in [schema, *schema["$defs"].values()]:
            for field, prop in section["properties"].items():
                rows = [line for line in text.splitlines() if line.startswith(f"| `{field}` |")]
                assert any(prop["description"].replace("|", "\\|") in row for row in rows), (kind, field)
    optimize = reference_markdown("optimize")
    assert "### `constraints.environment.shapes[]`" in optimize and "| `base_frequency` | number | `0.785" in optimize
