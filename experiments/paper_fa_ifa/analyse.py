"""Figures 3-4 of seed 000 from the paper_fa_ifa sweep: best and population-mean fitness per
iteration, median and inter-quartile band over seeds, and the table the README quotes."""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from tcbench.leaderboard import optimisation as leaderboard  # noqa: E402
from tcbench.tracking import store as tracking  # noqa: E402

POPULATION = 10
GENERATIONS = 50
CONVERGED = 1e-2  # population mean within this of f* counts as "converged to the global minimum"


def curves(client, runs, metric: str) -> dict[str, np.ndarray]:  # type: ignore[no-untyped-def]
    grid = POPULATION * (1 + np.arange(GENERATIONS + 1))  # evaluations after generation g
    return {m: y for m, (_, y) in leaderboard.step_curves(client, runs, metric, grid).items()}


def figure(task: str, best: dict, mean: dict, f_opt: float, path: Path) -> None:
    methods = sorted(best)
    fig, axes = plt.subplots(1, len(methods), figsize=(3.6 * len(methods), 3.4), sharey=True)
    it = np.arange(GENERATIONS + 1)
    for ax, m in zip(np.atleast_1d(axes), methods, strict=True):
        for label, y in (("best", best[m]), ("population mean", mean[m])):
            q25, q50, q75 = np.percentile(y, [25, 50, 75], axis=0)
            (line,) = ax.plot(it, q50, label=f"{label} (median)")
            ax.fill_between(it, q25, q75, color=line.get_color(), alpha=0.2, lw=0)
        ax.axhline(f_opt, color="k", ls=":", lw=0.8)
        ax.set(title=m, xlabel="iteration")
    np.atleast_1d(axes)[0].set_ylabel("fitness")
    np.atleast_1d(axes)[0].legend(fontsize=8)
    fig.suptitle(f"{task}: {len(next(iter(best.values())))} seeds, IQR bands")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sweep", required=True)
    ap.add_argument("--out", type=Path, default=Path(__file__).parent)
    ns = ap.parse_args()
    client = tracking.client()
    runs = leaderboard.load_runs(client, ["paper-fa-ifa"], ns.sweep)
    lines = [
        "| task | method | seeds | best @50 median [IQR] | pop. mean @50 median [IQR] | "
        f"pop. mean within {CONVERGED:g} of f* |",
        "|---|---|---|---|---|---|",
    ]
    for task, g in runs.groupby("task", sort=True):
        f_opt = float(g["f_opt"].dropna().iloc[0])
        best, mean = curves(client, g, "best_f"), curves(client, g, "pop_mean_f")
        figure(str(task), best, mean, f_opt, ns.out / f"{task}.png")
        for m in sorted(best):
            b, p = best[m][:, -1], mean[m][:, -1]
            qb, qp = np.percentile(b, [25, 50, 75]), np.percentile(p, [25, 50, 75])
            lines.append(
                f"| {task} | {m} | {len(b)} | {qb[1]:.4g} [{qb[0]:.4g}, {qb[2]:.4g}] | "
                f"{qp[1]:.4g} [{qp[0]:.4g}, {qp[2]:.4g}] | {np.mean(p - f_opt <= CONVERGED):.0%} |"
            )
    table = "\n".join(lines) + "\n"
    (ns.out / "results.md").write_text(f"Sweep {ns.sweep}.\n\n" + table)
    print(table)


if __name__ == "__main__":
    main()
