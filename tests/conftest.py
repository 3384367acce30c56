import json
import logging
import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("FE_BEAM_PROGRESS", "0")
# shared test helpers (tomlio, beam_cases, ...) importable from tests/ and its subfolders
sys.path.insert(0, str(Path(__file__).parent))

REFERENCE = Path(__file__).resolve().parents[1].parent / "shared" / "reference"


@pytest.fixture(autouse=True, scope="session")
def _quiet_jit():
    from fe_beam.cli import quiet_jit_logging

    quiet_jit_logging()
    logging.getLogger("UFL").setLevel(logging.WARNING)


def reference(name: str) -> dict:
    path = REFERENCE / name
    if not path.is_file():
        pytest.skip(f"{path} not available (tests read ../shared/reference/)")
    return json.loads(path.read_text())


@pytest.fixture(scope="session")
def mattiasson():
    return reference("elastica_tip_load.json")


@pytest.fixture(scope="session")
def frequencies():
    return reference("cantilever_frequencies.json")
