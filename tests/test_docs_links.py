"""The documentation's links and commands, checked.

Every relative link in README.md and docs/**/*.md must name a file or folder of the repository, and a link
with an ``#anchor`` into a Markdown page must name one of that page's headings, slugged as GitHub slugs
them. Every console script the README names (a ``smarticle-...`` word in a code span or block) must be an
entry point of some package's setup.py, so a renamed command cannot leave the front page behind.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

FENCE = re.compile(r'^\s*(```|~~~)')
HEADING = re.compile(r'^(#{1,6})\s+(.*?)\s*#*\s*$')
CODE_SPAN = re.compile(r'(`+)(.+?)\1')
#: The target of an inline link or image: ``](target)`` or ``](target "title")``.
LINK_TARGET = re.compile(r'\]\(\s*<?([^)\s>]+)>?(?:\s+"[^"]*")?\s*\)')
#: A reference definition: ``[name]: target``.
REFERENCE = re.compile(r'^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+"[^"]*")?\s*$')
HTML_ANCHOR = re.compile(r'<a\s+(?:name|id)="([^"]+)"', re.IGNORECASE)
SCRIPT_WORD = re.compile(r'(?<![\w-])(smarticle-[a-z0-9]+(?:-[a-z0-9]+)*)')
ENTRY_POINT = re.compile(r'^\s*([A-Za-z0-9_.-]+)\s*=\s*[A-Za-z0-9_.]+:[A-Za-z0-9_.]+\s*$')


def doc_pages(root: Path = ROOT) -> list[Path]:
    """README.md and every Markdown page under docs/."""
    return [root / 'README.md', *sorted((root / 'docs').rglob('*.md'))]


def prose_lines(text: str) -> list[tuple[int, str]]:
    """(line number, line) of the lines outside fenced code blocks."""
    out, fenced = [], False
    for number, line in enumerate(text.splitlines(), start=1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            out.append((number, line))
    return out


def github_slug(heading: str) -> str:
    """The anchor GitHub gives a heading: its rendered text lower-cased, punctuation dropped, spaces to '-'."""
    text = re.sub(r'!?\[([^\]]*)\]\([^)]*\)', r'\1', heading)  # links and images: their text
    text = re.sub(r'<[^>]+>', '', text)                           # inline HTML
    text = text.replace('`', '')
    text = re.sub(r'(\*\*|__|\*|~~)', '', text)
    text = text.strip().lower()
    text = re.sub(r'[^\w\- ]', '', text)
    return text.replace(' ', '-')


def anchors(page: Path) -> set[str]:
    """Every anchor of a Markdown page: its headings' slugs (duplicates numbered -1, -2, ...) and HTML anchors."""
    seen: dict[str, int] = {}
    found: set[str] = set()
    for _, line in prose_lines(page.read_text(encoding='utf-8')):
        match = HEADING.match(line)
        if match:
            base = github_slug(match.group(2))
            count = seen.get(base, 0)
            found.add(base if count == 0 else f'{base}-{count}')
            seen[base] = count + 1
        found.update(HTML_ANCHOR.findall(line))
    return found


def link_targets(page: Path) -> list[tuple[int, str]]:
    """(line number, target) of every link and image of a page, outside code blocks and code spans."""
    targets = []
    for number, line in prose_lines(page.read_text(encoding='utf-8')):
        reference = REFERENCE.match(line)
        if reference:
            targets.append((number, reference.group(1)))
            continue
        for target in LINK_TARGET.findall(CODE_SPAN.sub('', line)):
            targets.append((number, target))
    return targets


def broken_links(page: Path, root: Path = ROOT) -> list[str]:
    """Each relative link of ``page`` that names no file, or an anchor that is not a heading of its page."""
    problems = []
    for number, target in link_targets(page):
        if re.match(r'^[a-zA-Z][a-zA-Z0-9+.-]*:', target):   # http:, https:, mailto:
            continue
        path_part, _, anchor = target.partition('#')
        resolved = (page.parent / path_part).resolve() if path_part else page
        where = f'{page.relative_to(root)}:{number}: {target}'
        if not resolved.exists():
            problems.append(f'{where}: no such file')
            continue
        if not resolved.is_relative_to(root):
            problems.append(f'{where}: outside the repository')
            continue
        if anchor and resolved.suffix == '.md' and anchor not in anchors(resolved):
            problems.append(f'{where}: no heading with anchor #{anchor} in {resolved.relative_to(root)}')
    return problems


def console_scripts(root: Path = ROOT) -> set[str]:
    """The console-script names of every package's setup.py (``name = module:function`` strings)."""
    names = set()
    for setup in root.rglob('setup.py'):
        if {'.venv', 'build', 'install'} & set(setup.relative_to(root).parts):
            continue
        for node in ast.walk(ast.parse(setup.read_text(encoding='utf-8'))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                match = ENTRY_POINT.match(node.value)
                if match:
                    names.add(match.group(1))
    return names


def named_scripts(text: str) -> set[str]:
    """The ``smarticle-...`` words of a page's code blocks and code spans."""
    code, fenced = [], False
    for line in text.splitlines():
        if FENCE.match(line):
            fenced = not fenced
            continue
        if fenced:
            code.append(line)
        else:
            code.extend(match.group(2) for match in CODE_SPAN.finditer(line))
    return {word for chunk in code for word in SCRIPT_WORD.findall(chunk)}


@pytest.mark.parametrize('page', doc_pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_resolves(page: Path) -> None:
    assert broken_links(page) == []


def test_every_console_script_the_readme_names_is_an_entry_point() -> None:
    named = named_scripts((ROOT / 'README.md').read_text(encoding='utf-8'))
    assert named, 'the README names no console script: the pattern no longer matches its commands'
    assert sorted(named - console_scripts()) == []


def test_github_slugs() -> None:
    assert github_slug('P5: alpha_max sweep') == 'p5-alpha_max-sweep'
    assert github_slug("The authors' Hertzian contact between robots (MuJoCo)") == (
        'the-authors-hertzian-contact-between-robots-mujoco')
    assert github_slug('Node `feedback`') == 'node-feedback'
    assert github_slug('Threads: commands do not wait for the FSR step') == (
        'threads-commands-do-not-wait-for-the-fsr-step')
    assert github_slug('1/960 s with 5 solver iterations') == '1960-s-with-5-solver-iterations'


def test_the_checks_catch_a_broken_link_and_an_unknown_script(tmp_path: Path) -> None:
    docs = tmp_path / 'docs'
    docs.mkdir()
    (docs / 'a.md').write_text('# Title\n\n## Two words\n\n## Two words\n', encoding='utf-8')
    page = docs / 'b.md'
    page.write_text('[ok](a.md#two-words) [ok](a.md#two-words-1) [gone](missing.md) [bad](a.md#nope)\n'
                    '`[in code](missing.md)`\n```\n[in a block](missing.md)\n```\n[web](https://example.org/x)\n',
                    encoding='utf-8')
    problems = broken_links(page, root=tmp_path)
    assert len(problems) == 2
    assert 'missing.md: no such file' in problems[0]
    assert 'no heading with anchor #nope' in problems[1]
    assert named_scripts('run `smarticle-sim run` or\n```bash\nsmarticle-no-such --x\n```\nsmarticle-prose') == {
        'smarticle-sim', 'smarticle-no-such'}
    assert 'smarticle-no-such' not in console_scripts()
    assert 'smarticle-sim' in console_scripts()
