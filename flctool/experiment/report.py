"""The summary of an experiment (summary.json) and its report (report.md), read from the run
directories alone, so they come out the same whoever ran the jobs.

Learners are compared at equal numbers of training episodes: a generation of every learner is
``population x trials`` episodes (fuzzy_q's "generation" is that many episodes of its one
controller), and every curve is drawn over cumulative episodes. Wall time is left out: it
depends on the machine, not on the result.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.atomic import write_text_atomic
from flctool.errors import RunDirError
from flctool.experiment.runner import Experiment, read_heldout
from flctool.experiment.statistics import (
    Comparison,
    area,
    band,
    compare,
    first_crossing,
    halfway_level,
    quartiles,
)
from flctool.rollout import wilson_interval
from flctool.runs import open_run

FloatArray = NDArray[np.float64]
SUMMARY_FILE = "summary.json"
REPORT_FILE = "report.md"
#: One-sided significance level at which a claim counts as shown.
SIGNIFICANCE = 0.05
CLAIM_LEARNERS = ("hybrid", "pitt")


@dataclass(frozen=True)
class RunRecord:
    """What one run measured: per-generation curves (G,) and its totals."""

    learner: str
    seed: int
    mean: FloatArray
    std: FloatArray
    episodes: FloatArray  # cumulative training episodes at the end of each generation
    training_episodes: int
    training_steps: int
    selection_episodes: int
    selection_steps: int
    heldout: dict[str, Any]


def read_records(experiment: Experiment) -> list[RunRecord]:
    """Every run of the experiment, in job order; :class:`RunDirError` if one is unfinished."""
    records = []
    for learner, seed, directory in experiment.run_dirs():
        if not directory.is_dir():
            raise RunDirError(f"{directory}: this run has not started",
                              hint=f"run the experiment to the end: flctool experiment ... "
                              f"--out {experiment.path}")
        run = open_run(directory)
        metrics = run.metrics()
        if not metrics:
            raise RunDirError(f"{directory}: the run has no finished generation",
                              hint="run the experiment to the end")
        # training and model selection (validation episodes), as the run recorded them
        usage = run.summary().usage
        records.append(RunRecord(
            learner, seed, np.array([m.mean for m in metrics]),
            np.array([m.std for m in metrics]),
            np.cumsum([m.episodes for m in metrics]).astype(np.float64),
            int(sum(m.episodes for m in metrics)), int(sum(m.steps for m in metrics)),
            usage.selection_episodes if usage else 0, usage.selection_steps if usage else 0,
            read_heldout(directory)))
    return records


def _stats(values: list[float]) -> dict[str, Any]:
    low, median, high = quartiles(np.array(values))
    finite = [v for v in values if math.isfinite(v)]
    return {"values": [None if not math.isfinite(v) else v for v in values],
            "q25": _json_float(low), "median": _json_float(median), "q75": _json_float(high),
            "mean": float(np.mean(finite)) if len(finite) == len(values) else None,
            "reached": len(finite), "n": len(values)}


def _json_float(x: float) -> float | None:
    return x if math.isfinite(x) else None


def _comparison(metric: str, a: str, b: str, result: Comparison) -> dict[str, Any]:
    return {"metric": metric, "a": a, "b": b, "u": result.u, "p": result.p,
            "p_a_greater": result.p_greater, "effect_a_greater": result.effect}


def _values(entry: dict[str, Any]) -> FloatArray:
    return np.array([math.inf if v is None else v for v in entry["values"]])


def summarise(experiment: Experiment, level: float | None = None) -> dict[str, Any]:
    """Everything the report states, JSON-ready. ``level``: the mean fitness whose first
    crossing is reported as "episodes to reach the level" (default: half way from the lowest
    first-generation median to the highest last-generation median over the learners)."""
    records = read_records(experiment)
    plan = experiment.plan
    by_learner = {name: [r for r in records if r.learner == name] for name in plan.learners}
    curves: dict[str, Any] = {}
    for name, runs in by_learner.items():
        mean, std = band([r.mean for r in runs]), band([r.std for r in runs])
        longest = max(runs, key=lambda r: len(r.episodes))
        curves[name] = {"episodes": longest.episodes.tolist(), "runs": mean.n.tolist(),
                        "mean": _band_dict(mean), "std": _band_dict(std)}
    if level is None:
        level = halfway_level(min(c["mean"]["median"][0] for c in curves.values()),
                              max(c["mean"]["median"][-1] for c in curves.values()))
    learners: dict[str, Any] = {}
    for name, runs in by_learner.items():
        learners[name] = {
            "runs": len(runs),
            "auc_mean": _stats([area(r.mean) for r in runs]),
            "auc_std": _stats([area(r.std) for r in runs]),
            "final_mean": _stats([float(r.mean[-1]) for r in runs]),
            "final_std": _stats([float(r.std[-1]) for r in runs]),
            "episodes_to_level": _stats([first_crossing(r.mean, r.episodes, level)
                                         for r in runs]),
            "heldout_success": _stats([float(r.heldout["success_rate"]) for r in runs]),
            "heldout_pooled": _pooled(runs),
            "cost": _cost(runs),
        }
    metrics = {"auc_mean": "area under the mean-fitness curve",
               "heldout_success": "held-out success rate",
               "final_mean": "last generation's mean fitness",
               "episodes_to_level": f"training episodes to mean fitness {level:.3f}"}
    comparisons = [
        _comparison(metric, a, b, compare(_values(learners[a][metric]),
                                          _values(learners[b][metric])))
        for metric in metrics
        for i, a in enumerate(plan.learners) for b in plan.learners[i + 1:]]
    best = max(records, key=lambda r: (r.heldout["success_rate"], -plan.learners.index(
        r.learner), -r.seed))
    return {"behaviour": plan.behaviour, "plan": plan.to_dict(), "level": level,
            "metrics": metrics, "curves": curves, "learners": learners,
            "comparisons": comparisons, "claims": _claims(by_learner, curves),
            "best_run": {"learner": best.learner, "seed": best.seed,
                         "success_rate": best.heldout["success_rate"]}}


def _band_dict(b: Any) -> dict[str, list[float]]:
    return {"q25": b.low.tolist(), "median": b.median.tolist(), "q75": b.high.tolist()}


def _pooled(runs: list[RunRecord]) -> dict[str, Any]:
    successes = sum(int(r.heldout["successes"]) for r in runs)
    episodes = sum(int(r.heldout["episodes"]) for r in runs)
    return wilson_interval(successes, episodes).to_dict()


def _cost(runs: list[RunRecord]) -> dict[str, int]:
    return {"training_episodes": sum(r.training_episodes for r in runs),
            "training_steps": sum(r.training_steps for r in runs),
            "selection_episodes": sum(r.selection_episodes for r in runs),
            "selection_steps": sum(r.selection_steps for r in runs),
            "heldout_episodes": sum(int(r.heldout["episodes"]) for r in runs),
            "heldout_steps": sum(int(r.heldout["steps"]) for r in runs),
            "episodes_per_run_max": max(r.training_episodes + r.selection_episodes
                                        for r in runs)}


def _claims(by_learner: dict[str, list[RunRecord]], curves: dict[str, Any],
            ) -> list[dict[str, Any]]:
    """The paper's two claims (Sec. IV, Fig. 5-6): against Pitt, the hybrid's mean fitness
    rises sooner, and its population's std falls sooner."""
    texts = ("the hybrid's mean fitness rises sooner than Pitt's",
             "the hybrid's population std falls sooner than Pitt's")
    if any(name not in by_learner for name in CLAIM_LEARNERS):
        return [{"claim": text, "verdict": "not tested",
                 "reason": "the experiment needs both the pitt and hybrid learners"}
                for text in texts]
    hybrid, pitt = by_learner["hybrid"], by_learner["pitt"]
    claims = []
    for text, key, rising in ((texts[0], "mean", True), (texts[1], "std", False)):
        starts = [curves[n][key]["median"][0] for n in CLAIM_LEARNERS]
        ends = [curves[n][key]["median"][-1] for n in CLAIM_LEARNERS]
        level = (halfway_level(min(starts), max(ends)) if rising
                 else halfway_level(max(starts), min(ends)))

        def times(runs: list[RunRecord], key: str = key, level: float = level,
                  rising: bool = rising) -> list[float]:
            return [first_crossing(getattr(r, key), r.episodes, level, rising) for r in runs]

        hybrid_t, pitt_t = times(hybrid), times(pitt)
        # sooner = fewer episodes: the hybrid's times below Pitt's
        sooner = compare(np.array(pitt_t), np.array(hybrid_t))
        areas = {n: [area(getattr(r, key)) for r in by_learner[n]] for n in CLAIM_LEARNERS}
        # mean fitness: the hybrid's area larger; std: smaller
        larger, smaller = ("hybrid", "pitt") if rising else ("pitt", "hybrid")
        area_test = compare(np.array(areas[larger]), np.array(areas[smaller]))
        # The verdict rests on the area under the curve: a single run's curve is one noisy
        # trial per individual, so the first crossing of a level is decided by luck early on
        # (it is reported too); the area weighs every generation.
        reverse = compare(np.array(areas[smaller]), np.array(areas[larger]))
        if area_test.p_greater < SIGNIFICANCE:
            verdict = "holds"
        elif reverse.p_greater < SIGNIFICANCE:
            verdict = "does not hold: the opposite is significant"
        else:
            verdict = "does not hold: no significant difference"
        claims.append({
            "claim": text, "verdict": verdict, "curve": key, "level": level,
            "rising": rising,
            "episodes_hybrid": _stats(hybrid_t), "episodes_pitt": _stats(pitt_t),
            "p_hybrid_sooner": sooner.p_greater, "effect_pitt_later": sooner.effect,
            "area_hybrid": _stats(areas["hybrid"]), "area_pitt": _stats(areas["pitt"]),
            "p_area": area_test.p_greater, "effect_area": area_test.effect,
        })
    return claims


# -- the report -------------------------------------------------------------------------
def _num(x: float | None, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    return f"{x:.{digits}f}"


def _p(x: float) -> str:
    if math.isnan(x):
        return "–"
    return f"{x:.2g}" if x >= 1e-3 else f"{x:.1e}"


def _iqr(entry: dict[str, Any], digits: int = 3, never: str = "never") -> str:
    def show(x: float | None) -> str:
        return never if x is None else _num(x, digits)
    return f"{show(entry['median'])} [{show(entry['q25'])}, {show(entry['q75'])}]"


def report_markdown(summary: dict[str, Any]) -> str:
    """report.md: the claims, learning curves, per-run results, tests and costs."""
    plan = summary["plan"]
    learners = plan["learners"]
    overrides = ", ".join(f"`{k}={v}`" for k, v in plan["overrides"].items()) or "none"
    lines = [
        f"# Experiment: {summary['behaviour']}",
        "",
        f"Learners {', '.join(learners)}; seeds 0..{plan['seeds'] - 1} ({plan['seeds']} runs "
        f"each); overrides: {overrides}. Each run's best.yaml is tested on the same "
        f"{plan['heldout_episodes']} held-out episodes (`flctool evaluate best.yaml "
        f"--episodes {plan['heldout_episodes']} --seed {plan['heldout_seed']}`), whose seeds "
        "are never used in training. Spreads are the median and inter-quartile range "
        "[25 %, 75 %] across seeds; tests are Mann–Whitney U with the effect size "
        "A = P(first > second) + P(tie)/2 (0.5: no difference).",
        "",
        "## The paper's claims",
        "",
        f"A claim holds when the one-sided test on the area under the curve gives p < "
        f"{SIGNIFICANCE}; the first crossing of a level is reported beside it (a single "
        "run's curve is noisy, so a crossing can come early by luck).",
        "",
    ]
    for number, claim in enumerate(summary["claims"], 1):
        lines.append(f"{number}. **{claim['claim'][0].upper()}{claim['claim'][1:]}: "
                     f"{claim['verdict']}.**")
        if "reason" in claim:
            lines += [f"   {claim['reason']}.", ""]
            continue
        what = "mean fitness" if claim["rising"] else "population std"
        towards = "rises to" if claim["rising"] else "falls to"
        better = "larger" if claim["rising"] else "smaller"
        hybrid_t, pitt_t = claim["episodes_hybrid"], claim["episodes_pitt"]
        lines += [
            f"   Area under the {what} curve (sum over generations; {better} is sooner): "
            f"hybrid {_iqr(claim['area_hybrid'], 2)}, Pitt {_iqr(claim['area_pitt'], 2)}; "
            f"one-sided p (hybrid {better}) = {_p(claim['p_area'])}, "
            f"A = {_num(claim['effect_area'], 2)}. "
            f"Training episodes until a run's {what} first {towards} {claim['level']:.3f} "
            "(half way between the two learners' first- and last-generation medians): hybrid "
            f"{_iqr(hybrid_t, 0)} (reached in {hybrid_t['reached']}/{hybrid_t['n']} runs), "
            f"Pitt {_iqr(pitt_t, 0)} (reached in {pitt_t['reached']}/{pitt_t['n']}); "
            f"one-sided p (hybrid sooner) = {_p(claim['p_hybrid_sooner'])}, "
            f"A(Pitt later) = {_num(claim['effect_pitt_later'], 2)}.",
            ""]
    lines += _curve_table(summary)
    lines += _results_table(summary)
    lines += _comparison_table(summary)
    lines += _cost_table(summary)
    best = summary["best_run"]
    lines += [f"The best controller of the experiment (highest held-out success) is "
              f"`runs/{best['learner']}-seed{best['seed']}/best.yaml`, with "
              f"{_num(best['success_rate'])}.", ""]
    return "\n".join(lines)


def _curve_table(summary: dict[str, Any]) -> list[str]:
    learners = summary["plan"]["learners"]
    episodes = summary["curves"][learners[0]]["episodes"]
    count = len(episodes)
    picks = sorted({0, *range(count // 6 or 1, count, count // 6 or 1), count - 1})
    lines = ["## Learning curves", "",
             "Mean fitness and population std per generation, median [IQR] across seeds. "
             "For fuzzy_q the std is over the generation's episodes of its one controller.",
             "", "| episodes | " + " | ".join(f"{n} mean | {n} std" for n in learners) + " |",
             "|" + "---:|" * (1 + 2 * len(learners))]
    for g in picks:
        cells = []
        for name in learners:
            curve = summary["curves"][name]
            if g >= len(curve["episodes"]):
                cells += ["–", "–"]
                continue
            for key in ("mean", "std"):
                c = curve[key]
                cells.append(f"{c['median'][g]:.3f} [{c['q25'][g]:.3f}, {c['q75'][g]:.3f}]")
        lines.append(f"| {episodes[g]:.0f} | " + " | ".join(cells) + " |")
    return [*lines, ""]


def _results_table(summary: dict[str, Any]) -> list[str]:
    lines = ["## Per-run results", "",
             "| learner | area under mean fitness | last mean fitness | last std | "
             f"episodes to mean fitness {summary['level']:.3f} (reached) | held-out success "
             "| held-out success, all episodes pooled (95 % CI) |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for name in summary["plan"]["learners"]:
        s = summary["learners"][name]
        pooled = s["heldout_pooled"]
        lines.append(
            f"| {name} | {_iqr(s['auc_mean'], 2)} | {_iqr(s['final_mean'])} | "
            f"{_iqr(s['final_std'])} | {_iqr(s['episodes_to_level'], 0)} "
            f"({s['episodes_to_level']['reached']}/{s['episodes_to_level']['n']}) | "
            f"{_iqr(s['heldout_success'])} | {_num(pooled['value'])} "
            f"[{_num(pooled['low'])}, {_num(pooled['high'])}] |")
    return [*lines, ""]


def _comparison_table(summary: dict[str, Any]) -> list[str]:
    lines = ["## Pairwise tests", "",
             "Mann–Whitney U, two-sided p; A = P(first > second) + P(tie)/2 over runs "
             "(for episodes to the level, smaller is better and 'never' ranks last).", "",
             "| measure | first | second | U | p | A |", "|---|---|---|---:|---:|---:|"]
    for c in summary["comparisons"]:
        lines.append(f"| {summary['metrics'][c['metric']]} | {c['a']} | {c['b']} | "
                     f"{_num(c['u'], 1)} | {_p(c['p'])} | {_num(c['effect_a_greater'], 2)} |")
    return [*lines, ""]


def _cost_table(summary: dict[str, Any]) -> list[str]:
    lines = ["## What it cost", "",
             "Environment episodes and steps summed over every run of a learner: training, "
             "the run's own choice of best.yaml (model selection: its candidates re-run on "
             "validation episodes; 0 with `selection.candidates=0`), and the held-out test. "
             "'Largest run' is the most episodes one run used, training and selection.", "",
             "| learner | training episodes | training steps | selection episodes | "
             "selection steps | largest run (episodes) | held-out episodes | held-out steps |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for name in summary["plan"]["learners"]:
        c = summary["learners"][name]["cost"]
        lines.append(f"| {name} | {c['training_episodes']} | {c['training_steps']} | "
                     f"{c['selection_episodes']} | {c['selection_steps']} | "
                     f"{c['episodes_per_run_max']} | {c['heldout_episodes']} | "
                     f"{c['heldout_steps']} |")
    return [*lines, ""]


def write_report(experiment: Experiment, level: float | None = None) -> dict[str, Any]:
    """Write summary.json and report.md into the experiment directory; returns the summary."""
    summary = summarise(experiment, level)
    write_text_atomic(experiment.path / SUMMARY_FILE,
                      json.dumps(summary, indent=2, allow_nan=False) + "\n")
    write_text_atomic(experiment.path / REPORT_FILE, report_markdown(summary))
    return summary


def read_summary(path: Path) -> dict[str, Any]:
    try:
        data: dict[str, Any] = json.loads((path / SUMMARY_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise RunDirError(f"{path / SUMMARY_FILE} cannot be read ({exc})",
                          hint="run flctool experiment on it to the end") from None
    return data
