"""What a set of scenario runs adds up to: DIR/summary.json (every run's name, seed, verdict and
metrics; overall counts and the success rate with its 95 % Wilson interval; each metric's
quantiles; the worst runs) and DIR/report.md with PNGs under DIR/plots (each judged metric's
histogram and CDF with its bounds, and for a sweep each drawn value against pass/fail)."""

from __future__ import annotations

import json
import math
import shlex
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

Z_95 = 1.959963984540054  # standard normal quantile for a two-sided 95 % interval
QUANTILES = (0.0, 0.05, 0.25, 0.5, 0.75, 0.95, 1.0)
QUANTILE_NAMES = tuple(f"q{round(100 * q):02d}" for q in QUANTILES)  # q00 = min, q100 = max
WORST_RUNS = 10  # how many of the worst runs the report lists
# Measured on the wall clock, so they differ from play to play; every other metric of a lockstep
# run repeats exactly (the same record, whatever the machine's load).
WALL_CLOCK_METRICS = ("wall_time", "loop_wall_time")


def without_wall_clock(metrics: dict) -> dict:
    """A run's metrics without WALL_CLOCK_METRICS: what a replay of the run must repeat."""
    return {k: v for k, v in metrics.items() if k not in WALL_CLOCK_METRICS}


def wilson_interval(successes: int, runs: int, z: float = Z_95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (sound near 0 and 1, unlike p +- z*se)."""
    if runs == 0:
        return (0.0, 1.0)
    p = successes / runs
    centre = (p + z * z / (2 * runs)) / (1 + z * z / runs)
    half = z / (1 + z * z / runs) * math.sqrt(p * (1 - p) / runs + z * z / (4 * runs * runs))
    return (max(0.0, centre - half), min(1.0, centre + half))


def headline(values: dict) -> dict:
    """The few numbers worth a plot title and a summary row."""
    picks = {
        "lap_time": values.get("lap", {}).get("lap_time"),
        "xte_rms_cm": 100 * values["cross_track"]["rms"] if "cross_track" in values else None,
        "xte_max_cm": 100 * values["cross_track"]["max"] if "cross_track" in values else None,
        "stop_dist": values.get("target", {}).get("final_distance"),
        "park_err_cm": 100 * values["parking"]["position_error"] if "parking" in values else None,
        "missed": values["commands"]["missed_replies"],
        "sim_s": values["sim_time"],
        "wall_s": values.get("wall_time"),
    }
    return {k: v for k, v in picks.items() if v is not None}


def format_value(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def headline_text(run: dict) -> str:
    """A finished run's headline numbers on one line, or why it could not be played."""
    if "error" in run:
        return run["error"]
    return ", ".join(f"{k}={format_value(v)}" for k, v in headline(run["metrics"]).items())


def flatten(values, prefix: str = "") -> dict[str, float]:
    """Every finite number in nested metrics by dotted path (list items by index); no booleans."""
    items: Iterable[tuple[Any, Any]]
    if isinstance(values, dict):
        items = values.items()
    elif isinstance(values, list):
        items = enumerate(values)
    else:
        ok = isinstance(values, int | float) and not isinstance(values, bool)
        return {prefix: float(values)} if ok and math.isfinite(values) else {}
    out: dict[str, float] = {}
    for key, value in items:
        out.update(flatten(value, f"{prefix}.{key}" if prefix else str(key)))
    return out


def distributions(runs: list[dict]) -> dict[str, dict]:
    """Each metric's count, mean and quantiles (QUANTILES) over the runs that have it."""
    columns: dict[str, list[float]] = {}
    for run in runs:
        for path, value in flatten(run.get("metrics") or {}).items():
            columns.setdefault(path, []).append(value)
    out = {}
    for path, values in sorted(columns.items()):
        quantiles = np.quantile(values, QUANTILES)
        out[path] = {
            "count": len(values),
            "mean": float(np.mean(values)),
            **{name: float(v) for name, v in zip(QUANTILE_NAMES, quantiles, strict=True)},
        }
    return out


def tightest(run: dict) -> dict | None:
    """The run's criterion row with the least margin (a missing value counts as the least)."""
    rows = run.get("criteria", [])
    return min(rows, key=lambda c: -math.inf if c["margin"] is None else c["margin"], default=None)


def worst(runs: list[dict], count: int = WORST_RUNS) -> list[dict]:
    """The `count` worst runs: those that could not run, then failures, then the smallest
    margin to any criterion's bound."""

    def badness(run: dict) -> tuple:
        row = tightest(run)
        margin = math.inf if row is None else row["margin"]
        return ("error" not in run, run["passed"], -math.inf if margin is None else margin)

    return sorted(runs, key=badness)[:count]


def failures_by_criterion(runs: list[dict]) -> dict[str, dict]:
    """For each criterion some run failed: how many runs failed it, and how many failed only it
    (what the success rate would gain if that one held)."""
    out: dict[str, dict] = {}
    for run in runs:
        failed = [c["metric"] for c in run["criteria"] if not c["passed"]]
        for metric in failed:
            counts = out.setdefault(metric, {"runs": 0, "only": 0})
            counts["runs"] += 1
            counts["only"] += len(failed) == 1
    return dict(sorted(out.items(), key=lambda item: -item[1]["runs"]))


def summarise(results: list[dict]) -> dict:
    runs = [
        {
            "name": r["scenario"],
            "seed": r.get("seed"),
            "source": r.get("source"),
            "parameters": r.get("parameters") or {},
            "passed": r["passed"],
            **({"error": r["error"]} if "error" in r else {}),
            "criteria": r.get("criteria", []),
            "metrics": r.get("metrics"),
        }
        for r in results
    ]
    passed = sum(r["passed"] for r in runs)
    errors = sum("error" in r for r in runs)
    return {
        "runs": runs,
        "overall": {
            "runs": len(runs),
            "passed": passed,
            "failed": len(runs) - passed - errors,
            "errors": errors,
            "success_rate": passed / len(runs) if runs else 0.0,
            "success_interval_95": list(wilson_interval(passed, len(runs))),
            "failures_by_criterion": failures_by_criterion(runs),
        },
        "distributions": distributions(runs),
        "worst": [run["name"] for run in worst(runs)],
    }


def _criterion_text(row: dict) -> str:
    return f"{row['metric']} = {format_value(row['value'])} ({row['rule']})"


def replay_command(run: dict) -> str:
    source = shlex.quote(run["source"] or "SCENARIO.yaml")
    return f"rosrun harness run_scenario {source} --select {shlex.quote(run['name'])}"


def markdown(summary: dict, plots: dict[str, str]) -> str:
    overall = summary["overall"]
    low, high = overall["success_interval_95"]
    lines = [
        "# Scenario runs",
        "",
        f"{overall['passed']} of {overall['runs']} passed ({overall['failed']} failed, "
        f"{overall['errors']} could not run): success rate {overall['success_rate']:.3f}, "
        f"95 % Wilson interval [{low:.3f}, {high:.3f}].",
        "",
        "| run | seed | verdict | numbers | failed criteria |",
        "| --- | --- | --- | --- | --- |",
    ]
    for run in summary["runs"]:
        verdict = "ERROR" if "error" in run else "pass" if run["passed"] else "**FAIL**"
        numbers = headline_text(run)
        failed = "; ".join(_criterion_text(c) for c in run["criteria"] if not c["passed"])
        seed = "" if run["seed"] is None else run["seed"]
        link = f"[{run['name']}]({run['name']}/run.png)"
        lines.append(f"| {link} | {seed} | {verdict} | {numbers} | {failed} |")

    if overall["failures_by_criterion"]:
        lines += ["", "## Failures by criterion", "", "| criterion | runs failing it | "
                  "failing only it |", "| --- | --- | --- |"]  # fmt: skip
        for metric, counts in overall["failures_by_criterion"].items():
            lines.append(f"| {metric} | {counts['runs']} | {counts['only']} |")

    by_name = {run["name"]: run for run in summary["runs"]}
    lines += [
        "",
        "## Worst runs",
        "",
        "Those that could not run, then failures, then the least margin to a criterion's bound "
        "(the fraction of the bound's size still free). Replay one by name with the command.",
        "",
        "| run | seed | verdict | tightest criterion | margin | drawn values | replay |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for name in summary["worst"]:
        run = by_name[name]
        row = tightest(run)
        verdict = "ERROR" if "error" in run else "pass" if run["passed"] else "**FAIL**"
        criterion = run.get("error", "") if row is None else _criterion_text(row)
        margin = "" if row is None else format_value(row["margin"])
        drawn = ", ".join(f"{k}={format_value(v)}" for k, v in run["parameters"].items())
        seed = "" if run["seed"] is None else run["seed"]
        lines.append(
            f"| {name} | {seed} | {verdict} | {criterion} | {margin} | {drawn} | "
            f"`{replay_command(run)}` |"
        )

    lines += [
        "",
        "## Metric distributions",
        "",
        "Over the runs that have the metric; q00 is the minimum, q50 the median, q100 the "
        "maximum." + (" Judged metrics link their histogram and CDF." if plots else ""),
        "",
        "| metric | runs | mean | " + " | ".join(QUANTILE_NAMES) + " |",
        "| --- | --- | --- |" + " --- |" * len(QUANTILE_NAMES),
    ]
    for metric, d in summary["distributions"].items():
        label = f"[{metric}]({plots[metric]})" if metric in plots else metric
        numbers = " | ".join(format_value(d[q]) for q in QUANTILE_NAMES)
        lines.append(f"| {label} | {d['count']} | {format_value(d['mean'])} | {numbers} |")
    if "parameters" in plots:
        lines += ["", "## Drawn values", "", f"![drawn values]({plots['parameters']})"]
    return "\n".join(lines) + "\n"


def _save(figure: Figure, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(figure).print_png(str(path))


def plot_metric(path: Path, metric: str, values: list[float], bounds: list[float]) -> None:
    """Histogram and empirical CDF of one metric over the runs, its bounds as red lines."""
    figure = Figure(figsize=(9, 3.2), layout="constrained")
    histogram, cdf = figure.subplots(1, 2)
    histogram.hist(values, bins=min(30, max(5, len(values) // 4)), color="tab:blue")
    histogram.set_ylabel("runs")
    ordered = np.sort(values)
    cdf.step(ordered, np.arange(1, len(ordered) + 1) / len(ordered), where="post")
    cdf.set_ylabel("fraction of runs <= value")
    for ax in (histogram, cdf):
        ax.set_xlabel(metric)
        for bound in bounds:
            ax.axvline(bound, color="tab:red", linestyle="--")
    figure.suptitle(f"{metric} over {len(values)} runs")
    _save(figure, path)


def plot_parameters(path: Path, runs: list[dict]) -> None:
    """For each drawn number, its histogram split into passed and failed runs."""
    names = sorted({k for r in runs for k, v in r["parameters"].items() if _is_number(v)})
    figure = Figure(figsize=(4 * len(names), 3.2), layout="constrained")
    for ax, name in zip(np.atleast_1d(figure.subplots(1, len(names))), names, strict=True):
        drawn = [r for r in runs if name in r["parameters"]]
        passed = [r["parameters"][name] for r in drawn if r["passed"]]
        failed = [r["parameters"][name] for r in drawn if not r["passed"]]
        ax.hist([passed, failed], bins=12, stacked=True, color=["tab:green", "tab:red"],
                label=["passed", "failed"])  # fmt: skip
        ax.set_xlabel(name)
        ax.set_ylabel("runs")
    ax.legend()
    _save(figure, path)


def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def write_plots(out: Path, summary: dict) -> dict[str, str]:
    """PNGs under out/plots: each judged metric with a value in two or more runs, and the drawn
    values when runs were drawn. Returns their paths relative to `out`, by metric."""
    runs = summary["runs"]
    if len(runs) < 2:
        return {}
    bounds: dict[str, set[float]] = {}
    for run in runs:
        for row in run["criteria"]:
            rule_bounds = bounds.setdefault(row["metric"], set())
            rule_bounds.update(float(b) for b in row["rule"].split() if _is_float(b))
    plots = {}
    for metric, metric_bounds in sorted(bounds.items()):
        found = [flatten(run["metrics"] or {}).get(metric) for run in runs if "error" not in run]
        values = [v for v in found if v is not None]
        if len(values) >= 2 and len(set(values)) > 1:
            plots[metric] = f"plots/{metric}.png"
            plot_metric(out / plots[metric], metric, values, sorted(metric_bounds))
    if any(any(_is_number(v) for v in run["parameters"].values()) for run in runs):
        plots["parameters"] = "plots/parameters.png"
        plot_parameters(out / plots["parameters"], runs)
    return plots


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def write_summary(out: Path, results: list[dict]) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    summary = summarise(results)
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=float))
    (out / "report.md").write_text(markdown(summary, write_plots(out, summary)))
    return summary
