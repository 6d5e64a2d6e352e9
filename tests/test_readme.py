"""The README and the user guide run as written: every command of their ``bash`` and
``python`` blocks, the README's then the guide's, in order, in a scratch directory laid
out as a clone's root: a copy of ``warpcloth/``, ``kernels/`` and ``scenes/``, so a Python
block imports the clone's folder as it does in Jupyter opened there (the README's
paragraph after the install block states the conventions this test applies; they are the
constants below)."""

import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from conftest import run_cli

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
GUIDE = ROOT / "docs" / "guide.md"

SWEEP_SHORTER = "--set sweep.random.samples=8"  # appended to every `warpcloth sweep`
SKIP = "not run by the README test"
EXITS = re.compile(r"\bexits (\d+)\b")
ADDS = re.compile(r"README test adds (.+)$")
BLOCK = re.compile(r"^```(\w+)\n(.*?)^```$", re.MULTILINE | re.DOTALL)
TIMEOUT_S = 180
TAIL_CHARS = 3000
SEARCH = re.compile(r"(\d+) launches, (\d+) variants")  # what `warpcloth fit` prints
QUOTED = "{} launches ({} variants)"  # how the README quotes it


@dataclass
class Step:
    argv: list[str]
    shown: str
    exit_code: int = 0


def split_comment(line):
    """``line`` as (code, comment): the comment starts at the first ``#`` outside quotes
    that begins a word, as bash reads it."""
    quote = None
    for i, ch in enumerate(line):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (i == 0 or line[i - 1].isspace()):
            return line[:i].rstrip(), line[i + 1 :].strip()
    return line.rstrip(), ""


def samples_at_random(scene):
    """Whether the scene a `warpcloth sweep` names (bundled, or a path in the copy of the
    clone) has a [sweep.random] block, whose samples the README test cuts to 8 (a grid
    or zip sweep the guide keeps small itself); one that does not read is shortened too."""
    from warpcloth.errors import WarpclothError
    from warpcloth.scene import read_scene_file

    path = ROOT / scene
    try:
        data = read_scene_file(path if path.is_file() else scene)
    except WarpclothError:
        return True
    return "random" in (data.get("sweep") or {})


def bash_step(command, comments):
    """The step for one shell command and the comments that belong to it; None to skip it."""
    if any(SKIP in c for c in comments):
        return None
    for comment in comments:
        if added := ADDS.search(comment):
            command += " " + added.group(1).strip()
    argv = shlex.split(command)
    if argv[:2] == ["warpcloth", "sweep"] and samples_at_random(argv[2]):
        command += " " + SWEEP_SHORTER
    codes = {int(m.group(1)) for c in comments for m in EXITS.finditer(c)}
    assert len(codes) <= 1, f"README command {command!r} claims several exit codes: {sorted(codes)}"
    return Step(["bash", "-c", command], command, codes.pop() if codes else 0)


def bash_steps(body):
    """The commands of a bash block: continuation lines joined; a comment on the command's
    last line, or on comment lines just above it, belongs to it."""
    steps, above, command = [], [], ""
    for line in body.splitlines():
        code, comment = split_comment(line)
        if not code.strip() and not command:
            above = [*above, comment] if comment else []
            continue
        if code.endswith("\\") and not comment:
            command += code[:-1].strip() + " "
            continue
        # the command ends here (a continuation into a blank or comment line ends it too, as in bash)
        step = bash_step((command + code.strip()).strip(), [*above, comment])
        if step is not None:
            steps.append(step)
        above, command = [], ""
    assert not command, f"README block ends inside a continued command: {command!r}"
    return steps


def readme_steps(text):
    """Every step in README order (the README, then the guide). Of the first (install)
    block only its warpcloth commands run: the block installs the package and runs this suite."""
    found = list(BLOCK.finditer(text))
    assert found and found[0].group(1) == "bash", "the README starts with its install block"
    install = [part.strip() for line in found[0].group(2).splitlines() for part in line.split("&&")]
    steps = [Step(["bash", "-c", part], part) for part in install if part.startswith("warpcloth ")]
    assert steps, "the README's install block runs no warpcloth command"
    for block in found[1:]:
        language, body = block.groups()
        if language == "bash":
            steps += bash_steps(body)
        elif language == "python":
            steps.append(Step([sys.executable, "-c", body], body))
    return steps


SHELL_SYNTAX = re.compile(r"[|&;<>(){}$`*?~\\]")


def in_process(step, cwd):
    """A plain ``warpcloth ARGS`` command (no pipe, redirection, variable or glob for bash
    to expand) run by the entry point in this process, as bash would have split it: a
    child would spend ~1.5 s starting Python and Warp per command. None for anything else."""
    if step.argv[:2] != ["bash", "-c"] or SHELL_SYNTAX.search(step.argv[2].replace("'", "").replace('"', "")):
        return None
    words = shlex.split(step.argv[2])
    return run_cli(*words[1:], cwd=cwd) if words[0] == "warpcloth" else None


def test_split_comment_reads_quotes_as_bash_does():
    assert split_comment("a --where 'x#1' # note") == ("a --where 'x#1'", "note")
    assert split_comment('a --set "s=#" b#c') == ('a --set "s=#" b#c', "")
    assert split_comment("# only a comment") == ("", "only a comment")


def test_readme_conventions_are_parsed():
    steps = bash_steps(
        "warpcloth run a --out 'r#1' \\\n"
        "    --set x=1   # exits 2\n"
        "# README test adds --set y=2\n"
        "warpcloth sweep s\n"
        "warpcloth run gpu   # on a GPU; not run by the README test\n"
    )
    assert [(s.shown, s.exit_code) for s in steps] == [
        ("warpcloth run a --out 'r#1' --set x=1", 2),
        (f"warpcloth sweep s --set y=2 {SWEEP_SHORTER}", 0),
    ]


def clone_root(path):
    """``path`` laid out as a clone's root: the package's source folders copied there."""
    for folder in ("warpcloth", "kernels", "scenes"):
        shutil.copytree(ROOT / folder, path / folder, ignore=shutil.ignore_patterns("__pycache__"))


def test_the_package_imports_whole_in_a_clones_root(tmp_path):
    # `import warpcloth` in a clone's root finds the folder there, not the installed
    # package: its kernels and scenes are the ones beside that folder, whichever way (or
    # whether) the package was installed
    clone_root(tmp_path)
    probe = "import warpcloth, warpcloth.kernels, warpcloth.scenes as s; print(warpcloth.kernels.__file__, s.__file__)"
    done = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr[-TAIL_CHARS:]
    kernels, scenes = (Path(p).resolve() for p in done.stdout.split())
    assert kernels == (tmp_path / "kernels" / "__init__.py").resolve()
    assert scenes == (tmp_path / "scenes" / "__init__.py").resolve()


@pytest.mark.slow
def test_readme_runs_as_written(tmp_path):
    text = README.read_text(encoding="utf-8") + "\n" + GUIDE.read_text(encoding="utf-8")
    steps = readme_steps(text)
    searches = []
    clone_root(tmp_path)
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}")
    for step in steps:
        done = in_process(step, tmp_path) or subprocess.run(
            step.argv, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=TIMEOUT_S
        )
        output = done.stdout + done.stderr
        assert done.returncode == step.exit_code and "Traceback (most recent call last)" not in output, (
            f"README command:\n{step.shown}\nexited {done.returncode} (the README says {step.exit_code}); "
            f"output tail:\n{output[-TAIL_CHARS:]}"
        )
        searches += [(step.shown, QUOTED.format(*m.groups())) for m in SEARCH.finditer(output)]
    # the numbers the guide quotes for its fits are the ones its fit commands print now
    assert len(searches) >= 2, "the guide's fit commands printed no launch and variant counts"
    for shown, quoted in searches:
        assert quoted in text, f"guide command:\n{shown}\nprinted {quoted!r}, which the guide does not quote"
