"""What a set of scenario runs adds up to: DIR/summary.json (every run's name, seed, verdict and
metrics; overall counts and the success rate with its 95 % Wilson interval) and DIR/report.md."""

from __future__ import annotations

import json
import math
from pathlib import Path

Z_95 = 1.959963984540054  # standard normal quantile for a two-sided 95 % interval


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


def summarise(results: list[dict]) -> dict:
    runs = [
        {
            "name": r["scenario"],
            "seed": r.get("seed"),
            "passed": r["passed"],
            **({"error": r["error"]} if "error" in r else {}),
            "failed_criteria": [c for c in r.get("criteria", []) if not c["passed"]],
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
        },
    }


def markdown(summary: dict) -> str:
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
        if "error" in run:
            verdict, numbers = "ERROR", run["error"]
        else:
            verdict = "pass" if run["passed"] else "**FAIL**"
            numbers = ", ".join(
                f"{k}={format_value(v)}" for k, v in headline(run["metrics"]).items()
            )
        failed = "; ".join(
            f"{c['metric']} = {format_value(c['value'])} ({c['rule']})"
            for c in run["failed_criteria"]
        )
        seed = "" if run["seed"] is None else run["seed"]
        link = f"[{run['name']}]({run['name']}/run.png)"
        lines.append(f"| {link} | {seed} | {verdict} | {numbers} | {failed} |")
    return "\n".join(lines) + "\n"


def write_summary(out: Path, results: list[dict]) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    summary = summarise(results)
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=float))
    (out / "report.md").write_text(markdown(summary))
    return summary
