#!/usr/bin/env python3
"""Prints the tables of docs/results.md from the experiment's CSV files.

    python3 docs/results/tables.py docs/results/area-one docs/results/area-two

For each experiment directory: utility, localization error and planning time per
algorithm and budget (summary.csv), walk lengths and terminations (runs.csv) and the
reference errors (baselines.csv). Nothing is computed that the CSVs do not hold, except
means and counts over their rows.
"""

import csv
import sys
from collections import defaultdict


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def fmt_time(ms):
    ms = float(ms)
    if ms < 1000:
        return f"{ms:.0f} ms"
    return f"{ms / 1000:.2f} s" if ms < 10000 else f"{ms / 1000:.1f} s"


def table(title, algs, budgets, cell):
    out = [f"| {title} | " + " | ".join(f"B = {b} m" for b in budgets) + " |"]
    out.append("|---|" + "---:|" * len(budgets))
    for a in algs:
        out.append(f"| {a} | " + " | ".join(cell(a, b) for b in budgets) + " |")
    return "\n".join(out)


def main(dirs):
    for d in dirs:
        summary = rows(f"{d}/summary.csv")
        runs = rows(f"{d}/runs.csv")
        algs = list(dict.fromkeys(r["algorithm"] for r in summary))
        budgets = list(dict.fromkeys(r["budget_m"] for r in summary))
        s = {(r["algorithm"], r["budget_m"]): r for r in summary}
        print(f"## {d}\n")
        print(table("utility, nats (mean ± sd)", algs, budgets,
                    lambda a, b: f"{float(s[a, b]['utility_mean']):.2f} ± {float(s[a, b]['utility_sd']):.2f}"))
        print()
        print(table("localization error, m (mean ± sd)", algs, budgets,
                    lambda a, b: f"{float(s[a, b]['error_mean_m']):.2f} ± {float(s[a, b]['error_sd_m']):.2f}"))
        print()

        def time_cell(a, b):
            r = s[a, b]
            t = fmt_time(r["elapsed_mean_ms"])
            n = int(r["time_limited"])
            return t + (f" ({n} of {r['runs']} at the limit)" if n else "")

        print(table("planning time (mean)", algs, budgets, time_cell))
        print()
        lengths = defaultdict(set)
        terms = defaultdict(int)
        for r in runs:
            lengths[r["algorithm"], r["budget_m"]].add(f"{float(r['length_m']):.1f}")
            terms[r["algorithm"], r["termination"]] += 1
        print("walk lengths (m), per algorithm and budget:")
        for a in algs:
            print(f"  {a}: " + "; ".join(", ".join(sorted(lengths[a, b], key=float)) for b in budgets))
        print("terminations:", dict(terms))
        base = rows(f"{d}/baselines.csv")
        print("baselines:", [(r["name"], r["mean_error_m"], r["median_error_m"]) for r in base])
        corr = rows(f"{d}/correlation.csv")
        print("correlation:", [(r["scope"], r["pearson_r"]) for r in corr])
        print()


if __name__ == "__main__":
    main(sys.argv[1:])
