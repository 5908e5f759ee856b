"""The repository is self-contained: every file it names exists, and no internal ticket
number is left in it.

**Where we look**: every file git tracks in the checkout (code, tests, configs, docs,
benchmarks, notebooks, the Makefile and CI script), except binary files and the licence
texts.

**What counts as a path** (a mention of a repository file or folder):

* a Markdown link target ``[text](target)`` that is not a URL or an anchor;
* a token made of letters, digits and ``_ . - /`` that contains a ``/`` and either ends
  in a file extension of the repository (``.py .md .yaml .toml .json .xml .stl .ipynb
  .txt``) or ends in ``/`` and starts with a top-level folder of the repository
  (``conf/``, ``docs/controllers/``);
* a bare Markdown file name (``friction.md``, ``SOMETHING.md``): docs cite each other by
  name.

Not paths: tokens with a placeholder (``<robot>``, ``{name}``, ``*``, ``$``, ``…``, a
part in capitals such as ``NAME``), URLs, absolute paths and ``~/…`` (outside the
repository), a path whose first folder is no folder of the repository (``my_conf/…`` in an
example: the top level's, the package's, ``conf/``'s, ``tests/``'s and ``docs/``'s count),
and names under the folders runs write (``runs/``, ``outputs/``, ``multirun/``, a run
directory's ``figures/``, ``comparison/``, ``tuning/``, ``.hydra/``, ``.submitit/``,
``.cache/``), which exist only after a run.

**Where a path may exist**: relative to the repository root, to the package folder
(docs abbreviate ``compliant_docking/control/jit.py`` as ``control/jit.py``), to
``conf/``, to ``tests/``, or to the mentioning file's folder (Markdown links, sibling
docs); a bare Markdown name may be any tracked Markdown file. The exceptions are listed:
files commands write (:data:`OUTPUT_NAMES`), files of other projects (:data:`EXTERNAL`)
and names a test uses because they do not exist (:data:`MISSING_ON_PURPOSE`).

**Ticket numbers**: ``issue 10``, ``issue-12``, ``issue12``, ``ticket 3``, ``#12`` in
prose … say what a thing is, not which ticket brought it. The paper's "Table 10" is
not a ticket.
"""

from __future__ import annotations

import re
import subprocess
from functools import cache
from pathlib import Path

import pytest

from tests.helpers import REPO_ROOT

EXTENSIONS = ("py", "md", "yaml", "toml", "json", "xml", "stl", "ipynb", "txt")
#: files read as text (the rest of the tracked files are binary or licence texts)
TEXT_SUFFIXES = {".py", ".md", ".yaml", ".yml", ".toml", ".ipynb", ".txt", ".cfg", ".xml", ""}
SKIPPED = {"LICENSE", "NOTICE", "LICENSES/Apache-2.0.txt", "tests/test_references.py"}
#: folders that exist only once something ran (run directories and their parts, caches)
OUTPUT_PARTS = {
    "runs",
    "outputs",
    "multirun",
    "figures",
    "comparison",
    "tuning",
    ".hydra",
    ".submitit",
    ".cache",
}
#: names of files that commands write (a sweep's summary, MLflow's copy of the config)
OUTPUT_NAMES = {"summary.md", "hydra/config.yaml"}
#: files of other projects, named where numbers come from (MuJoCo Menagerie's models)
EXTERNAL = {"franka_fr3/fr3.xml", "kuka_iiwa_14/iiwa14.xml"}
#: names a test uses because they do not exist (name → why)
MISSING_ON_PURPOSE = {
    "assets/interfaces/nothing/tool.xml": "tests/test_package.py: the 'no such file' message",
    "interfaces/nothing/tool.xml": "tests/test_package.py: the same, under the packaged assets",
}

LINK = re.compile(r"\]\(([^)\s]+)\)")
TOKEN = re.compile(
    r"(?<![\w./-])((?:[\w.-]+/)+(?:[\w.-]+\.(?:" + "|".join(EXTENSIONS) + r")\b|(?=[\s`'\")|,;:]|$)))"
)
BARE_MD = re.compile(r"(?<![\w./-])([\w-]+\.md)\b")
PLACEHOLDER = re.compile(r"[<>{}*$…]|\.\.\.|(?:^|/)[A-Z_]{2,}(?:/|$)")
TICKET = re.compile(
    r"\b(?:issue|ticket|wave)[\s_-]?#?\d+\b|(?<![\w&/#\"'])#\d{1,4}\b(?![\w-])", re.IGNORECASE
)


@cache
def tracked() -> tuple[str, ...]:
    out = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    return tuple(p for p in out.stdout.splitlines() if (REPO_ROOT / p).is_file())


def text_files() -> list[str]:
    return [p for p in tracked() if Path(p).suffix in TEXT_SUFFIXES and p not in SKIPPED]


@cache
def top_level() -> frozenset[str]:
    return frozenset(p.split("/")[0] for p in tracked() if "/" in p)


@cache
def repository_folders() -> frozenset[str]:
    """The folders a repository path may start with: the top level's, the package's and conf/'s."""
    inner = {
        p.split("/")[i]
        for p in tracked()
        for prefix, i in (("compliant_docking/", 1), ("conf/", 1), ("tests/", 1), ("docs/", 1))
        if p.startswith(prefix) and p.count("/") > i
    }
    return top_level() | inner


@cache
def markdown_names() -> frozenset[str]:
    return frozenset(Path(p).name for p in tracked() if p.endswith(".md"))


def mentions(path: str, text: str) -> list[str]:
    """The paths ``text`` (the content of the tracked file ``path``) mentions (see the docstring)."""
    found = [m.group(1).split("#")[0] for m in LINK.finditer(text) if path.endswith((".md", ".ipynb"))]
    found = [f for f in found if f and "://" not in f and not f.startswith("mailto:")]
    for m in TOKEN.finditer(text):
        token = m.group(1)
        if token.endswith("/") and token.split("/")[0] not in top_level():
            continue
        found.append(token)
    found += [m.group(1) for m in BARE_MD.finditer(text)]
    return found


def exists(mention: str, path: str) -> bool:
    if (
        PLACEHOLDER.search(mention)
        or mention.startswith(("/", "~"))
        or mention in MISSING_ON_PURPOSE.keys() | EXTERNAL
    ):
        return True
    parts = [p for p in mention.split("/") if p not in ("", ".")]
    if any(p in OUTPUT_PARTS for p in parts) or mention in OUTPUT_NAMES:
        return True
    if "/" in mention.rstrip("/") and not mention.startswith("..") and parts[0] not in repository_folders():
        return True  # my_conf/…, a user's folder in an example: not a repository path
    if "/" not in mention.rstrip("/") and mention.endswith(".md"):
        return mention in markdown_names()
    here = (REPO_ROOT / path).parent
    bases = (REPO_ROOT, REPO_ROOT / "compliant_docking", REPO_ROOT / "conf", REPO_ROOT / "tests", here)
    return any((base / mention).exists() for base in bases)


def dead_references() -> list[str]:
    dead = []
    for path in text_files():
        text = (REPO_ROOT / path).read_text(encoding="utf-8", errors="replace")
        for mention in dict.fromkeys(mentions(path, text)):
            if not exists(mention, path):
                dead.append(f"{path}: {mention}")
    return dead


def ticket_numbers() -> list[str]:
    found = []
    for path in text_files():
        for number, line in enumerate((REPO_ROOT / path).read_text(encoding="utf-8").splitlines(), 1):
            for m in TICKET.finditer(line):
                found.append(f"{path}:{number}: {m.group(0)!r} in {line.strip()[:100]!r}")
    return found


def test_every_repository_path_named_in_code_and_docs_exists():
    dead = dead_references()
    assert not dead, f"{len(dead)} mentions of files that do not exist:\n" + "\n".join(dead)


def test_no_internal_ticket_numbers():
    found = ticket_numbers()
    assert not found, f"{len(found)} ticket numbers:\n" + "\n".join(found)


@pytest.mark.parametrize(
    ("text", "path", "expected"),
    [
        ("see docs/control_laws.md §2", "README.md", ["docs/control_laws.md"]),
        ("`control/jit.py` compiles", "docs/x.md", ["control/jit.py"]),
        (
            "[friction](friction.md) and CONTROL_LAWS.md",
            "docs/controllers/x.md",
            ["friction.md", "friction.md", "CONTROL_LAWS.md"],
        ),
        ("conf/robot_controller/<robot>_<controller>.yaml", "README.md", []),  # a placeholder: not a path
        ("the folder conf/experiment/ and a/b", "README.md", ["conf/experiment/"]),
        ("a URL https://example.org/x.md", "README.md", []),
    ],
)
def test_what_counts_as_a_path(text, path, expected):
    assert [m for m in mentions(path, text) if "://" not in m and "example.org" not in m] == expected


@pytest.mark.parametrize(
    ("mention", "path", "ok"),
    [
        ("docs/control_laws.md", "README.md", True),
        ("control/jit.py", "docs/sweeps.md", True),  # package-relative
        ("../control_laws.md", "docs/controllers/hqp.md", True),  # relative to the mentioning file
        ("CONTROL_LAWS.md", "compliant_docking/control/impedance.py", False),  # nowhere in the repository
        ("docs/nothing.md", "README.md", False),
        ("runs/multirun/x/summary.md", "README.md", True),  # written by a run
        ("conf/robot_controller/<robot>_<controller>.yaml", "README.md", True),  # a placeholder
    ],
)
def test_where_a_path_may_exist(mention, path, ok):
    assert exists(mention, path) is ok


@pytest.mark.parametrize(
    ("line", "tickets"),
    [
        ("the contact metrics of issue 10", ["issue 10"]),
        ("compiled kernels (issue12)", ["issue12"]),
        ("analysis/issue10/", ["issue10"]),
        ("the Table-10 metrics; Table 10 of the paper", []),
        ("colour #0C5DA5, x#1", []),
        ("fixed in #123.", ["#123"]),
    ],
)
def test_what_counts_as_a_ticket_number(line, tickets):
    assert [m.group(0) for m in TICKET.finditer(line)] == tickets
