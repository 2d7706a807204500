"""Reports from runs: real runs of the search with test doubles (whose SUT is wrong in
known places) and hand-made run directories for the hard cases (no tests, no failures,
only errors, captioning, SUT text with HTML and script tags)."""
import csv
import json
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy.stats import mannwhitneyu

from isu_validate.analysis import build_report, write_run_report
from isu_validate.analysis.failures import feature_errors
from isu_validate.analysis.multi_report import ReportSettings
from isu_validate.analysis.regions import failure_regions
from isu_validate.analysis.rq1 import comparisons, rate_key, run_rates
from isu_validate.analysis.runs import load_run
from isu_validate.analysis.timeline import band_by_tests, band_by_time
from isu_validate.archive import Archive
from isu_validate.archive import TestRecord as Record  # (a Test* name would be collected by pytest)
from isu_validate.cli import main
from isu_validate.pipeline import PipelineConfig
from isu_validate.search import RunConfig, run_search
from isu_validate.space import load_space
from tests.test_analysis_stats import brute_force_p

ROOT = Path(__file__).resolve().parent.parent
FACTORY = "tests.doubles:build"
EVIL = "<script>alert('owned')</script><img src=x onerror=alert(1)>"


# ------------------------------------------------------------------ hand-made run directories
def make_run(path: Path, tests: list[dict], algorithm="rs", seed=1, mode="vqa", sut="reference") -> Path:
    """A run directory written the way the search writes one; each test dict may give
    `scene`, `wrong` (feature -> answer), `sut_error`, `caption`, `f_emb`, `raw`."""
    space = load_space("isu-paper")
    path.mkdir(parents=True)
    (path / "images").mkdir()
    info = {"config": {"pipeline": {"run_dir": str(path), "space": "isu-paper", "sut": sut, "mode": mode,
                                    "threshold": None}, "algorithm": algorithm, "pop_size": 10, "seed": seed},
            "space": space.to_dict(), "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    (path / "run.json").write_text(json.dumps(info))
    archive = Archive(path / "archive.sqlite")
    rng = np.random.default_rng(seed)
    for i, spec in enumerate(tests):
        archive.add(_record(space, path, i, spec, algorithm, seed, mode, rng))
    archive.close()
    return path


def _record(space, path, i, spec, algorithm, seed, mode, rng) -> Record:
    scene = spec.get("scene") or space.sample(rng, 1)[0]
    canonical = space.canonical(scene)
    test_id = f"g{i // 10:04d}-i{i % 10:03d}"
    Image.new("RGB", (64, 48), tuple(int(v) for v in rng.integers(0, 255, 3))).save(path / "images" / f"{test_id}.png")
    record = Record(test_id=test_id, generation=i // 10, index=i % 10, algorithm=algorithm, seed=seed,
                        scene_key=space.key(scene), scene=scene, canonical=canonical, image=f"images/{test_id}.png",
                        created=time.time() + i * 0.01, timings={"render_s": 0.01, "sut_s": 0.01})
    if spec.get("sut_error"):
        record.sut_error, record.sut_raw, record.primary = spec["sut_error"], spec.get("raw", ""), 1.0
        return record
    record.sut_raw = spec.get("raw", "")
    if mode == "vc":
        record.caption = spec.get("caption", "a driver")
        record.fitness = {"f_emb": spec["f_emb"]}
        record.primary, record.failed = spec["f_emb"], spec["f_emb"] <= 0.65
        record.details = {"verdict": {"reference_caption": "a male driver wearing a seat belt"}}
        return record
    questions = space.questions(canonical)
    record.answers = {q.key: spec.get("wrong", {}).get(q.key, q.truth) for q in questions}
    total = sum(q.weight for q in questions)
    f_qa = sum(q.weight for q in questions if record.answers[q.key] == q.truth) / total
    record.fitness, record.primary, record.failed = {"f_qa": f_qa}, f_qa, f_qa < 1.0
    return record


def html_of(path: Path) -> str:
    return path.read_text(encoding="utf-8")


# ------------------------------------------------------------------ real runs (search + doubles)
@pytest.fixture(scope="module")
def runs_root(tmp_path_factory):
    """Two seeds of each algorithm, 30 tests each, through the real search loop."""
    root = tmp_path_factory.mktemp("runs")
    for algorithm in ("rs", "nsga2"):
        for seed in (1, 2):
            pipeline = PipelineConfig(run_dir=str(root / f"{algorithm}-{seed}"), factory=FACTORY)
            run_search(RunConfig(pipeline=pipeline, algorithm=algorithm, pop_size=10, seed=seed, budget_tests=30))
    return root


def test_the_run_command_writes_the_single_run_report(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    assert main(["run", "--out", str(tmp_path / "r"), "--pipeline-factory", FACTORY, "--budget", "10",
                 "--pop-size", "5"]) == 0
    html = html_of(tmp_path / "r" / "report.html")
    for heading in ("Summary", "Failure rates at thresholds", "Tests over time", "Failure analysis per feature",
                    "Failure regions", "Failing scenes", "SUT and render errors"):
        assert f"<h2>{heading}</h2>" in html


def test_the_single_run_report_shows_rates_with_one_decimal_as_the_report_over_runs(runs_root):
    from isu_validate.analysis import write_run_report
    from isu_validate.analysis.rq1 import run_rates

    run = sorted(runs_root.iterdir())[0]
    row = run_rates(load_run(run))
    html = html_of(write_run_report(run))
    rates = [row[rate_key(t)] for t in load_run(run).thresholds]
    assert any(round(r, 1) != round(r, 3) for r in rates)   # a rate such as 16.667 is on the page
    for r in rates:
        assert f"<td>{r:.1f}</td>" in html and f"<td>{r:.3f}</td>" not in html.replace(f"<td>{r:.1f}</td>", "")


def test_failure_analysis_finds_the_doubles_known_faults(runs_root):
    runs = [load_run(p) for p in sorted(runs_root.iterdir())]
    rows, pairs = feature_errors(runs)
    wrong = {r["feature"] for r in rows if r["wrong"]}
    assert wrong == {"seat_belt", "luggage_position"}  # the double errs about nothing else
    assert {(p["truth"], p["answer"]) for p in pairs if p["feature"] == "luggage_position"} == {("PASSENGER", "BACK")}
    for run in runs:  # seat belts are misread only in low external light
        for record in run.valid:
            misread = record.answers["seat_belt"] != run.truth(record)["seat_belt"]
            assert misread == (record.canonical["external_light"] == "LOW")
    tests = [r for run in runs for r in run.valid]
    rules = {r["rule"]: r for r in failure_regions(runs[0].space, [t.canonical for t in tests],
                                                   [t.failed for t in tests])}
    for fault in ("external_light = LOW", "luggage_position = PASSENGER"):  # the tree isolates both faults
        assert any(fault in rule and r["precision"] == 1.0 for rule, r in rules.items()), rules
    assert sum(r["failing"] for r in rules.values()) == sum(t.failed for t in tests)


def test_rates_agree_with_the_archive(runs_root):
    for path in sorted(runs_root.iterdir()):
        run = load_run(path)
        row = run_rates(run)
        assert row["failures"] == sum(r.failed for r in run.records)
        assert row[rate_key(1.0)] == pytest.approx(100.0 * row["failures"] / row["with_verdict"])
        rates = [row[rate_key(t)] for t in run.thresholds]
        assert rates == sorted(rates, reverse=True)  # a lower threshold can only fail fewer tests


def test_report_command_writes_html_and_every_table(runs_root, tmp_path, capsys):
    out = tmp_path / "report"
    assert main(["report", str(runs_root), "--out", str(out), "--embedding", "scene", "--clusters", "500"]) == 0
    html = html_of(out / "report.html")
    expected = ["runs", "rq1", "statistics", "timeline", "feature_errors", "confusions", "feature_values", "regions",
                "diversity", "diversity_runs", "diversity_statistics", "entropy_gaps", "clusters", "failures",
                "sut_errors"]
    for name in expected:
        assert (out / f"{name}.csv").is_file(), name
    report = json.loads((out / "report.json").read_text())
    assert set(expected) <= set(report["tables"])
    assert report["settings"]["embedding"] == "scene" and report["settings"]["clusters_requested"] == 500
    rq1 = list(csv.DictReader(open(out / "rq1.csv")))
    assert sorted(r["algorithm"] for r in rq1) == ["nsga2", "rs"]
    assert all(r["runs"] == "2" for r in rq1)
    stats = list(csv.DictReader(open(out / "statistics.csv")))
    runs = [load_run(p) for p in sorted(runs_root.iterdir())]
    assert [float(r["threshold"]) for r in stats] == list(runs[0].thresholds)
    for row in stats:  # each comparison is of the per-run failure rates at its threshold
        rates = {a: [run_rates(r)[rate_key(float(row["threshold"]))] for r in runs if r.algorithm == a]
                 for a in (row["a"], row["b"])}
        x, y = rates[row["a"]], rates[row["b"]]
        assert (row["a"], row["b"], row["method"]) == ("nsga2", "rs", "exact")
        assert (float(row["median_a"]), float(row["median_b"])) == pytest.approx((np.median(x), np.median(y)))
        assert float(row["U"]) == mannwhitneyu(x, y).statistic
        assert float(row["p"]) == pytest.approx(brute_force_p(np.array(x), np.array(y)))
        wins = sum((a > b) + 0.5 * (a == b) for a in x for b in y)
        assert float(row["A12"]) == pytest.approx(wins / (len(x) * len(y)))
    failing = {(r.name, t.test_id) for r in runs for t in r.failures}
    clusters = list(csv.DictReader(open(out / "clusters.csv")))
    assert {(c["run"], c["test_id"]) for c in clusters} == failing and len(clusters) == len(failing)
    assert "k lowered from 500" in html  # k larger than the number of failures
    gaps = list(csv.DictReader(open(out / "entropy_gaps.csv")))  # nsga2 - rs over five k-means seeds
    assert [(g["a"], g["b"], g["clusterings"]) for g in gaps] == [("nsga2", "rs", "5")]
    assert float(gaps[0]["min"]) <= float(gaps[0]["mean"]) <= float(gaps[0]["max"]) and "Entropy difference" in html
    assert " · cluster " in html  # gallery cards name their RQ2 cluster
    assert html.count("<script>") == 1 and "data:image/png;base64," in html


def test_the_report_states_thresholds_reads_as_prose_and_prints_its_failure_regions(runs_root, tmp_path, capsys):
    one = sorted(runs_root.iterdir())[0]
    out = tmp_path / "report"
    assert main(["report", str(one), "--out", str(out), "--embedding", "scene"]) == 0
    printed = capsys.readouterr()
    assert "report: 1 run, " in printed.err and "1 runs" not in printed.err
    rules = json.loads((out / "report.json").read_text())["tables"]["regions"]
    assert rules and "failure regions (decision-tree rules where most tests fail):" in printed.out
    for r in rules:   # the terminal says what the report's regions table says
        assert f"  {r['rule']}: {r['failing']} of {r['tests']} tests failing" in printed.out
    html = html_of(out / "report.html")
    runs = list(csv.DictReader(open(out / "runs.csv")))
    assert runs[0]["oracle_threshold"] == str(load_run(one).oracle_threshold)
    assert "<th>oracle_threshold</th>" in html and "1 run ·" in html
    assert "{'vqa'" not in html and "vqa: f_qa" in html   # settings read as prose, not Python dicts


def test_entropy_of_an_even_spread_is_exactly_one():
    from isu_validate.analysis.diversity import normalised_entropy
    for k in (5, 7, 12):   # float error: 1.0000000000000002 for 5 and 12, 0.9999999999999999 for 7 before rounding
        assert normalised_entropy(list(range(k)) * 3, k) == 1.0
    assert normalised_entropy([0, 0], 3) == 0.0


def test_report_errors_name_the_problem(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    assert main(["report", str(tmp_path / "empty"), "--out", str(tmp_path / "o")]) == 2
    assert "neither a run directory nor a folder of runs" in capsys.readouterr().err
    run = make_run(tmp_path / "r", [{}])
    assert main(["report", str(run), "--out", str(tmp_path / "o"), "--embedding", "vgg"]) == 2
    assert "unknown embedding 'vgg'" in capsys.readouterr().err
    assert main(["report", str(run), "--out", str(tmp_path / "o"), "--embedding", "clip:/no/such.pt"]) == 2
    assert "CLIP weights /no/such.pt not found" in capsys.readouterr().err


# ------------------------------------------------------------------ hard cases
def test_run_with_no_tests(tmp_path):
    run = make_run(tmp_path / "r", [])
    (run / "archive.sqlite").unlink()
    html = html_of(write_run_report(run))
    assert "no evaluated tests" in html and "No failing tests." in html
    out = build_report([run], tmp_path / "rep", ReportSettings(embedding="scene"))
    assert "no failures to cluster" in html_of(out)


def test_run_with_zero_failures(tmp_path):
    run = make_run(tmp_path / "r", [{} for _ in range(12)])
    html = html_of(write_run_report(run))
    assert "No failing tests." in html and "No region: no failures." in html
    out = tmp_path / "rep"
    build_report([run, make_run(tmp_path / "n", [{} for _ in range(5)], algorithm="nsga2")], out,
                 ReportSettings(embedding="scene"))
    diversity = {r["algorithm"]: r for r in csv.DictReader(open(out / "diversity.csv"))}
    assert diversity["rs"]["failures"] == "0" and diversity["rs"]["entropy"] == ""  # undefined, not 0
    stats = list(csv.DictReader(open(out / "statistics.csv")))
    assert all(r["p"] == "1.0" and r["note"] == "all values tied" for r in stats)


def test_run_with_only_sut_errors(tmp_path):
    run = make_run(tmp_path / "r", [{"sut_error": "HTTP 503 from the SUT"} for _ in range(4)])
    loaded = load_run(run)
    row = run_rates(loaded)
    assert (row["tests"], row["with_verdict"], row["failures"], row["sut_errors"]) == (4, 0, 0, 4)
    html = html_of(write_run_report(run))
    assert html.count("HTTP 503 from the SUT") == 4
    assert "<b>4</b>SUT errors" in html and "<b>0</b>failures" in html


def test_sut_text_with_html_and_script_is_escaped(tmp_path):
    space = load_space("isu-paper")
    scene = space.sample(np.random.default_rng(0), 1)[0]
    tests = [{"scene": scene, "wrong": {"seat_belt": EVIL}, "raw": EVIL},
             {"sut_error": f"bad reply {EVIL}", "raw": EVIL}]
    run = make_run(tmp_path / "r", tests)
    vc = make_run(tmp_path / "c", [{"caption": EVIL, "f_emb": 0.2}], mode="vc")
    pages = [html_of(write_run_report(run)), html_of(write_run_report(vc)),
             html_of(build_report([run, vc], tmp_path / "rep", ReportSettings(embedding="scene")))]
    for html in pages:
        assert "alert('owned')</script>" not in html and "<img src=x" not in html
        assert html.count("<script>") == 1  # the report's own
        assert "&lt;script&gt;alert(&#x27;owned&#x27;)&lt;/script&gt;" in html


def test_captioning_thresholds_follow_the_oracle(tmp_path):
    run = load_run(make_run(tmp_path / "c", [{"f_emb": v} for v in (0.8, 0.65, 0.3, 0.9)], mode="vc"))
    row = run_rates(run)
    assert run.thresholds == (0.8, 0.7, 0.6, 0.5)
    # F_emb <= t fails: 0.8 fails at 0.8
    assert [row[rate_key(t)] for t in run.thresholds] == [75.0, 50.0, 25.0, 25.0]
    assert row["failures"] == 2  # the run's own oracle at 0.65


def test_vqa_thresholds_fail_strictly_below(tmp_path):
    space = load_space("isu-paper")
    rng = np.random.default_rng(4)
    scenes = [s for s in space.sample(rng, 40) if s["child_seat"] == "NO" and s["luggage"] == "NO"][:2]
    # weights of the always-asked questions sum to 0.7: one wrong 0.05-weight answer gives 0.65/0.7
    can = "colacan_codriver_seat"
    run = load_run(make_run(tmp_path / "r", [{"scene": scenes[0], "wrong": {can: "NO" if scenes[0][can] == "YES"
                                                                              else "YES"}}, {"scene": scenes[1]}]))
    row = run_rates(run)
    assert row[rate_key(1.0)] == 50.0 and row[rate_key(0.9)] == 0.0


def test_time_bands_with_runs_of_different_length(tmp_path):
    long = load_run(make_run(tmp_path / "a", [{"wrong": {"driver_gender": "NONE"}} for _ in range(6)]))
    short = load_run(make_run(tmp_path / "b", [{"wrong": {"driver_gender": "NONE"}} for _ in range(3)], seed=2))
    band = band_by_tests([long, short])
    assert list(band.mean) == [1, 2, 3, 4, 5, 6] and list(band.runs) == [2, 2, 2, 1, 1, 1]
    assert list(band.std[:3]) == [0, 0, 0]
    wall = band_by_time([long, short])
    assert wall.mean[-1] == pytest.approx((6 + 3) / 2)  # a finished run keeps its final count


def test_runs_of_different_spaces_are_not_mixed(tmp_path):
    a = make_run(tmp_path / "a", [{}])
    b = make_run(tmp_path / "b", [{}], algorithm="nsga2")
    info = json.loads((b / "run.json").read_text())
    info["space"]["features"]["driver_height"]["values"] = ["H1", "H2"]
    (b / "run.json").write_text(json.dumps(info))
    with pytest.raises(ValueError, match="searched different scene spaces"):
        build_report([a, b], tmp_path / "rep", ReportSettings(embedding="scene"))


def test_comparison_with_an_algorithm_without_verdicts_says_why(tmp_path):
    a = make_run(tmp_path / "a", [{"wrong": {"colacan_codriver_seat": "NONE"}}, {}], algorithm="nsga2")
    b = make_run(tmp_path / "b", [{"sut_error": "refused"}], algorithm="rs")
    rows = comparisons([load_run(a), load_run(b)])
    assert rows and all(r["method"] == "undefined" for r in rows)
    assert rows[0]["note"] == "no run of rs has a test with a verdict: nothing to compare"


def test_runs_with_the_same_folder_name_get_distinct_names(tmp_path):
    a = make_run(tmp_path / "exp1" / "rs-1", [{"wrong": {"colacan_codriver_seat": "NONE"}}])
    b = make_run(tmp_path / "exp2" / "rs-1", [{}], seed=2)
    build_report([a, b], tmp_path / "rep", ReportSettings(embedding="scene"))
    names = [r["run"] for r in csv.DictReader(open(tmp_path / "rep" / "runs.csv"))]
    assert names == ["exp1/rs-1", "exp2/rs-1"]


def test_gallery_lets_runs_take_turns_among_equal_failures(tmp_path):
    from isu_validate.analysis.gallery import pick
    scene = load_space("isu-paper").sample(np.random.default_rng(0), 1)[0]   # one scene: equal fitness by design
    runs = [load_run(make_run(tmp_path / name, [{"scene": scene, "wrong": {"driver_gender": "NONE"}}] * 4, seed=i))
            for i, name in enumerate(["a", "b"])]
    chosen = pick([(run, rec) for run in runs for rec in run.failures], limit=4)
    assert [run.name for run, _ in chosen] == ["a", "b", "a", "b"]
