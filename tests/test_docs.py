"""The documentation's cheap invariants: the README is a short quick start, and every command
of the CLI and every configuration table has a generated page (docs/_ext). The site itself is
built by `./bootstrap docs` (CI), not here."""

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXT = ROOT / "docs" / "_ext"


def test_readme_is_a_quick_start():
    text = (ROOT / "README.md").read_text()
    assert len(text) < 12_000
    blocks = text.split("```")
    assert len(blocks) > 2
    first = blocks[1].splitlines()
    assert first[0].strip() == "bash"
    assert [line.split("#")[0].strip() for line in first[1:3]] == [
        "./bootstrap demo", "./bootstrap test"]
    for needed in ("docs/figure2_a_inextensible.png", "fe_beam.run(", "fe-beam static",
                   "./bootstrap docs"):
        assert needed in text


@pytest.fixture(scope="module")
def docs_ext():
    if importlib.util.find_spec("sphinx") is None:
        pytest.skip("sphinx is not installed (pip install -e .[docs])")
    sys.path.insert(0, str(EXT))
    try:
        import fe_beam_docs
        import fe_beam_reference
    finally:
        sys.path.remove(str(EXT))
    return fe_beam_reference, fe_beam_docs


def test_every_command_has_a_page(docs_ext, tmp_path):
    reference, generator = docs_ext
    from fe_beam.cli import COMMANDS

    listed = [name for name, _, _ in reference.commands()]
    assert listed == list(COMMANDS)
    common = reference.common_arguments()
    tables = reference.tables()
    readers = reference.command_tables()
    for name, help_text, extra in reference.commands():
        assert help_text
        page = generator.command_page(name, help_text, extra, common, readers.get(name), tables)
        assert page.count(f"# fe-beam {name}") == 1
        assert f"fe-beam {name} CONFIG.toml" in page
        for argument in extra:
            assert argument["flags"] in page
        assert (ROOT / "docs" / "notes" / "commands" / f"{name}.md").exists(), name
    assert "--data" in generator.command_page(
        "calibrate", "x", dict((n, e) for n, _, e in reference.commands())["calibrate"], common,
        readers.get("calibrate"), tables)


def test_config_reference_lists_every_key(docs_ext):
    reference, generator = docs_ext
    from fe_beam.config.schema import SCHEMA

    tables = reference.tables()
    assert set(SCHEMA) <= set(tables)
    page = generator.config_reference(tables, reference.command_tables(),
                                      reference.section_dimensions())
    for table, keys in tables.items():
        assert f"({generator.table_target(table)})=" in page
        for key in keys:
            assert f"`{key}`" in page, (table, key)
    for key, entry in SCHEMA["solver"].items():
        assert entry.doc.replace("|", "\\|") in page, key
