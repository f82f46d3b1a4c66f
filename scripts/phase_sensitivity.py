#!/usr/bin/env python3
"""How much of a person's planned utility depends on walking at exactly the planned speed.

A person's samples fall every `speed x scan interval` metres along the walk (SPEC 4: 4.8 m
by default), so a walk's utility depends on where those samples land: near a vertex or
not, right after a check-in or not. A planner can tune a walk to that phase. This script
evaluates saved plans (`trailprint plan --json` output) at the planned speed and at
speeds a little off it, so that a plan's margin over another can be split into what the
walk's route gives and what the exact phase gives.

    python3 scripts/phase_sensitivity.py BUILDING.json PLAN.json [PLAN.json ...]

Prints, per plan, the utility at the planned 1.2 m/s and at 1.2 x (1 +- 0.4%, 0.8%,
1.7%), and their mean off the planned speed. Needs the release binary (TRAILPRINT_BIN,
else target/release/trailprint).
"""
import json, os, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("TRAILPRINT_BIN") or os.path.join(ROOT, "target", "release", "trailprint")
SPEED = 1.2
FACTORS = [-0.017, -0.008, -0.004, 0.004, 0.008, 0.017]


def utility(building, walk, speed):
    out = subprocess.run([BIN, "utility", "--building", building, "--walk", ",".join(walk),
                          "--model", "human", "--speed", f"{speed:.5f}", "--json"],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.splitlines()[0])["utility_nats"]


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    building = sys.argv[1]
    print(f"| plan | {SPEED} m/s | " + " | ".join(f"{f:+.1%}" for f in FACTORS) + " | mean off |")
    print("|---|---|" + "---|" * len(FACTORS) + "---|")
    for path in sys.argv[2:]:
        walk = json.load(open(path))["walk"]
        at = utility(building, walk, SPEED)
        off = [utility(building, walk, SPEED * (1 + f)) for f in FACTORS]
        cells = " | ".join(f"{u:.2f}" for u in off)
        print(f"| {os.path.basename(path)} | {at:.2f} | {cells} | {sum(off) / len(off):.2f} |")


if __name__ == "__main__":
    main()
