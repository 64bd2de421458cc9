"""Whether every CaPaMan rung's scene has a collision-free tour: the witness of
:func:`paragym.tasks.capaman.solvable` over reset seeds 0 to ``--seeds`` - 1 of each rung.

The tests check the first 250 seeds of each rung; this checks as many as asked (1,000 when the ladder was made),
about 40 ms a scene here, and prints per rung the seeds whose scene has no tour (none, for the ladder to hold).

    python benchmarks/capaman_solvable.py [--seeds 1000] [--record]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from results_file import add_record_option, paragraph, record

from paragym import registry
from paragym.tasks.capaman import LADDER, ladder_scenarios, solvable


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=1000, help="reset seeds per rung, from 0")
    add_record_option(parser)
    args = parser.parse_args()
    if args.seeds < 1:
        parser.error(f"--seeds must be at least 1, got {args.seeds}")
    rows = []
    for row in registry.ladders("capaman")[0]:
        start = time.perf_counter()
        scenes = ladder_scenarios([np.random.default_rng(s) for s in range(args.seeds)], LADDER[row.rung])
        unsolved = [s for s, scene in enumerate(scenes) if not solvable(scene)]
        rows.append([row.id, args.seeds, len(unsolved), " ".join(map(str, unsolved[:10])) or "none",
                     f"{time.perf_counter() - start:.0f}"])
        print(" | ".join(map(str, rows[-1])), flush=True)
    if args.record:
        record("capaman_solvable", "Every CaPaMan rung's scenes have a collision-free tour", paragraph(__doc__),
               ["rung", "seeds", "without a tour", "first such seeds", "seconds"], rows, folder=args.record)


if __name__ == "__main__":
    main()
