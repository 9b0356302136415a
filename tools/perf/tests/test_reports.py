"""The kernel lab's committed reports (tools/perf/results/*.md) carry no unfilled template text: a report is
generated from its script's NOTES and measurements, and a placeholder left in the NOTES reaches
users as is (session 15's RENDER.md shipped one)."""
import re
from pathlib import Path

import pytest

RESULTS = Path(__file__).resolve().parents[1] / "results"
REPORTS = sorted(RESULTS.glob("*.md"))
# Tokens that mark text meant to be replaced before a report is committed.
UNFILLED = re.compile(r"\b[A-Z]+_PLACEHOLDER\b|\bPLACEHOLDER\b|\bTODO\b|\bXXX\b|\{[a-z_]+\}")


def test_reports_exist():
    names = {p.name for p in REPORTS}
    assert {"RESULTS.md", "RESULTS_zen4.md"} <= names


@pytest.mark.parametrize("path", REPORTS, ids=lambda p: p.name)
def test_report_has_no_unfilled_template_text(path):
    text = path.read_text(encoding="utf-8")
    hits = [(i + 1, line.strip()) for i, line in enumerate(text.splitlines()) if UNFILLED.search(line)]
    assert not hits, f"{path.name}: unfilled template text at lines {hits[:5]}"
