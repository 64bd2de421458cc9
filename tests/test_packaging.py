"""The wheel installs and works on its own; the console script runs."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # every test here starts processes or runs a benchmark

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                    "-w", str(out), str(ROOT)], check=True)
    (whl,) = out.glob("paragym-*.whl")
    return whl


def test_wheel_installs_and_registers_the_envs(wheel, tmp_path):
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(target),
                    str(wheel)], check=True)
    code = (
        "import paragym, paragym.envs, paragym.planners, paragym.baselines, gymnasium as gym\n"
        f"assert paragym.envs.__file__.startswith({str(target)!r}), paragym.envs.__file__\n"
        "env = gym.make('paragym/CaPaManCollisionFree-v0', scenario='paper')\n"
        "obs, info = env.reset(seed=0)\n"
        "print(obs.shape, info['scenario'].name)\n"
        "from paragym.baselines.policies import shipped_models_dir\n"
        f"assert str(shipped_models_dir()).startswith({str(target)!r}), shipped_models_dir()\n"
        "print(len(list(shipped_models_dir().glob('*/*_seed*.zip'))), 'shipped models')\n"
    )
    env = dict(os.environ, PYTHONPATH=str(target))
    res = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert "(38,) paper" in res.stdout and "91 shipped models" in res.stdout


def test_cli_lists_envs_and_writes_a_demo_picture(tmp_path):
    res = subprocess.run([sys.executable, "-m", "paragym.cli", "envs"], capture_output=True, text=True, check=True)
    assert "paragym/CaPaManCollisionFree-v0" in res.stdout
    res = subprocess.run([sys.executable, "-m", "paragym.cli", "demo", "CaPaManCollisionFree-v0",
                          "--out", str(tmp_path), "--gif", "--frame-every", "20"],
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert "success True" in res.stdout and "RRT + GA" in res.stdout
    png = tmp_path / "CaPaManCollisionFree-v0_paper_seed0_best.png"
    assert png.stat().st_size > 50_000 and (tmp_path / "CaPaManCollisionFree-v0_paper_seed0_best.gif").exists()
    res = subprocess.run([sys.executable, "-m", "paragym.cli", "demo", "Nope-v0"], capture_output=True, text=True)
    assert res.returncode == 2 and "unknown env id" in res.stderr
    res = subprocess.run([sys.executable, "-m", "paragym.cli", "demo", "CaPaManCollisionFree-v0",
                          "--scenario", "moon", "--out", str(tmp_path)], capture_output=True, text=True)
    assert res.returncode == 2 and "scenario must be" in res.stderr


def test_cli_plan_writes_the_figure_and_the_trajectory(tmp_path):
    res = subprocess.run([sys.executable, "-m", "paragym.cli", "plan", "CaPaManCollisionFree-v0",
                          "--scenario", "paper", "--dt", "0.09", "--out", str(tmp_path)],
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert "fitness J" in res.stdout and "within 60 mm" in res.stdout
    import json

    stats = json.loads((tmp_path / "CaPaManCollisionFree-v0_plan_paper_seed0.json").read_text())
    assert len(stats["via_points_rad"]) == 21 and stats["min_clearance_m"] > 0
    assert stats["tool_radius_about_obstacle_axis_m"][1] < 0.06
    assert (tmp_path / "CaPaManCollisionFree-v0_plan_paper_seed0.png").stat().st_size > 50_000


def test_cli_validate_prints_the_report_and_writes_figs_8_and_9(tmp_path):
    res = subprocess.run([sys.executable, "-m", "paragym.cli", "validate", "CaPaManCollisionFree-v0",
                          "--scenario", "paper", "--dt", "0.09", "--out", str(tmp_path)],
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "verdict: PASS" in res.stdout and "a_Hx" in res.stdout
    folder = tmp_path / "CaPaManCollisionFree-v0_paper_seed0_dt0.09"
    assert (folder / "fig8_raw.png").exists() and (folder / "fig9_kf.png").exists()
    assert (folder / "report.json").exists()


def test_cli_plans_and_validates_the_hybrid_robot(tmp_path):
    res = subprocess.run([sys.executable, "-m", "paragym.cli", "plan", "HybridSingularityFree-v0",
                          "--scenario", "paper", "--out", str(tmp_path)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert "nominal, Delta = 0.5" in res.stdout
    assert (tmp_path / "HybridSingularityFree-v0_plan_paper_seed0.png").exists()
    res = subprocess.run([sys.executable, "-m", "paragym.cli", "validate", "HybridSingularityFree-v0",
                          "--scenario", "paper", "--out", str(tmp_path)], capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "verdict: PASS" in res.stdout
