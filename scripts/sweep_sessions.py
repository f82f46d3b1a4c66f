#!/usr/bin/env python3
"""Simulated survey sessions on a folder of buildings (for example the one
`sweep_generated.py` keeps): on each, a person with a wrong turn at 10% of the vertices on
half the total edge length and a robot with 5% on a quarter, start = end at a seeded
random vertex, `trailprint simulate` with its defaults, one core a session (two at a time,
pinned to cores 0 and 1).

    python3 scripts/sweep_sessions.py FOLDER [SEED]     (SEED: the starts' and the sessions', default 1)

Prints one line a session (planned and collected utility, walked / budget as the session
counted it and as the simulated surveyor really walked, wrong turns, replans, the slowest
replan) and flags a session that does not finish, really walks more than 5% over its
budget, or replans slower than 1.3 s (auto's 1 s replan limit plus set-up) on a building
of more than 200 vertices. Needs the release binary (TRAILPRINT_BIN, else
target/release/trailprint) and Python's sqlite3 (the replan times are the plans' own).
"""
import json, os, random, sqlite3, subprocess, sys, tempfile, time

from sweep_common import on_two_cores, total_length

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("TRAILPRINT_BIN") or os.path.join(ROOT, "target", "release", "trailprint")
# Who walks, the chance of a wrong turn at a vertex, and the budget's share of the edges.
SURVEYORS = (("human", 0.1, 0.5), ("robot", 0.05, 0.25))


def simulate(job, seed, tmp, core):
    """One session; its JSON summary with the slowest replan, or the error."""
    name, path, _, start, model, deviate, budget = job
    db = os.path.join(tmp, f"{name}-{model}.db")
    t0 = time.time()
    out = subprocess.run(["taskset", "-c", str(core), BIN, "simulate", "--db", db, "--building", path,
                          "--start", start, "--budget", f"{budget:.1f}", "--surveyor", model,
                          "--deviate", str(deviate), "--seed", str(seed), "--json"],
                         capture_output=True, text=True, env=dict(os.environ, RAYON_NUM_THREADS="1"))
    wall = time.time() - t0
    if out.returncode != 0:
        return dict(error=out.stderr.strip()[-300:], wall=wall)
    v = json.loads(out.stdout.strip().splitlines()[-1])
    # Every plan after the session's first is a replan; each row keeps its own time.
    times = [r[0] for r in sqlite3.connect(db).execute("SELECT elapsed_ms FROM plans ORDER BY id")][1:]
    v["replan_max_ms"] = max(times, default=0)
    v["wall"] = wall
    return v


def main():
    folder = sys.argv[1]
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 1
    rng = random.Random(seed)
    jobs = []
    for name in sorted(os.listdir(folder)):
        if not name.endswith(".json"):
            continue
        path = os.path.join(folder, name)
        b = json.load(open(path))
        start = rng.choice([v["id"] for v in b["vertices"]])
        for model, deviate, share in SURVEYORS:
            jobs.append((name, path, len(b["vertices"]), start, model, deviate, share * total_length(b)))
    tmp = tempfile.mkdtemp()
    results = on_two_cores(jobs, lambda j, core: simulate(j, seed, tmp, core))
    flagged = 0
    for j, v in sorted(results, key=lambda r: (r[0][0], r[0][4])):
        name, _, nv, start, model, _, budget = j
        head = f"{name} {nv} vertices {model} {budget:.0f} m from {start}:"
        if "error" in v:
            flagged += 1
            print(head, "ERROR", v["error"])
            continue
        flags = []
        if v["status"] != "finished":
            flags.append("not finished")
        if v["true_walked_m"] > 1.05 * budget:
            flags.append("over budget + 5%")
        if nv > 200 and v["replan_max_ms"] > 1300:
            flags.append("slow replan")
        flagged += bool(flags)
        print(head, f"planned {v['planned_utility_nats']:.2f} collected {v['collected_utility_nats']:.2f} "
              f"walked/budget {v['walked_m'] / budget:.3f} true {v['true_walked_m'] / budget:.3f} "
              f"wrong turns {v['wrong_turns']} replans {v['replans']} slowest replan {v['replan_max_ms']} ms "
              f"wall {v['wall']:.1f} s", "; ".join(flags))
    print(f"{len(results)} sessions, {flagged} flagged")


if __name__ == "__main__":
    main()
