"""docs/limits.md states each limit with the constant that holds it: every
value in its table is the constant's value (so the page cannot drift)."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest


PAGE = (Path(__file__).resolve().parents[1] / "docs" / "limits.md").read_text()
ROWS = [line.split("|")[1:-1] for line in PAGE.splitlines() if line.startswith("| ") and "`drake_social." in line]


def _constant(dotted: str):
    module, name = dotted.rsplit(".", 1)
    return getattr(importlib.import_module(module), name)


def test_the_page_lists_the_limits():
    assert len(ROWS) >= 20


@pytest.mark.parametrize("row", ROWS, ids=lambda r: r[2].strip(" `"))
def test_each_stated_bound_is_its_constant(row):
    _, bound, constant, _ = (cell.strip() for cell in row)
    dut = float(re.search(r"[-+]?\d[\d.e+-]*", bound).group())
    assert dut == pytest.approx(float(_constant(constant.strip("`"))), rel=1e-15, abs=0)


def test_the_names_and_chunks_in_the_text_are_the_constants():
    study = importlib.import_module("drake_social.experiments.study")
    assert f"`{study.NAME_PATTERN}`" in PAGE
    text = " ".join(PAGE.split())  # the paragraph's line breaks as spaces
    assert f"at most {importlib.import_module('drake_social.cost.social').FIELD_CHUNK_ELEMENTS} (point" in text
    assert f"at most {importlib.import_module('drake_social.model.plant').ENVIRONMENT_PART} shapes" in text
    proximity, world = (importlib.import_module(f"drake_social.{m}") for m in ("people.proximity", "viz.world"))
    assert f"at most {proximity.DISTANCE_CHUNK_ELEMENTS} (sample, part" in text
    assert f"at most {world.MAP_PICTURE_CELLS} pixels along a side" in text
    assert f"at most {world.MAP_MAX_OUTLINES} box outlines" in text
