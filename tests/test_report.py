"""report.html: every table and image of the results folder, parsed with html.parser."""

from __future__ import annotations

import base64
import json
from html.parser import HTMLParser

import pytest

from baselines.cli import main
from baselines.report import build_report, write_report
from motion_envs.models.paper_values import FARAWAY_CHOE_TABLE1


class _Collector(HTMLParser):
    """Tables (caption, header, rows of cell text), images and section titles."""

    def __init__(self) -> None:
        super().__init__()
        self.tables: list[dict] = []
        self.images: list[dict] = []
        self.h2: list[str] = []
        self._stack: list[str] = []
        self._text = ""

    def handle_starttag(self, tag, attrs):
        self._stack.append(tag)
        if tag == "table":
            self.tables.append({"caption": "", "header": [], "rows": []})
        elif tag == "tr":
            self.tables[-1]["rows"].append([])
        elif tag in ("td", "th", "caption", "h2"):
            self._text = ""
        elif tag == "img":
            self.images.append(dict(attrs))

    def handle_endtag(self, tag):
        if self._stack and self._stack[-1] == tag:
            self._stack.pop()
        text = self._text.strip()
        if tag == "td":
            self.tables[-1]["rows"][-1].append(text)
        elif tag == "th":
            self.tables[-1]["header"].append(text)
        elif tag == "caption":
            self.tables[-1]["caption"] = text
        elif tag == "h2":
            self.h2.append(text)

    def handle_data(self, data):
        self._text += data


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    out = tmp_path_factory.mktemp("results")
    jobs = [
        ("orientation-vr-kitchen", "Orientation on vr-kitchen", ["orientation"]),
        (
            "position-lasa",
            "Position on LASA",
            ["position", "--shapes", "GShape", "Angle", "Sshape", "--no-peers", "--no-progress"],
        ),
    ]
    index = {"jobs": []}
    for folder, title, argv in jobs:
        assert main([*argv, "--out", str(out / folder)]) == 0
        index["jobs"].append(
            {"folder": folder, "title": title, "command": " ".join(argv), "exit_code": 0}
        )
    (out / "index.json").write_text(json.dumps(index))
    return out


@pytest.mark.slow
def test_report_holds_every_table_image_and_paper_value(results):
    path = write_report(results)
    assert path.name == "report.html"
    page = _Collector()
    page.feed(path.read_text())
    assert page.h2 == ["Contents", "Orientation on vr-kitchen", "Position on LASA"]

    # orientation: one table, one row per criterion of results.json, the paper beside ours
    criteria = json.loads((results / "orientation-vr-kitchen" / "results.json").read_text())
    table1 = page.tables[0]
    assert table1["header"][:4] == ["criterion", "name", "ours (rad)", "paper (rad)"]
    body = [r for r in table1["rows"] if r]
    assert [r[1] for r in body] == list(criteria["criteria"])
    for row in body:
        ours = criteria["criteria"][row[1]]
        assert row[2] == f"{ours:.3f}"
        paper = FARAWAY_CHOE_TABLE1.get(row[1])
        assert row[3] == (f"{paper:.3f}" if paper is not None else "\u2013")

    # position: the summary, the per-shape wins and the timing tables
    doc = json.loads((results / "position-lasa" / "results.json").read_text())
    summary = next(t for t in page.tables if t["caption"].startswith("lasa: median"))
    assert summary["header"] == ["criterion", *doc["methods"], "paper"]
    rows = [r for r in summary["rows"] if r]
    assert len(rows) == len(doc["criteria"])
    assert rows[0][1 + doc["methods"].index("null")] == (
        f"{doc['summary_median_across_shapes']['null']['max_error']:.3f}"
    )
    assert any("lower max error" in " ".join(t["header"]) for t in page.tables[2:])
    assert all(t["caption"] for t in page.tables)

    # every image embedded as a PNG, one per plot written (learned_ratio.png included)
    written = [p for f in ("orientation-vr-kitchen", "position-lasa")
               for p in sorted((results / f).glob("*.png"))]  # fmt: skip
    assert len(page.images) == len(written) == 4
    for img in page.images:
        assert img["src"].startswith("data:image/png;base64,")
        assert base64.b64decode(img["src"].split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
        assert img["alt"]


@pytest.mark.slow
def test_report_is_self_contained_and_names_the_models_doc(results):
    text = build_report(results)
    assert "docs/models.md" in text and "MODELS.md" not in text.replace("docs/models.md", "")
    for needle in ('src="http', "src='http", "<script", "<link"):
        assert needle not in text


@pytest.mark.slow
def test_a_failed_or_unknown_job_is_reported_not_raised(results, tmp_path):
    index = json.loads((results / "index.json").read_text())
    index["jobs"].append({"folder": "juggling-sim", "title": "Juggling", "exit_code": 1})
    index["jobs"].append({"folder": "position-missing", "title": "Missing", "exit_code": 2})
    (tmp_path / "index.json").write_text(json.dumps(index))
    for job in index["jobs"][:2]:
        (tmp_path / job["folder"]).symlink_to(results / job["folder"])
    page = _Collector()
    page.feed(build_report(tmp_path))
    assert page.h2[-2:] == ["Juggling", "Missing"]


@pytest.mark.slow
def test_motion_bench_all_writes_the_report(tmp_path):
    out = tmp_path / "res"
    assert main(["all", "--out", str(out), "--only", "orientation-vr-kitchen"]) == 0
    page = _Collector()
    page.feed((out / "report.html").read_text())
    assert len(page.h2) == 2 and page.h2[0] == "Contents" and "vr-kitchen" in page.h2[1]
    # Table 1 and the learned comparisons; residuals.png and learned_ratio.png
    assert len(page.tables) == 2 and len(page.images) == 2


@pytest.mark.slow
def test_juggling_section_has_catch_rates_per_phase_errors_and_the_figure(tmp_path):
    folder = tmp_path / "juggling"
    argv = ["juggling", "--cycles", "12", "--world", "model", "--no-video", "--no-progress"]
    assert main([*argv, "--out", str(folder)]) == 0
    job = {"folder": "juggling", "title": "Juggling (SIMULATED)", "exit_code": 0}
    (tmp_path / "index.json").write_text(json.dumps({"jobs": [job]}))
    page = _Collector()
    page.feed(write_report(tmp_path).read_text())
    doc = json.loads((folder / "results.json").read_text())
    assert page.h2 == ["Contents", "Juggling (SIMULATED)"]
    catch, phases, validation = page.tables
    assert validation["header"][:2] == ["phase", "coordinate"]
    assert len([r for r in validation["rows"] if r]) == sum(map(len, doc["validation"].values()))
    # one row per catch-rate run: the unperturbed one, then each noise level off/on
    rates = [r for r in catch["rows"] if r]
    assert len(rates) == 1 + len(doc["catch_rates"])
    assert rates[0][3] == f"{doc['catch_rate']:.3f}"
    for row, run in zip(rates[1:], doc["catch_rates"], strict=True):
        assert row[2] == ("on" if run["correction"] else "off")
        assert row[3] == f"{run['catch_rate']:.3f}"
    # one row per phase: each method's max error (RMSE), within-person, the ratio
    methods = list(next(iter(doc["per_phase"].values()))["methods"])
    assert phases["header"] == ["phase", "N (sines)", *methods, "within-person", "lippi / within"]
    body = [r for r in phases["rows"] if r]
    assert [r[0] for r in body] == list(doc["per_phase"])
    for row, v in zip(body, doc["per_phase"].values(), strict=True):
        assert row[2] == (
            f"{v['methods']['lippi']['max_error']:.4f} ({v['methods']['lippi']['rmse']:.4f})"
        )
    # simulated data labelled as such in every table and the figure
    assert doc["simulated"]
    assert all("SIMULATED" in t["caption"] for t in page.tables)
    assert len(page.images) == 1 and "SIMULATED" in page.images[0]["alt"]
    assert base64.b64decode(page.images[0]["src"].split(",", 1)[1])[:4] == b"\x89PNG"


@pytest.mark.slow
def test_report_has_provenance_contents_learned_intervals_and_validation(results):
    """Once, report.html left out the learned-ratio figures, their intervals, the
    validation tables, and had no version, commit, date or table of contents."""
    import motion_envs

    text = build_report(results)
    page = _Collector()
    page.feed(text)
    assert f"motion-envs {motion_envs.__version__}, commit" in text and " UTC</p>" in text
    assert '<nav><h2>Contents</h2><ol class="toc"><li><a href="#orientation-vr-kitchen">' in text
    assert 'id="position-lasa"' in text
    learned = [t for t in page.tables if t["caption"].startswith("Learned vs analytic")]
    assert len(learned) == 2
    doc = json.loads((results / "position-lasa" / "results.json").read_text())
    first = doc["learned"]["comparisons"][0]
    row = next(r for r in learned[1]["rows"] if r)
    lo, hi = first["ratio_ci95"]
    assert row[2] == f"{first['ratio']:.3f}" and row[3] == f"[{lo:.3f}, {hi:.3f}]"
    validation = [t for t in page.tables if t["caption"].startswith("Validation")]
    assert len(validation) == 1
    shapes = {r[0] for r in validation[0]["rows"] if r}
    assert shapes == set(doc["per_shape"])
    assert sum("per group" in img["alt"] for img in page.images) == 2


@pytest.mark.slow
def test_juggling_animation_embedded_as_gif(tmp_path):
    folder = tmp_path / "juggling"
    folder.mkdir()
    argv = ["juggling", "--cycles", "12", "--world", "model", "--no-progress"]
    assert main([*argv, "--out", str(folder)]) == 0
    assert (folder / "juggling.gif").is_file()
    (tmp_path / "index.json").write_text(json.dumps({"jobs": [{"folder": "juggling"}]}))
    page = _Collector()
    page.feed(build_report(tmp_path))
    gifs = [i for i in page.images if i["src"].startswith("data:image/gif;base64,")]
    assert len(gifs) == 1 and "SIMULATED" in gifs[0]["alt"]
    assert base64.b64decode(gifs[0]["src"].split(",", 1)[1])[:6] in (b"GIF87a", b"GIF89a")


class _Paragraphs(HTMLParser):
    """The text of every ``<p>`` (tags inside it would end up outside: a raw ``<`` in a
    sentence starts a tag and cuts the sentence)."""

    def __init__(self) -> None:
        super().__init__()
        self.paragraphs: list[str] = []
        self._open = False

    def handle_starttag(self, tag, attrs):
        if tag == "p":
            self._open = True
            self.paragraphs.append("")
        elif self._open:
            self._open = False  # a tag inside the sentence: the browser cuts it here

    def handle_endtag(self, tag):
        if tag == "p":
            self._open = False

    def handle_data(self, data):
        if self._open:
            self.paragraphs[-1] += data


def test_every_reading_survives_an_html_parser(tmp_path):
    """Once, Juggling-v1's "Targets met: fixed_point<juggler_easy" wrote a raw ``<``:
    a browser's parser cut the sentence and swallowed the rest. Each section's reading is
    plain text that the page escapes (one place for every section): a parser gets the
    sentence back whole."""
    from baselines.report._html import BUILDERS

    levels = tmp_path / "juggling_v1-levels"
    levels.mkdir()
    method = {"catch_rate": 0.5, "catch_rate_ci": [0.4, 0.6]}
    method |= {"consecutive_catches_median": 2.0, "deviation_m": 0.01}
    doc = {
        "seeds": {"count": 10, "split": "test"},
        "demonstrations": "SIMULATED",
        "levels": [{"level": "easy", "methods": {"juggler": method}}],
        "targets": {
            "fixed_point<juggler_easy": {"met": True},
            "juggler>fixed & <b>": {"met": False},
        },
    }
    (levels / "results.json").write_text(json.dumps(doc))
    jobs = [{"folder": levels.name, "title": "Juggling-v1 <levels> & more", "exit_code": 0}]
    (tmp_path / "index.json").write_text(json.dumps({"jobs": jobs}))
    page = _Paragraphs()
    page.feed(build_report(tmp_path))
    readings = [
        BUILDERS[job["folder"].split("-", 1)[0]](tmp_path / job["folder"], job).reading
        for job in jobs
    ]
    assert "fixed_point<juggler_easy" in readings[-1]
    for reading in readings:
        assert reading in page.paragraphs
    titles = _Collector()
    titles.feed(build_report(tmp_path))
    assert titles.h2 == ["Contents", "Juggling-v1 <levels> & more"]
