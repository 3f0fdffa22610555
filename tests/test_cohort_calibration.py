"""Virtual cohort configs (validation, packaging) and ``motion-bench calibrate-cohort``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml

from baselines.calibrate_cohort import (
    PAPER_TARGETS,
    calibrate,
    cohort_criteria,
    format_report,
    relative_miss,
)
from baselines.cli import main
from motion_envs.datasets.cohort_config import (
    CALIBRATED_PARAMETERS,
    CohortConfig,
    available_cohorts,
    load_cohort_config,
    resolve_cohort_config,
)

REPO = Path(__file__).resolve().parents[1]


def _tiny(**values) -> CohortConfig:
    return load_cohort_config("faraway2008").with_values(**{"design.n_subjects": 3, **values})


def test_shipped_config_is_the_package_file():
    """``configs/cohorts/NAME.yaml`` of the checkout is the package's file (through the
    link, tests/test_packaged_configs.py), not a copy."""
    assert "faraway2008" in available_cohorts()
    packaged = REPO / "motion_envs" / "datasets" / "cohorts" / "faraway2008.yaml"
    assert resolve_cohort_config("faraway2008").resolve() == packaged.resolve()


def test_committed_config_records_its_calibration():
    cfg = load_cohort_config("faraway2008")
    cal = cfg.get("calibration")
    assert cal["target"] == "paper"
    assert set(cal["achieved"]) >= set(PAPER_TARGETS)
    assert cfg.get("simulated") is True
    assert resolve_cohort_config("faraway2008").name == "faraway2008.yaml"


def test_save_and_load_round_trip(tmp_path):
    cfg = _tiny()
    back = load_cohort_config(cfg.save(tmp_path / "c.yaml"))
    assert back.data == cfg.data
    assert (tmp_path / "c.yaml").read_text().startswith("# Virtual cohort configuration")


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("design.n_subjects", 0, "design.n_subjects"),
        ("design.dropout", 1.0, "design.dropout"),
        ("design.requested_tasks", ["low-centre-nowhere"], "design.requested_tasks"),
        ("residual.trial.scale", -0.1, "residual.trial.scale"),
        ("residual.decay", "smooth", "residual.decay"),
        ("speed_profile.a", 0.0, "speed_profile.a"),
        ("simulated", False, "simulated"),
        ("residual.common.coefficients", [[1.0, 0.0]], "residual.common.coefficients"),
    ],
)
def test_bad_values_name_the_key(key, value, message):
    with pytest.raises(ValueError, match=message.replace(".", r"\.")):
        _tiny(**{key: value})


def test_unknown_and_missing_keys(tmp_path):
    data = _tiny().data
    data["residual"]["elbow"] = 1
    with pytest.raises(ValueError, match="unknown key"):
        CohortConfig(data)
    del data["residual"]["elbow"]
    del data["durations"]["base_s"]
    with pytest.raises(ValueError, match=r"durations\.base_s"):
        CohortConfig(data)
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: [unclosed\n")
    with pytest.raises(ValueError, match="not valid YAML"):
        load_cohort_config(bad)
    with pytest.raises(ValueError, match="unknown cohort"):
        load_cohort_config("no-such-cohort")


def test_relative_miss():
    assert relative_miss(0.25, (0.242, 0.265)) == 0.0
    assert relative_miss(0.3, (0.242, 0.265)) == pytest.approx(math.log(0.3 / 0.265))
    assert relative_miss(0.2, (0.25, 0.25)) == pytest.approx(math.log(0.8))


def test_calibration_recovers_a_known_target():
    """Targets computed at known parameters are met again from a perturbed start."""
    truth = _tiny()
    names = ("within_subject", "slerp_empirical", "null_d2")
    want = cohort_criteria(truth)
    targets = {n: (want[n], want[n]) for n in names}
    start = truth.with_values(
        **{
            "residual.trial.scale": truth.get("residual.trial.scale") * 1.6,
            "residual.common.scale": truth.get("residual.common.scale") * 0.7,
        }
    )
    first = cohort_criteria(start)
    assert max(abs(relative_miss(first[n], targets[n])) for n in names) > 0.1
    result = calibrate(start, targets, max_evaluations=40, progress=False)
    assert set(result.config.calibrated_values()) == set(CALIBRATED_PARAMETERS)
    for name, dev in result.deviations().items():
        assert abs(dev) < 2.0, (name, dev)
    # the achieved values are what the returned config really gives
    again = cohort_criteria(result.config)
    for n in names:
        assert again[n] == pytest.approx(result.achieved[n], abs=1e-12)
    assert "achieved" in format_report(result)


def test_calibration_rejects_bad_targets():
    with pytest.raises(ValueError, match="interval"):
        calibrate(_tiny(), {"within_subject": (0.2, 0.1)}, progress=False)
    with pytest.raises(ValueError, match="not computed"):
        calibrate(_tiny(), {"null_d7": (0.1, 0.1)}, max_evaluations=3, progress=False)


def test_cli_writes_a_calibrated_config(tmp_path, capsys):
    src = _tiny().save(tmp_path / "tiny.yaml")
    target = tmp_path / "target.json"
    target.write_text(json.dumps({"within_subject": 0.11, "between_subject": [0.2, 0.3]}))
    out = tmp_path / "out.yaml"
    code = main(
        [
            "calibrate-cohort",
            "--config",
            str(src),
            "--target",
            str(target),
            "--out",
            str(out),
            "--max-evaluations",
            "25",
            "--check-seeds",
            "1",
            "--no-progress",
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "within_subject" in text and "achieved" in text and f"wrote {out}" in text
    written = yaml.safe_load(out.read_text())
    assert written["calibration"]["target"] == str(target)
    start = cohort_criteria(_tiny())["within_subject"]
    achieved = written["calibration"]["achieved"]["within_subject"]
    assert abs(achieved - 0.11) < abs(start - 0.11)  # a short budget: better, not done
    assert load_cohort_config(out).data == {**written}
    assert main(["calibrate-cohort", "--target", "nonsense", "--config", str(src)]) == 2
