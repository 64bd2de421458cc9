"""The README's main job from a fresh clone: how long its install and its first run take on this machine.

Clones the repository's committed HEAD into a temporary folder, then runs the
README's first command there part by part (the ``&&``-joined steps: make the
venv, install, run the quick leaderboard), timing each, and checks that every
part exits with 0. The first run compiles the kernels (numba's cache of the
clone is empty), as a user's first run does. ``--record`` writes the row for
the speed page.

    python benchmarks/main_job.py [--record]
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from results_file import add_record_option, record  # this folder is on the path when it runs

ROOT = Path(__file__).resolve().parent.parent

#: the speed page's paragraph above this script's table (``--record``)
PARAGRAPH = (
    "The README's first command in a fresh clone of the committed tree, in a new venv, part by part: the install "
    "and the first run of the quick leaderboard, which compiles the kernels. Two things move these times, and "
    "each row says how they stood: pip's cache (the packages the install downloaded, against those it took from "
    "the cache) and the machine's load (the highest one-minute load average seen, against the cores; a load "
    "above the cores slows every part)."
)


def readme_command() -> str:
    """The README's first bash block: the main job."""
    return re.findall(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), re.S)[0].strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_record_option(parser)
    args = parser.parse_args()
    command = readme_command()
    parts = [p.strip() for p in command.split("&&")]
    with tempfile.TemporaryDirectory() as tmp:
        clone = Path(tmp) / "paragym"
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH", "NUMBA_CACHE_DIR")}
        times, loads, fetched = [], [os.getloadavg()[0]], {"downloaded": 0, "from the cache": 0}
        for part in parts:
            t0 = time.perf_counter()
            res = subprocess.run(["bash", "-c", part], cwd=clone, env=env, capture_output=True, text=True)
            times.append(time.perf_counter() - t0)
            loads.append(os.getloadavg()[0])
            fetched["downloaded"] += len(re.findall(r"^\s*Downloading ", res.stdout, re.M))
            fetched["from the cache"] += len(re.findall(r"^\s*Using cached ", res.stdout, re.M))
            print(f"{times[-1]:7.1f} s  exit {res.returncode}  {part}", flush=True)
            if res.returncode != 0:
                sys.exit(f"the README's main job failed at {part!r}:\n{res.stderr[-2000:]}")
        written = (clone / "results" / "LEADERBOARD.md").is_file()
    if not written:
        sys.exit("the main job wrote no results/LEADERBOARD.md")
    pip = f"{fetched['downloaded']} downloaded, {fetched['from the cache']} from the cache"
    load = f"{max(loads):.1f} on {os.cpu_count()} cores"
    row = [f"{times[0]:.1f}", f"{times[1]:.1f}", f"{times[2]:.1f}", f"{sum(times):.1f}", pip, load]
    print(f"install {times[0] + times[1]:.1f} s, first run {times[2]:.1f} s, in all {sum(times):.1f} s; "
          f"pip: {pip}; highest load {load}")
    if args.record:
        record("main_job", "The main job from a fresh clone", PARAGRAPH,
               ["make the venv (s)", "install (s)", "first `leaderboard --quick` (s)", "in all (s)", "pip's packages",
                "highest load"], [row], order=5, folder=args.record)


if __name__ == "__main__":
    main()
