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
    from paragym.docpages import readme_env_table

    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 250
    assert readme_env_table() in text, "README's env table is stale: paste paragym.docpages.readme_env_table()"
