"""Every Python example of README.md and docs/*.md runs as written.

The rule, as a reader meets it:

* An example is a fenced block opened by a line that is exactly ```` ```python ````. Each
  is one test, named ``file:line`` (the line of its opening fence).
* Every file is one Python session: its blocks run in the order they appear, in one
  namespace that starts empty for each file, so a later block may use what an earlier
  block of the same file defined (``import fbs_core as fc`` once at the top). Nothing is
  carried from one file to another. A block run on its own (``-k``) first runs the blocks
  of its file above it.
* The working directory is the repository root, as for a reader who runs the examples
  there: ``data/...`` paths name the shipped reference data. An example that writes a
  file says where: a folder of ``tempfile.mkdtemp()`` (here made under the test's
  ``tmp_path``, which pytest removes); a block that leaves a new file or folder in the
  repository root, ``data/`` or ``docs/`` fails.
* No block is skipped or expected to fail; a slow example is made small in the document
  itself (its prose says how to scale it up).

:func:`test_no_python_example_escapes` fails when a file holds a Python block the
collector would not run: a fence spelled differently (```` ```py ````, ```` ```Python ````,
``~~~python``, an indented fence) or an unlabelled fence whose text is Python using
``fbs_core``.
"""

from __future__ import annotations

import ast
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
FILES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: Documents that hold at least one example (the collector must find it).
DOCUMENTED = [
    "analysis.md",
    "chassis-model.md",
    "corridor.md",
    "file-formats.md",
    "tire-model.md",
    "vehicle-model.md",
    "verdict.md",
    "vpt.md",
]
#: Folders a block must not leave new entries in.
WATCHED = [ROOT, ROOT / "data", ROOT / "docs"]

OPEN = "```python"
FENCE = re.compile(r"^(?P<indent>[ \t]*)(?P<fence>`{3,}|~{3,})(?P<info>.*)$")
PYTHON_INFO = re.compile(r"^\{?\.?(py|python|python3|py3|pycon|ipython|ipython3)\b", re.I)


@dataclass(frozen=True)
class Block:
    path: Path
    line: int  # 1-based line of the opening fence
    code: str

    @property
    def id(self) -> str:
        return f"{self.path.relative_to(ROOT).as_posix()}:{self.line}"


def _fences(text: str) -> list[tuple[int, str, str, str]]:
    """Fenced blocks of a Markdown text: (line of the opening fence, its line, info, body).

    A fence closes at the next line of the same fence character, at least as long, with
    nothing after it (CommonMark); an unclosed fence runs to the end of the file.
    """
    lines = text.splitlines()
    out = []
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence = m["fence"]
        body = []
        j = i + 1
        while j < len(lines):
            c = FENCE.match(lines[j])
            if c and c["fence"][0] == fence[0] and len(c["fence"]) >= len(fence):
                if not c["info"].strip():
                    break
            body.append(lines[j])
            j += 1
        out.append((i + 1, lines[i], m["info"].strip(), "\n".join(body) + "\n"))
        i = j + 1
    return out


def collect(path: Path) -> list[Block]:
    """The examples the tests run: blocks opened by exactly ```` ```python ````."""
    return [
        Block(path, n, body)
        for n, opening, _, body in _fences(path.read_text(encoding="utf-8"))
        if opening.rstrip() == OPEN
    ]


BLOCKS = [b for p in FILES for b in collect(p)]
_sessions: dict[Path, tuple[int, dict[str, object]]] = {}


def _entries() -> set[Path]:
    return {p for d in WATCHED for p in d.iterdir()}


def _run(block: Block, namespace: dict[str, object]) -> None:
    # padded to the block's lines: a traceback names the document's own line and text
    # (and without this module's __future__ imports: the block runs as a reader's script)
    code = compile("\n" * block.line + block.code, str(block.path), "exec", dont_inherit=True)
    before = _entries()
    exec(code, namespace)
    new = sorted(str(p) for p in _entries() - before)
    assert not new, f"{block.id} wrote {new} into the repository; examples write elsewhere"


@pytest.mark.parametrize("block", BLOCKS, ids=lambda b: b.id)
def test_example_runs(block: Block, monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # pytest cleans up after
    same_file = [b for b in BLOCKS if b.path == block.path]
    k = same_file.index(block)
    done, namespace = _sessions.pop(block.path, (-1, {}))
    if done != k - 1 or k == 0:  # first block, or run on its own: the file from the top
        namespace = {"__name__": "__main__"}
        for earlier in same_file[:k]:
            _run(earlier, namespace)
    _run(block, namespace)  # a failure leaves no session: the next block starts again
    if k + 1 < len(same_file):
        _sessions[block.path] = (k, namespace)


def test_examples_found() -> None:
    """The collector finds the examples: README.md's eight and the documents' own."""
    count = {p.name: sum(b.path == p for b in BLOCKS) for p in FILES}
    assert count["README.md"] >= 8, count
    for name in DOCUMENTED:
        assert count.get(name, 0) >= 1, f"no ```python example found in docs/{name}"


def escaped(text: str) -> list[tuple[int, str]]:
    """Python blocks of a Markdown text that :func:`collect` does not run: (line, why)."""
    out = []
    for n, opening, info, body in _fences(text):
        if opening.rstrip() == OPEN:
            continue
        if PYTHON_INFO.match(info):
            out.append((n, f"{opening.strip()!r} (open examples with {OPEN!r} at column 0)"))
        elif not info and ("fbs_core" in body or re.search(r"\bfc\.", body)):
            try:
                ast.parse(body)
            except SyntaxError:
                continue
            out.append((n, f"an unlabelled block of Python (label it {OPEN!r})"))
    return out


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_no_python_example_escapes(path: Path) -> None:
    """Every Python block of the file is one the collector runs."""
    found = escaped(path.read_text(encoding="utf-8"))
    where = path.relative_to(ROOT).as_posix()
    assert not found, "Python examples the tests do not run:\n" + "\n".join(
        f"{where}:{n}: {why}" for n, why in found
    )


def test_escape_check_sees_other_spellings(tmp_path: Path) -> None:
    """The check itself: other spellings and unlabelled Python are found, shell and
    Python-looking text in other languages are not, and ```` ```python ```` is collected."""
    text = "\n".join(
        [
            "```py",
            "x = 1",
            "```",
            "```Python",
            "x = 1",
            "```",
            "~~~python",
            "x = 1",
            "~~~",
            "  ```python",
            "  x = 1",
            "  ```",
            "```",
            "import fbs_core",
            "```",
            "```bash",
            ".venv/bin/python -m fbs_core.campaign run campaigns/example.toml",
            "```",
            "```",
            "GET /fbs_core?x=1 HTTP/1.1",
            "```",
            "```python",
            "y = 2",
            "```",
        ]
    )
    assert [n for n, _ in escaped(text)] == [1, 4, 7, 10, 13]
    doc = tmp_path / "doc.md"
    doc.write_text(text, encoding="utf-8")
    assert [(b.line, b.code) for b in collect(doc)] == [(22, "y = 2\n")]
