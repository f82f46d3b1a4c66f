#!/usr/bin/env python3
"""Pearson r of utility against mean localization error from an experiment's runs.csv,
with and without greedy (whose degenerate walks dominate the correlation in
correlation.csv). Standard library only.

    python3 docs/results/correlations.py docs/results/area-one/runs.csv
"""
import csv
import sys
from statistics import mean


def pearson(x, y):
    mx, my = mean(x), mean(y)
    sxy = sum((a - mx) * (b - my) for a, b in zip(x, y))
    sxx = sum((a - mx) ** 2 for a in x)
    syy = sum((b - my) ** 2 for b in y)
    return sxy / (sxx * syy) ** 0.5 if sxx > 0 and syy > 0 else None


def fmt(rows):
    r = pearson([float(x["utility_nats"]) for x in rows], [float(x["mean_error_m"]) for x in rows])
    return "undefined" if r is None else f"{r:+.2f}"


for path in sys.argv[1:]:
    rows = list(csv.DictReader(open(path, newline="")))
    without = [x for x in rows if x["algorithm"] != "greedy"]
    print(f"{path}: all {fmt(rows)} (n={len(rows)}), without greedy {fmt(without)} (n={len(without)})")
    for b in sorted({x["budget_m"] for x in rows}, key=float):
        at = [x for x in rows if x["budget_m"] == b]
        at_ng = [x for x in without if x["budget_m"] == b]
        print(f"  budget {b}: all {fmt(at)}, without greedy {fmt(at_ng)}")
