"""What the README says around its commands is true (PyTorch builds, report.html)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
QUICKSTART = README.split("## Quickstart", 1)[1].split("\n## ", 1)[0]


def test_test_command_does_not_claim_a_cpu_build_it_does_not_install():
    # `pip install torch==2.13.0` from PyPI is the CUDA build on Linux x86_64
    assert "installs the CPU build" not in QUICKSTART
    assert "CUDA build" in QUICKSTART
    cpu = "pip install torch==2.13.0 --index-url https://download.pytorch.org/whl/cpu"
    assert cpu in QUICKSTART and cpu in README.split("**PyTorch and CUDA.**", 1)[1]


def test_readme_and_cli_cite_the_projects_models_doc():
    assert (ROOT / "docs" / "models.md").exists()
    for path in [
        ROOT / "README.md",
        *(ROOT / "baselines").rglob("*.py"),
        *(ROOT / "motion_envs").rglob("*.py"),
    ]:
        text = path.read_text()
        assert "MODELS.md" not in text, path
        assert "../shared" not in text, path
    assert "report.html" in QUICKSTART
