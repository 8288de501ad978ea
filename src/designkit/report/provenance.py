"""Where a report comes from: designkit version, git commit, Python, OS, command line, dependencies.

:func:`provenance_rows` is what the report shows (the provenance table and, with the dependency
versions of :func:`designkit.pipeline.versions`, the PDF metadata).

Reproducibility.  The same spec in the same environment gives the same report bytes: every value
here is read once per process and none is a time stamp.  The git commit, the dirty flag and the
command line do change from one commit (or invocation) to the next, so a committed example report
regenerated at a new commit differs in those lines only.  Setting ``DESIGNKIT_PROVENANCE=stable``
leaves them out, and the OS release with them (the designkit, Python, OS name and dependency versions
stay): regenerate the committed example reports in ``reports/`` with it, so that they change only when
their content does (``DESIGNKIT_PROVENANCE=stable designkit synth specs/x.yaml``).
"""

from __future__ import annotations

import functools
import os
import platform
import shlex
import subprocess
import sys
from importlib import metadata
from pathlib import Path

_GIT_TIMEOUT = 2.0  # seconds for each git call; a slow or absent git only drops the commit
STABLE_ENV = "DESIGNKIT_PROVENANCE"


def designkit_version() -> str:
    """The installed designkit version (``"unknown"`` when not installed as a distribution)."""
    try:
        return metadata.version("designkit")
    except metadata.PackageNotFoundError:
        return "unknown"


def _git(args: list[str], cwd: Path) -> str | None:
    try:
        done = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, timeout=_GIT_TIMEOUT,
                              check=False, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip() if done.returncode == 0 else None


@functools.lru_cache(maxsize=1)
def git_state(package_dir: str | None = None) -> tuple[str, bool] | None:
    """``(commit, dirty)`` of the git checkout designkit runs from, or None (no git, not a checkout).

    ``dirty`` is True when the package's own sources differ from the commit (changes elsewhere in
    the work tree, such as regenerated reports, do not count: they did not make the report).
    """
    here = Path(package_dir) if package_dir else Path(__file__).resolve().parents[1]
    if not here.is_dir():
        return None
    commit = _git(["rev-parse", "--verify", "HEAD"], here)
    if not commit:
        return None
    tracked = _git(["ls-files", "--", "__init__.py"], here)
    if not tracked:  # designkit installed inside some other repository: not its checkout
        return None
    status = _git(["status", "--porcelain", "--untracked-files=no", "--", "."], here)
    if status is None:
        return None
    return commit, bool(status)


def command_line(argv: list[str] | None = None) -> str:
    """The command line, shell-quoted, with the program reduced to its name (not its install path)."""
    args = list(sys.argv if argv is None else argv)
    if not args:
        return ""
    args[0] = Path(args[0]).name or args[0]
    return shlex.join(args)


def provenance_rows(argv: list[str] | None = None, *, stable: bool | None = None) -> tuple[tuple[str, str], ...]:
    """``(name, value)`` rows: designkit version, git commit and dirty flag (when run from a checkout),
    Python, OS and the command line.

    ``stable`` (default: the environment variable ``DESIGNKIT_PROVENANCE`` is ``stable``) leaves out
    the commit, the dirty flag and the command line, which change with every commit or invocation.
    """
    if stable is None:
        stable = os.environ.get(STABLE_ENV, "").strip().lower() == "stable"
    rows = [("designkit", designkit_version())]
    if not stable:
        state = git_state()
        if state is not None:
            commit, dirty = state
            rows.append(("git commit", commit))
            rows.append(("uncommitted changes", "yes: the sources differ from this commit" if dirty else "no"))
    rows.append(("Python", f"{platform.python_implementation()} {platform.python_version()}"))
    release = "" if stable else f" {platform.release()}"
    rows.append(("operating system", f"{platform.system()}{release} ({platform.machine()})"))
    if not stable:
        rows.append(("command line", command_line(argv)))
    else:
        rows.append(("command line", f"not recorded ({STABLE_ENV}=stable)"))
    return tuple(rows)


__all__ = ["STABLE_ENV", "command_line", "designkit_version", "git_state", "provenance_rows"]
