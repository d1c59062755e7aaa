"""The documentation a user reads: no issue numbers or commit hashes outside the development page,
and the output page's Python loading block runs on files excite wrote."""

import importlib.util
import os
import re
from pathlib import Path

import yaml
from conftest import pendulum_config
from typer.testing import CliRunner

from excite_cli.cli import app

ROOT = Path(__file__).resolve().parent.parent
USER_PAGES = [ROOT / "README.md", *sorted(p for p in (ROOT / "docs").glob("*.md") if p.name != "development.md")]
#: Development history: "issue 41", "#41", "commit 9dfa958", a bare short hash "at 9dfa958".
HISTORY = re.compile(
    r"\b[Ii]ssues? #?\d+|(?<![\w-])#\d+\b|\bcommits? [0-9a-f]{7,40}\b|\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7}\b"
)


def test_user_pages_name_no_issue_numbers_or_commit_hashes():
    found = [
        f"{p.name}:{k}: {m.group()}"
        for p in USER_PAGES
        for k, line in enumerate(p.read_text().splitlines(), 1)
        for m in HISTORY.finditer(line)
    ]
    assert found == []


def test_the_history_pattern_finds_what_it_is_for():
    assert [m.group() for m in HISTORY.finditer("after issue 41 (commit 9dfa958, at e0df957; #12)")] == [
        "issue 41",
        "commit 9dfa958",
        "e0df957",
        "#12",
    ]
    assert not HISTORY.search("digest 06591cc39302, 1000000 samples, 2026-11-24, panda_joint7")


def test_the_output_page_loading_block_runs_on_what_excite_writes(tmp_path, monkeypatch):
    """A pendulum run under the guide's file names: optimize, simulate, identify (consistent fit, so
    the report has bodies), export; then the page's ```python block, as a user would paste it."""
    monkeypatch.chdir(tmp_path)
    runner = CliRunner()
    pendulum_config(tmp_path, iterations=2, changes={"output": str(tmp_path / "ur3.h5")})
    assert runner.invoke(app, ["optimize", "pendulum.yaml"]).exit_code == 0
    effects = {"sample_rate": 100.0, "periods": 2, "torque_noise": 0.01, "seed": 1, "effects": {"viscous": {"*": 0.2}}}
    (tmp_path / "effects.yaml").write_text(yaml.safe_dump(effects))
    assert runner.invoke(app, ["simulate", "ur3.h5", "effects.yaml", "-o", "runs"]).exit_code == 0
    identify = {
        "robot": {"urdf": "pendulum.urdf", "active_joints": ["hinge"]},
        "data": {"runs": [{"file": "runs/run_1.csv"}], "columns": {"q": ["q_hinge"], "tau": ["tau_hinge"]}},
    }
    (tmp_path / "id.yaml").write_text(yaml.safe_dump(identify))
    result = runner.invoke(app, ["identify", "id.yaml", "-o", "ur3_identified.h5", "--urdf-out", "id.urdf"])
    assert result.exit_code == 0, result.output
    assert (
        runner.invoke(app, ["export", "ur3.h5", "-k", "2", "--rate", "100", "-o", "ur3_iteration2.csv"]).exit_code == 0
    )
    [block] = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "output.md").read_text(), flags=re.S)
    names: dict = {}
    exec(compile(block, "output.md", "exec"), names)
    assert list(names["table"]["iteration"]) == [1, 2]
    assert names["joints"] == ["hinge"] and names["alpha"].shape == (1, 7)
    assert "viscous" in names["effects"]["effect"].tolist() and set(names["effects"]["joint"]) == {"hinge"}
    assert names["bodies"]["body"].tolist()[0] and names["bodies"]["com"].iloc[0].shape == (3,)
    assert list(names["base"].index) and "tau_hinge_Nm" in names["played"].columns


def test_the_figures_page_shows_a_plot_of_each_plotted_table_drawn_from_it(tmp_path):
    """docs/figure_plots.py draws its plots from the tables of docs/figures.md (so they cannot
    disagree); each plot it draws is on the page and committed."""
    spec = importlib.util.spec_from_file_location("figure_plots", ROOT / "docs" / "figure_plots.py")
    plots = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(plots)
    drawn = plots.main(tmp_path)
    page = (ROOT / "docs" / "figures.md").read_text()
    assert len(drawn) >= 4
    for path in drawn:
        assert path.stat().st_size > 10_000
        assert f"](images/{path.name})" in page and (ROOT / "docs" / "images" / path.name).is_file()
    rows = plots.table("Random feasible motions + greedy selection", page)
    assert rows[0][0] == "motion index" and plots.number(rows[1][2]) == 644.7


def test_the_api_page_example_runs_as_written(tmp_path, monkeypatch):
    """docs/api.md's ```python block, pasted into a notebook started in the repository's folder."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "configs").symlink_to(ROOT / "configs")
    [block] = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "api.md").read_text(), flags=re.S)
    names: dict = {}
    exec(compile(block, "api.md", "exec"), names)
    assert [r.index for r in names["run"].results] == [1]
    assert names["export"].rate == 500.0 and names["path"].is_file()


#: A Markdown table that did not render: a line of a paragraph that starts with a pipe and holds three.
RAW_TABLE = re.compile(r"(?:<p>|\n)\|[^<\n]*\|[^<\n]*\|")
#: A list that did not render: a line of a paragraph that starts with "- " (no blank line before it).
RAW_LIST = re.compile(r"<p>(?:(?!</p>).)*?\n[-*] ", re.S)


def test_the_built_site_has_no_raw_table_pipes_or_list_dashes(tmp_path):
    """Every page built as ``make docs`` builds it; no table or list is left unrendered (one that
    follows a paragraph line without a blank line shows as pipes or dashes in the paragraph)."""
    import subprocess
    import sys

    site = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet", "-d", str(site)],
        cwd=ROOT,
        check=True,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
    )
    raw = [
        f"{page.relative_to(site)}: {m.group()[:80]}"
        for page in site.rglob("*.html")
        for pattern in (RAW_TABLE, RAW_LIST)
        for m in pattern.finditer(page.read_text())
    ]
    assert raw == []
    assert RAW_LIST.search("<p>it assumed:\n- joints</p>") and not RAW_LIST.search("<p>a - b</p><ul><li>x</li></ul>")
    assert RAW_TABLE.search("<p>| a | b |\n| 1 | 2 |</p>") and not RAW_TABLE.search("<td>a</td><td>b | c</td>")


#: What a development log says and a page of current results does not.
DEVELOPMENT_LOG = re.compile(
    r"\b(before this work|the earlier version|the code (of today|before)|re-measured|\d{4}-\d{2}-\d{2})\b", re.I
)


def test_the_figures_page_holds_current_results_only():
    """History (before/after, earlier versions, dated rows) is on the measurement history page; every
    plot on the figures page has a caption (an italic paragraph below it)."""
    page = (ROOT / "docs" / "figures.md").read_text()
    assert [m.group() for m in DEVELOPMENT_LOG.finditer(page)] == []
    assert DEVELOPMENT_LOG.search("re-measured with the code of today (2026-11-25)")
    images = re.findall(r"^!\[.*\]\(images/.*\)\n\n(.*)$", page, flags=re.M)
    assert len(images) == page.count("](images/") and all(line.startswith("*") for line in images)


def test_every_section_of_how_it_works_cited_elsewhere_is_a_heading_its_links_reach():
    """Other pages cite How it works by section: each citation is a link, and each link's anchor is
    the slug mkdocs gives one of the page's headings (the build checks links to pages, not anchors)."""
    from markdown.extensions.toc import slugify

    page = (ROOT / "docs" / "how-it-works.md").read_text()
    anchors = {slugify(title, "-") for title in re.findall(r"^#+ (.+)$", page, flags=re.M)}
    pages = [ROOT / "README.md", *sorted(p for p in (ROOT / "docs").glob("*.md") if p.name != "how-it-works.md")]
    texts = {p.name: p.read_text() for p in pages}
    linked = {(name, a) for name, text in texts.items() for a in re.findall(r"how-it-works\.md#([\w-]+)", text)}
    cited = [(name, m.group()) for name, text in texts.items() for m in re.finditer(r'(?<!\[)[Hh]ow it works, "', text)]
    assert cited == []  # every citation by section is a link
    assert len({a for _, a in linked}) >= 8
    assert sorted((name, a) for name, a in linked if a not in anchors) == []


def test_the_readme_and_index_quote_the_figures_page_and_state_no_test_count():
    """Times of `make optimize` and the other ready problems ("43 s of iterations", "50 s wall") and the
    README's Table I are the figures page's; a count of tests would be stale at the next test."""
    figures = (ROOT / "docs" / "figures.md").read_text()
    pages = {page.name: page.read_text() for page in (ROOT / "README.md", ROOT / "docs" / "index.md")}
    quoted = {(name, t) for name, text in pages.items() for t in re.findall(r"\b\d+ s (?:of iterations|wall)", text)}
    assert ("README.md", "43 s of iterations") in quoted  # the pattern sees them
    assert {(name, t) for name, t in quoted if t not in figures} == set()
    rows = re.findall(r"^\| (\d) \| ([\d.]+) \| (\d+) \| ([\d.]+) \| ([\d.]+ mm) \|", pages["README.md"], re.M)
    assert len(rows) == 3
    for k, *numbers in rows:
        [row] = [line for line in figures.splitlines() if line.startswith(f"| {k} | ")][:1]
        assert all(f"| {x} |" in row for x in numbers), (row, numbers)
    for page in ("README.md", "docs/index.md", "docs/development.md"):
        assert not re.search(r"\b\d+ tests\b", (ROOT / page).read_text()), page
