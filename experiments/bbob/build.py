"""Build ``leaderboards/bbob/`` from the IOHprofiler logs of the BBOB sweep (``sweep.py``).

Per dimension: runtime ECDFs as COCO draws them — the fraction of (function, instance, target)
triples reached against evaluations / dimension on a log axis, for the 51 targets
10^2 ... 10^-8 of the precision f - f_opt, over all 24 functions and per function group, with a
cross at each method's budget — and the functions solved per method: a function counts as
solved to a target when the median run over its instances reaches it. Planned runs that left
no log count as never reaching any target and are listed. Also a per-function CSV (success
rates, median final precision, expected running time) and, with ``--ioh-merged``, the runs
gathered into one IOHprofiler folder per method for IOHanalyzer.

Run from the repository root:
python experiments/bbob/build.py --runs experiments/bbob/runs --out leaderboards/bbob
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.leaderboard.ecdf import TARGETS, ecdf_curves, hitting_evaluations
from tcbench.leaderboard.iohprofiler import IOHRun, read_runs, write_merged
from tcbench.leaderboard.optimisation import expected_running_time, markdown_table

GROUPS = {
    "separable (f1-f5)": range(1, 6),
    "low or moderate conditioning (f6-f9)": range(6, 10),
    "high conditioning, unimodal (f10-f14)": range(10, 15),
    "multimodal, adequate global structure (f15-f19)": range(15, 20),
    "multimodal, weak global structure (f20-f24)": range(20, 25),
}
PAPER_METHODS = ["fa", "ifa", "ga", "pso", "bas"]  # the seed papers' optimisers
REFERENCE = "cmaes"
SOLVED_TARGETS = {"1e-2": 1e-2, "1e-8": 1e-8}
NAMES = {"fa": "FA", "ifa": "IFA", "ga": "GA", "pso": "PSO", "bas": "BAS", "sa": "SA", "cmaes": "CMA-ES",
         "ipop_cmaes": "IPOP-CMA-ES", "scipy_de": "DE (scipy)", "dual_annealing": "dual annealing",
         "ng_de": "DE (nevergrad)", "ngopt": "NGOpt", "tpe": "TPE"}


def runs_table(ioh_dir: Path, plan: dict) -> tuple[pd.DataFrame, pd.DataFrame, list[IOHRun]]:
    """One row per planned run (found or missing) with its hitting evaluations per target; the
    planned runs that left no log; and the planned runs found (runs of another grid under
    ``ioh_dir`` are left out)."""
    rows: dict[tuple[str, int, int, int, int], dict] = {}
    for r in read_runs(ioh_dir):
        if r.meta.suite != "BBOB":
            continue
        # A run made at another budget (an earlier grid) is kept on disk but is not this plan's.
        key = (r.algorithm, r.meta.function_id, r.meta.dim, r.meta.instance, int(r.attributes.get("budget", -1)))
        if key in rows:
            raise SystemExit(f"build: two runs of {key[0]} on f{key[1]} {key[2]}-D instance {key[3]} at budget "
                             f"{key[4]} under {ioh_dir}; remove one")
        rows[key] = {
            "hits": hitting_evaluations(r.evaluations.astype(float), r.raw_y), "evals": r.evals,
            "final": float(r.best_so_far()[-1]), "run": r,
        }
    planned, missing, found_runs = [], [], []
    for m in plan["methods"]:
        for d in plan["dims"]:
            budget = plan["budgets"][m][str(d)]
            for f in plan["functions"]:
                for i in plan["instances"][str(d)]:
                    found = rows.get((m, f, d, i, budget))
                    if found is None:
                        missing.append({"method": m, "function": f, "dim": d, "instance": i})
                        found = {"hits": np.full(TARGETS.size, np.inf), "evals": budget, "final": np.inf}
                    else:
                        found = dict(found)
                        found_runs.append(found.pop("run"))
                    planned.append({"method": m, "function": f, "dim": d, "instance": i, "budget": budget, **found})
    return (pd.DataFrame(planned), pd.DataFrame(missing, columns=["method", "function", "dim", "instance"]),
            found_runs)


def hit_at(runs: pd.DataFrame, target: float) -> np.ndarray:
    """Evaluation at which each run first reached ``target`` (inf: never)."""
    j = int(np.argmin(np.abs(np.log10(TARGETS) - np.log10(target))))
    return np.array([h[j] for h in runs["hits"]])


def per_function(runs: pd.DataFrame) -> pd.DataFrame:
    """Per method, dimension and function: success rates, median final precision, ERT."""
    out = []
    for (m, d, f), g in runs.groupby(["method", "dim", "function"], sort=True):
        row = {"method": m, "dim": d, "function": f, "runs": len(g),
               "median_final_precision": float(np.median(g["final"]))}
        for label, t in SOLVED_TARGETS.items():
            hits = hit_at(g, t)
            ok = np.isfinite(hits)
            row[f"success_{label}"] = float(ok.mean())
            row[f"ert_{label}"] = expected_running_time(g["evals"].to_numpy(float), hits, ok)
        out.append(row)
    return pd.DataFrame(out)


def solved_table(funcs: pd.DataFrame, runs: pd.DataFrame, missing: pd.DataFrame) -> pd.DataFrame:
    """Per method and dimension: functions solved (median run reaches the target), share of runs
    reaching it, share of (function, instance, target) triples reached at the budget."""
    out = []
    for (m, d), g in funcs.groupby(["method", "dim"], sort=False):
        r = runs[(runs["method"] == m) & (runs["dim"] == d)]
        row = {"method": m, "dim": int(d), "budget": int(r["budget"].iloc[0]), "runs": len(r),
               "missing": int(((missing["method"] == m) & (missing["dim"] == d)).sum()) if len(missing) else 0}
        for label in SOLVED_TARGETS:
            row[f"solved_{label}"] = int((g[f"success_{label}"] >= 0.5).sum())
        for label, t in SOLVED_TARGETS.items():
            row[f"runs_{label}"] = float(np.isfinite(hit_at(r, t)).mean())
        row["ecdf_at_budget"] = float(np.isfinite(np.vstack(r["hits"].to_numpy())).mean())
        out.append(row)
    table = pd.DataFrame(out).sort_values(["dim", "solved_1e-8", "solved_1e-2", "ecdf_at_budget"],
                                          ascending=[True, False, False, False])
    return table.reset_index(drop=True)


def ecdf_table(runs: pd.DataFrame) -> pd.DataFrame:
    """(method, dim, task, evaluations / dim) per run and target, as :func:`tcbench.leaderboard.ecdf.ecdf_curves` takes."""
    n = TARGETS.size
    return pd.DataFrame({
        "method": np.repeat(runs["method"].to_numpy(), n), "dim": np.repeat(runs["dim"].to_numpy(), n),
        "task": np.repeat(runs["function"].to_numpy(), n),
        "evaluations": np.concatenate(runs["hits"].to_numpy()) / np.repeat(runs["dim"].to_numpy(), n),
    })


def draw_ecdfs(ax, runs: pd.DataFrame, dim: int, grid: np.ndarray, styles: dict[str, dict], title: str) -> None:  # type: ignore[no-untyped-def]
    """COCO-style ECDF panel: one step curve per method, a cross at the median number of
    evaluations its runs used (/ dim)."""
    curves = ecdf_curves(ecdf_table(runs), grid).get(dim, {})
    for m, frac in sorted(curves.items(), key=lambda kv: -kv[1][-1]):
        used = float(np.median(runs.loc[runs["method"] == m, "evals"])) / dim
        ax.step(grid, frac, where="post", label=f"{NAMES.get(m, m)} ({frac[-1]:.0%})", **styles[m])
        ax.plot([used], [frac[max(np.searchsorted(grid, used, side="right") - 1, 0)]], "x", ms=8, mew=2,
                color=styles[m]["color"])
    ax.set_xscale("log")
    ax.set(xlim=(grid[0], grid[-1] * 1.6), ylim=(0, 1), title=title, xlabel="evaluations / dimension",
           ylabel="fraction of (function, instance, target)")
    ax.grid(True, which="both", alpha=0.3)


def write_plots(runs: pd.DataFrame, out: Path) -> list[Path]:
    """``ecdf_<d>d.png`` (all functions) and ``ecdf_groups_<d>d.png`` (the five groups) per dimension."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tab10 = plt.get_cmap("tab10").colors
    others = [m for m in dict.fromkeys(runs["method"]) if m not in PAPER_METHODS and m != REFERENCE]
    styles = {m: {"color": tab10[k], "lw": 2.2, "ls": "-"} for k, m in enumerate(PAPER_METHODS)}
    styles[REFERENCE] = {"color": "black", "lw": 2.2, "ls": "-"}
    styles |= {m: {"color": tab10[5 + k % 5], "lw": 1.4, "ls": ("--", "-.", ":")[k // 5 % 3]}
               for k, m in enumerate(others)}
    paths = []
    for dim in sorted(runs["dim"].unique()):
        sub = runs[runs["dim"] == dim]
        top = float(sub["budget"].max()) / dim
        grid = np.unique(np.concatenate([np.geomspace(1.0 / dim, top, 400), sub["budget"].unique() / dim]))
        n_inst = sub.groupby(["method", "function"]).size().max()
        fig, ax = plt.subplots(figsize=(10, 5.5))
        draw_ecdfs(ax, sub, int(dim), grid, styles, f"BBOB, {sub['function'].nunique()} functions, {dim}-D, "
                   f"{n_inst} instances, 51 targets 1e2..1e-8")
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                  title="solid: seed papers, CMA-ES\n×: median evaluations used", title_fontsize=8)
        fig.tight_layout()
        paths.append(out / f"ecdf_{dim}d.png")
        fig.savefig(paths[-1], dpi=110)
        plt.close(fig)
        fig, axes = plt.subplots(2, 3, figsize=(16, 9.5))
        for ax, (name, fids) in zip(axes.flat, GROUPS.items(), strict=False):
            group = sub[sub["function"].isin(list(fids))]
            if group.empty:
                ax.set_title(f"{dim}-D {name}: not in this sweep")
                ax.axis("off")
                continue
            draw_ecdfs(ax, group, int(dim), grid, styles, f"{dim}-D {name}")
            ax.legend(fontsize=7, loc="upper left")
        axes.flat[-1].axis("off")
        fig.tight_layout()
        paths.append(out / f"ecdf_groups_{dim}d.png")
        fig.savefig(paths[-1], dpi=90)
        plt.close(fig)
    return paths


def function_matrix(funcs: pd.DataFrame, dim: int, n_instances: int) -> str:
    """Markdown: per function (rows) and method (columns), instances reaching 1e-8 (and 1e-2)."""
    g = funcs[funcs["dim"] == dim]
    methods = list(dict.fromkeys(g["method"]))
    head = "| f | " + " | ".join(NAMES.get(m, m) for m in methods) + " |"
    lines = [head, "|---|" + "---|" * len(methods)]
    for f, rows in g.groupby("function", sort=True):
        cells = []
        for m in methods:
            r = rows[rows["method"] == m].iloc[0]
            a, b = round(r["success_1e-8"] * r["runs"]), round(r["success_1e-2"] * r["runs"])
            cells.append(f"**{a}** ({b})" if r["success_1e-8"] >= 0.5 else f"{a} ({b})")
        lines.append(f"| f{f} | " + " | ".join(cells) + " |")
    return (f"Instances (of {n_instances}) whose run reached 1e-8 (in brackets: 1e-2); bold: solved "
            "(the median run reaches 1e-8).\n\n" + "\n".join(lines))


def standing(solved: pd.DataFrame, n_functions: int) -> str:
    """Plain-language paragraph per dimension: where the seed papers' methods stand against
    CMA-ES (without restarts) and IPOP-CMA-ES."""
    text = []
    for dim, g in solved.groupby("dim", sort=True):
        g = g.set_index("method")
        refs = [m for m in (REFERENCE, "ipop_cmaes") if m in g.index]
        paper = [m for m in PAPER_METHODS if m in g.index]
        parts = [f"In {dim}-D ({n_functions} functions):"]
        for m in refs:
            parts.append(f"{NAMES[m]} solves {int(g.loc[m, 'solved_1e-8'])} of them to 1e-8 and "
                         f"{int(g.loc[m, 'solved_1e-2'])} to 1e-2, and reaches {g.loc[m, 'ecdf_at_budget']:.0%} of "
                         "the (function, instance, target) triples within its budget.")
        if paper:
            listing = ", ".join(f"{NAMES[m]} {int(g.loc[m, 'solved_1e-8'])} and {int(g.loc[m, 'solved_1e-2'])}"
                                for m in paper)
            best = max(paper, key=lambda m: (g.loc[m, "ecdf_at_budget"], g.loc[m, "solved_1e-8"]))
            worst = min(paper, key=lambda m: (g.loc[m, "ecdf_at_budget"], g.loc[m, "solved_1e-8"]))
            ranked = g.sort_values("ecdf_at_budget", ascending=False).index.tolist()
            parts.append(f"The seed papers' methods solve (to 1e-8 and to 1e-2): {listing}. The strongest of "
                         f"them, {NAMES[best]}, reaches {g.loc[best, 'ecdf_at_budget']:.0%} of the triples "
                         f"(rank {ranked.index(best) + 1} of {len(ranked)} methods), the weakest, "
                         f"{NAMES[worst]}, {g.loc[worst, 'ecdf_at_budget']:.0%}.")
            for ref in refs:
                level = g.loc[ref, "ecdf_at_budget"]
                beaten = [NAMES[m] for m in paper if g.loc[m, "ecdf_at_budget"] >= level]
                parts.append(f"None of them reaches as many triples as {NAMES[ref]}." if not beaten else
                             f"{', '.join(beaten)} reach{'es' if len(beaten) == 1 else ''} as many triples as "
                             f"{NAMES[ref]} or more.")
        text.append(" ".join(parts))
    return "\n\n".join(text)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=Path, required=True, help="the sweep's output folder (plan.json, ioh/)")
    ap.add_argument("--out", type=Path, required=True, help="leaderboard folder to write")
    ap.add_argument("--ioh-merged", type=Path, help="also gather the runs here, one folder per method, for IOHanalyzer")
    ns = ap.parse_args(argv)
    plan_path = ns.runs / "plan.json"
    if not plan_path.is_file():
        print(f"build: error: {plan_path} not found: run sweep.py first", file=sys.stderr)
        return 2
    plan = json.loads(plan_path.read_text())
    runs, missing, found_runs = runs_table(ns.runs / "ioh", plan)
    funcs = per_function(runs)
    solved = solved_table(funcs, runs, missing)
    ns.out.mkdir(parents=True, exist_ok=True)
    funcs.to_csv(ns.out / "per_function.csv", index=False)
    solved.to_csv(ns.out / "solved.csv", index=False)
    plots = write_plots(runs, ns.out)
    shown = solved.assign(method=solved["method"].map(lambda m: NAMES.get(m, m)))
    errors = []
    failed_path = ns.runs / "failed.jsonl"
    if len(missing) and failed_path.is_file():
        left = {tuple(r) for r in missing[["method", "function", "dim", "instance"]].itertuples(index=False)}
        for line in failed_path.read_text().splitlines():
            e = json.loads(line)
            if (e["method"], e["function"], e["dim"], e["instance"]) in left:
                errors.append(f"- {e['method']} f{e['function']} {e['dim']}-D instance {e['instance']}: {e['error']}")
    inst = {d: len(v) for d, v in plan["instances"].items()}
    budgets = "; ".join(f"{NAMES.get(m, m)} " + ", ".join(f"{b} ({d}-D)" for d, b in per_dim.items())
                        for m, per_dim in plan["budgets"].items())
    readme = [
        "# BBOB f1–f24 (ioh): the seed papers' methods against the peers",
        "",
        "Generated by `bash experiments/bbob/run.sh` (see `experiments/bbob/README.md`); do not edit.",
        (f"Dimensions {', '.join(map(str, plan['dims']))}; instances per dimension "
         f"{', '.join(f'{d}-D: {n}' for d, n in inst.items())} (the run seed is the instance number); "
         f"budgets in evaluations: {budgets}. Precision = f − f_opt; a run stops at 1e-8."),
        "",
        "## Where the seed papers' methods stand",
        "",
        standing(solved, len(plan['functions'])),
        "",
        "## Functions solved",
        "",
        (f"`solved_<t>`: functions (of {len(plan['functions'])}) whose median run over the instances "
         "reaches precision t; `runs_<t>`: share of runs that reach it; `ecdf_at_budget`: share of "
         "(function, instance, target) triples reached, 51 targets 1e2…1e-8; `missing`: planned runs "
         "that left no log (counted as reaching nothing)."),
        "",
        markdown_table(shown),
        "",
        *(["Runs that failed:", "", *errors, ""] if errors else []),
        "## Runtime ECDFs",
        "",
        *[f"![{p.stem}]({p.name})" for p in plots],
        "",
    ]
    for d in plan["dims"]:
        readme += [f"## Per function, {d}-D", "", function_matrix(funcs, d, inst[str(d)]), ""]
    readme += [("`per_function.csv`: success rates, median final precision and ERT (evaluations) per "
                "method, dimension and function; `solved.csv`: the table above.")]
    (ns.out / "README.md").write_text("\n".join(readme) + "\n")
    print(markdown_table(shown))
    print(f"\n{standing(solved, len(plan['functions']))}\n\nwritten: {ns.out}/README.md, solved.csv, per_function.csv, "
          f"{', '.join(p.name for p in plots)}; missing runs: {len(missing)}")
    if ns.ioh_merged:
        written = write_merged(found_runs, ns.ioh_merged)
        print(f"IOHanalyzer folder: {ns.ioh_merged} ({len(written)} files; upload it zipped)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
