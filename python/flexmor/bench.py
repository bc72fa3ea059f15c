"""What the benchmark drivers (scripts/bench_tradeoff.py, scripts/bench_sweep.py) share: the
machine and commit they ran on, the command that ran them, CSV output and process output
helpers."""
from __future__ import annotations

import csv
import os
import platform
import shlex
import subprocess
import sys
from pathlib import Path
from typing import Any, Sequence


def last_line(text: str) -> str:
    """The last non-blank line of a process's output (its error message)."""
    lines = [line.strip() for line in text.strip().splitlines() if line.strip()]
    return lines[-1] if lines else ""


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def usable_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def git_commit(root: str | os.PathLike) -> str:
    """Short commit of the repository at ``root``, with '+ uncommitted changes' when the
    tracked files differ from it (read only: no index refresh); 'unknown' without git."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root,
                              capture_output=True, text=True, timeout=30)
        if head.returncode != 0:
            return "unknown"
        status = subprocess.run(["git", "--no-optional-locks", "status", "--porcelain",
                                 "--untracked-files=no"], cwd=root, capture_output=True,
                                text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    dirty = status.returncode == 0 and status.stdout.strip()
    return head.stdout.strip() + (" + uncommitted changes" if dirty else "")


def write_csv(rows: list[dict[str, Any]], columns: Sequence[str], path: Path) -> None:
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(columns))
        writer.writeheader()
        writer.writerows(rows)


def command_line(prog: str, argv: Sequence[str] | None) -> str:
    """The command as the user typed it (argv None: this process's own)."""
    if argv is None:
        return shlex.join(getattr(sys, "orig_argv", sys.argv))
    return shlex.join([prog, *argv])
