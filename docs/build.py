"""Build paragym's documentation site: ``python docs/build.py`` (needs the ``docs`` extra).

Writes the generated pages (one per env id, the speed and conformance pages from the benchmarks' result files,
and the ladders' page and figure from the committed leaderboard, ``docs/pages.py``), then runs Sphinx in
strict mode (a warning is an error) into ``docs/_build/html``. ``--no-images`` keeps the
rendered frames as they are; ``--check`` only builds.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-images", action="store_true", help="do not render the env pages' frames again")
    parser.add_argument("--check", action="store_true", help="build only: write no generated page")
    parser.add_argument("--out", default=str(DOCS / "_build" / "html"), help="where the HTML goes")
    args = parser.parse_args(argv)
    if not args.check:
        from pages import conformance_page, ladder_figure, ladders_page, speed_page, write_pages

        board = DOCS.parent / "leaderboard" / "leaderboard.csv"
        write_pages(DOCS / "envs", images=not args.no_images, board=board)
        (DOCS / "speed.md").write_text(speed_page(DOCS.parent / "benchmarks" / "results"))
        (DOCS / "conformance.md").write_text(conformance_page(DOCS.parent / "benchmarks" / "results"))
        (DOCS / "ladders.md").write_text(ladders_page(board))
        if not args.no_images:
            ladder_figure(board, DOCS / "reports" / "ladders.png")
    return subprocess.call([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(DOCS),
                            args.out])


if __name__ == "__main__":
    raise SystemExit(main())
