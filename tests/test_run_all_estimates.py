"""``motion-bench all`` prints a measured estimate before each long job, records each
job's CPU time in the index, and the README's total is the jobs' measured sum."""

from __future__ import annotations

import re
from pathlib import Path

from baselines import run_all

ROOT = Path(__file__).resolve().parents[1]


def test_a_long_job_is_announced_with_its_measured_cpu_time():
    long = [job for job in run_all.JOBS if job.cpu_seconds >= run_all.LONG_JOB_CPU_SECONDS]
    assert len(long) >= 3  # vr-kitchen, LASA, the juggling levels at least
    for job in run_all.JOBS:
        line = job.estimate("full")
        if job in long:
            assert line is not None and f"about {job.cpu_seconds:.0f} s of CPU time" in line
            assert run_all.MEASURED in line
            assert "(less at quick)" in (job.estimate("quick") or "")
        else:
            assert line is None


def test_the_run_prints_the_estimate_first_and_records_cpu_time(tmp_path, monkeypatch):
    """The cohort job (short) announced as if it were long: the line comes right after
    its title, before its tables; the index holds its CPU seconds."""
    import dataclasses

    jobs = tuple(
        dataclasses.replace(job, cpu_seconds=99.0) if job.folder == "orientation-cohort" else job
        for job in run_all.JOBS
    )
    monkeypatch.setattr(run_all, "JOBS", jobs)
    lines: list[str] = []
    index = run_all.run(
        run_all.AllConfig(out=tmp_path, only=("orientation-cohort",), progress=False),
        echo=lines.append,
    )
    assert lines[1].startswith("estimate: about 99 s of CPU time")
    assert "Orientation trajectories on the virtual cohort" in lines[0]
    (entry,) = index["jobs"]
    assert 0 < entry["cpu_seconds"] < 60 and entry["seconds"] > 0


def test_the_readme_total_is_the_jobs_measured_sum():
    readme = (ROOT / "README.md").read_text()
    total = sum(job.cpu_seconds for job in run_all.JOBS)
    said = re.search(r"`motion-bench all` used (\d+) s of CPU time", readme)
    assert said is not None and abs(int(said.group(1)) - total) <= 3, (said, total)
