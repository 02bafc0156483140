"""One set of words in the docs: the unit W, the README's length and its status rows, checked against the code.

W (= BL) is the body width of the robot in use: the glossary defines it once with each preset's width in
centimetres, as ``smarticle_common.facts`` gives them; every other page that writes "W = ... cm" uses one of
those widths; no page calls W the body length (the paper's own "body length" is quoted as the paper's). The
README stays a front page (at most 150 lines), and every figure in its status table is a figure of the page
its row links to, so a changed result cannot leave the front page behind.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from smarticle_common.facts import PRESETS

ROOT = Path(__file__).resolve().parents[1]
README_MAX_LINES = 150
#: Pages that describe the present (history and the archive are kept as measured).
LIVE_PAGES = [ROOT / 'README.md', *(p for p in sorted((ROOT / 'docs').rglob('*.md')) if 'history' not in p.parts)]
#: "W = 5.4 cm", "BL = W = 0.054 m", "W = BL = 6.5 cm", "W (= BL = 5.4 cm)": the value given for the unit
#: (not a multiple of it: "1.6 BL = 8.64 cm").
UNIT_VALUE = re.compile(r'(?<![\d.] )\b(?:W|BL)\s*\(?=\s*(?:(?:W|BL)\s*=\s*)?(\d+(?:\.\d+)?)\s*(cm|m)\b')
NUMBER = re.compile(r'(?<![\w.])\d[\d,]*(?:\.\d+)?')


def widths_cm() -> set[str]:
    """Each preset's body width in cm, as the docs write it (one decimal)."""
    return {f'{spec.body_width * 100:.1f}' for spec in PRESETS.values()}


def test_readme_is_a_front_page() -> None:
    lines = (ROOT / 'README.md').read_text(encoding='utf-8').splitlines()
    assert len(lines) <= README_MAX_LINES, f'README.md has {len(lines)} lines, at most {README_MAX_LINES}: link to docs'


def test_the_glossary_defines_w_as_the_body_width_of_each_preset() -> None:
    glossary = (ROOT / 'docs' / 'glossary.md').read_text(encoding='utf-8')
    rows = [line for line in glossary.splitlines() if re.match(r'^\|\s*(W, BL|BL, W)\s*\|', line)]
    assert len(rows) == 1, 'the glossary has no single row defining W'
    assert 'body width' in rows[0]
    for cm in widths_cm():
        assert f'{cm} cm' in rows[0], f'the glossary row of W does not give the {cm} cm of a preset'


@pytest.mark.parametrize('page', LIVE_PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_value_given_for_w_is_a_presets_body_width(page: Path) -> None:
    text = page.read_text(encoding='utf-8')
    allowed = widths_cm()
    wrong = []
    for match in UNIT_VALUE.finditer(text):
        value, unit = float(match.group(1)), match.group(2)
        cm = f'{value * (100 if unit == "m" else 1):.1f}'
        if cm not in allowed:
            wrong.append(match.group(0))
    assert not wrong, f'{page.name}: W given as {wrong}, not a preset body width ({sorted(allowed)} cm)'


@pytest.mark.parametrize('page', LIVE_PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_page_calls_w_the_body_length(page: Path) -> None:
    text = page.read_text(encoding='utf-8')
    found = [text[max(0, m.start() - 40):m.end()] for m in re.finditer(r'body lengths?\b', text, re.IGNORECASE)
             if 'paper' not in text[max(0, m.start() - 40):m.start()]]
    assert not found, f'{page.name} calls the unit the body length (W is the body width): {found}'


def status_rows() -> list[tuple[str, str, Path]]:
    """(what, figure, linked page) of each row of the README's status table."""
    readme = (ROOT / 'README.md').read_text(encoding='utf-8')
    section = readme.split('## Where it stands', 1)[1].split('\n## ', 1)[0]
    rows = []
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip('|').split('|')]
        if len(cells) != 3 or cells[0] in ('what', '---'):
            continue
        target = re.search(r'\]\(([^)#]+)', cells[2])
        assert target, f'status row without a link: {line}'
        rows.append((cells[0], cells[1], ROOT / target.group(1)))
    return rows


def test_the_readme_has_a_status_table() -> None:
    assert len(status_rows()) >= 10


@pytest.mark.parametrize('what, figure, page', status_rows(), ids=[r[0][:40] for r in status_rows()])
def test_every_status_figure_is_on_the_page_its_row_links(what: str, figure: str, page: Path) -> None:
    """Each number of a row's figure is a number of its linked page (rounded to the row's digits)."""
    on_page = set(NUMBER.findall(page.read_text(encoding='utf-8')))
    values = []
    for text in on_page:
        try:
            values.append(float(text.replace(',', '')))
        except ValueError:
            continue
    missing = []
    for text in NUMBER.findall(figure):
        if text in on_page:
            continue
        digits = len(text.split('.')[1]) if '.' in text else 0
        wanted = float(text.replace(',', ''))
        if not any(round(v, digits) == wanted for v in values):
            missing.append(text)
    assert not missing, f'README status row {what!r}: {missing} not on {page.relative_to(ROOT)}'
