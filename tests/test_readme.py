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


def test_the_own_agent_example_runs(tmp_path, monkeypatch):
    """The README's "Evaluating your own agent" block, on one episode instead of the full suite."""
    text = (ROOT / "README.md").read_text()
    block = text.split("### Evaluating your own agent")[1].split("```python\n")[1].split("```")[0]
    assert len(block.strip().splitlines()) <= 13
    from paragym.baselines import leaderboard

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(leaderboard, "FULL", leaderboard.EvalSuite("test", (0,), 1))
    # replace=True: the block may run twice in one session
    code = block.replace('description="my method")', 'description="my method", replace=True)')
    exec(compile(code, "README", "exec"), {})
    (md_path,) = (tmp_path / "results" / "mine").glob("partial-Orthoglide2PRRKappa-v0-*/LEADERBOARD.md")
    md = md_path.read_text()
    assert "my-agent" in md and "gradient-c" in md
