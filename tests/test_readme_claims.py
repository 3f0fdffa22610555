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


def test_data_page_has_the_csv_formats_the_readme_sends_to():
    """The README sends "the CSV formats" to docs/data.md: each loader's header is
    there, built from the code's own column lists."""
    from motion_envs.datasets.juggling import JUGGLING_COLUMNS
    from motion_envs.datasets.orientation import CSV_COLUMNS as ORIENTATION
    from motion_envs.datasets.position_csv import CSV_COLUMNS as POSITION

    assert "[Data](docs/data.md)" in README and "the CSV formats" in README
    page = (ROOT / "docs" / "data.md").read_text()
    formats = page.split("## CSV formats", 1)[1]
    for columns in (ORIENTATION, POSITION, JUGGLING_COLUMNS):
        assert f"`{','.join(columns)}" in formats, columns


def test_using_envs_counts_and_names_every_id():
    """docs/using-envs.md once said five ids when there were nine."""
    import motion_envs

    words = {7: "seven", 8: "eight", 9: "nine", 10: "ten", 11: "eleven", 12: "twelve"}
    page = (ROOT / "docs" / "using-envs.md").read_text()
    n = len(motion_envs.ENV_IDS)
    assert f"registers {words[n]} Gymnasium ids" in page
    for env_id in motion_envs.ENV_IDS:
        assert f"`{env_id}`" in page, env_id


def test_the_sine_series_is_credited_to_lippi():
    """A tutorial once credited the sine series to Faraway & Choe (it is Lippi et al.'s;
    Faraway & Choe's model is the slerp residual with Bézier curves)."""
    import re

    for path in [*(ROOT / "examples").glob("*.py"), *(ROOT / "docs").rglob("*.md")]:
        for sentence in re.split(r"(?<=[.;])\s", " ".join(path.read_text().split())):
            if "sum of sines" in sentence or "sine series" in sentence.lower():
                assert "Faraway" not in sentence, f"{path.name}: {sentence}"
