"""The README's two commands come first and CI runs the second one."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    blocks = text.split("```bash\n")[1:]
    return [b.split("```")[0].strip() for b in blocks]


def test_readme_starts_with_the_main_job_and_the_tests():
    main_job, tests = _commands()[:2]
    assert "pip install -e" in main_job and "paragym leaderboard --quick" in main_job
    assert '.[dev]' in tests and "pytest" in tests


def test_ci_runs_the_readme_test_command():
    ci = (ROOT / ".ci" / "run").read_text()
    assert _commands()[1] in ci.splitlines()


def test_the_readme_is_a_front_page_with_a_true_env_table():
    """At most about 250 lines; its env table is the registry's, status column included (generated)."""
    from pages import readme_env_table

    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 250
    assert readme_env_table() in text, "README's env table is stale: paste docs/pages.py's readme_env_table()"


def test_the_readme_leaderboard_is_the_committed_run_with_its_intervals():
    """The headline table is generated from the committed leaderboard/leaderboard.csv, which the committed
    LEADERBOARD.md was written with: the same run, of this version, with no path of the machine that ran it."""
    from pages import readme_leaderboard_table

    import paragym

    text = (ROOT / "README.md").read_text()
    assert readme_leaderboard_table(ROOT / "leaderboard" / "leaderboard.csv") in text, \
        "README's leaderboard is stale: paste docs/pages.py's readme_leaderboard_table('leaderboard/leaderboard.csv')"
    from pages import ladder_table

    assert ladder_table(ROOT / "leaderboard" / "leaderboard.csv", newest=True) in text, \
        "README's ladder table is stale: paste docs/pages.py's ladder_table('leaderboard/leaderboard.csv', " \
        "newest=True)"
    board = (ROOT / "LEADERBOARD.md").read_text()
    assert f"package version {paragym.__version__}; full suite" in board
    assert "[95% CI]" in board and "apart from #1" in board
    for name in ("LEADERBOARD.md", "report/REPORT.md"):
        page = (ROOT / name).read_text()
        assert "/home/" not in page and "/tmp/" not in page and "/work/" not in page, name
