#!/usr/bin/env python3
"""Auto against the systematic `coverage` walk on buildings the benchmark does not have:
random `trailprint generate` buildings (1-3 floors, 2-10 rooms a side, corridors of 24-90 m,
rooms 6-14 m deep, grids of 1.5-3 m), a random start and end on each, both surveyor
models, budgets of 25%, 50% and 100% of the building's total edge length; `auto` with its
default 2 s limit, one core a plan (two plans at a time, pinned to cores 0 and 1).

    python3 scripts/sweep_generated.py [SEED] [BUILDINGS] [--vary-radio] [--small]     (defaults 7 and 8)

With `--vary-radio` each building also draws its number of access points (2-40) and pilot
points (8-60) instead of the generator's defaults (a separate random stream, so the
buildings, starts and ends of a seed are the same with and without it).

With `--small` the buildings are drawn small (1-2 floors, 2-8 rooms a side, corridors of
20-40 m, rooms 6-10 m deep, grids of 2-4 m) and those of more than 100 vertices are
skipped: the floors where `auto` runs its small-building portfolio.

Prints one line per row (with a person's reversals per 100 m) and flags a row where auto is below 1.05x coverage, uses less than
95% of the budget, or takes longer than 2.35 s (wall, process start-up included); a
refusal for memory is printed as such. The last two lines name the folder that keeps the
buildings and count the flagged rows.
Needs the release binary (TRAILPRINT_BIN, else target/release/trailprint).
"""
import json, os, random, subprocess, sys, tempfile, time

from sweep_common import on_two_cores, total_length

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("TRAILPRINT_BIN") or os.path.join(ROOT, "target", "release", "trailprint")


def reversals(path, walk):
    """Reversals of `walk` (ids) on the building at `path`: walking straight back along
    the edge just walked (`a, v, a`) where `v` is not a dead end, as `plan::coverage::reversals`
    counts them."""
    b = json.load(open(path))
    degree = {}
    for e in b["edges"]:
        degree[e["a"]] = degree.get(e["a"], 0) + 1
        degree[e["b"]] = degree.get(e["b"], 0) + 1
    return sum(1 for a, v, c in zip(walk, walk[1:], walk[2:]) if a == c and degree[v] > 1)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    vary_radio = "--vary-radio" in sys.argv[1:]
    small = "--small" in sys.argv[1:]
    seed = int(args[0]) if len(args) > 0 else 7
    count = int(args[1]) if len(args) > 1 else 8
    rng = random.Random(seed)
    radio_rng = random.Random(seed * 1_000_003 + 17)
    tmp = tempfile.mkdtemp()
    jobs = []
    for k in range(count):
        if small:
            o = dict(floors=rng.choice([1, 1, 2]), rooms=rng.choice([2, 3, 4, 5, 8]),
                     corridor=rng.choice([20, 24, 30, 40]), depth=rng.choice([6, 8, 10]),
                     grid=rng.choice([2.0, 3.0, 4.0]), seed=rng.randrange(1000))
        else:
            o = dict(floors=rng.choice([1, 1, 2, 3]), rooms=rng.choice([2, 3, 5, 8, 10]),
                     corridor=rng.choice([24, 40, 60, 90]), depth=rng.choice([6, 8, 10, 14]),
                     grid=rng.choice([1.5, 2.0, 3.0]), seed=rng.randrange(1000))
        path = os.path.join(tmp, f"b{k}.json")
        subprocess.run([BIN, "generate", "--out", path, "--name", f"b{k}", "--floors", str(o["floors"]),
                        "--rooms", str(o["rooms"]), "--corridor-length", str(o["corridor"]),
                        "--room-depth", str(o["depth"]), "--grid-spacing", str(o["grid"]),
                        "--seed", str(o["seed"])]
                       + (["--aps", str(radio_rng.choice([2, 3, 5, 8, 12, 20, 40])),
                           "--pilot", str(radio_rng.choice([8, 12, 20, 35, 60]))] if vary_radio else []),
                       check=True, capture_output=True)
        b = json.load(open(path))
        total = total_length(b)
        ids = [v["id"] for v in b["vertices"]]
        if small and len(ids) > 100:
            continue
        start, end = rng.choice(ids), rng.choice(ids + [None])
        for model in ("robot", "human"):
            for frac in (0.25, 0.5, 1.0):
                jobs.append((f"b{k}", path, len(ids), start, end or start, model, frac * total))

    def plan(job, alg, core):
        _, path, _, start, end, model, budget = job
        t0 = time.time()
        out = subprocess.run(["taskset", "-c", str(core), BIN, "plan", "--building", path, "--start", start,
                              "--end", end, "--budget", f"{budget:.1f}", "--model", model, "--algorithm", alg,
                              "--seed", "1", "--json"], capture_output=True, text=True,
                             env=dict(os.environ, RAYON_NUM_THREADS="1"))
        wall = time.time() - t0
        if out.returncode != 0:
            return dict(error=out.stderr.strip()[:160], wall=wall)
        d = json.loads(out.stdout)
        return dict(u=d["utility_nats"], length=d["length_m"], wall=wall,
                    reversals=reversals(path, d["walk"]))

    results = [(j, auto, coverage) for j, (auto, coverage) in
               on_two_cores(jobs, lambda j, core: (plan(j, "auto", core), plan(j, "coverage", core)))]
    flagged = 0
    refused = 0
    for j, a, c in sorted(results, key=lambda r: (r[0][0], r[0][5], r[0][6])):
        name, _, nv, start, end, model, budget = j
        head = f"{name} {nv} vertices {model} {budget:.0f} m {start} -> {end}:"
        if "error" in a or "error" in c:
            refused += 1
            print(head, "refused:", a.get("error") or c.get("error"))
            continue
        ratio = a["u"] / c["u"]
        flags = []
        if ratio < 1.05:
            flags.append("below 1.05x coverage")
        if a["length"] < 0.95 * budget:
            # A person's samples fall every 4.8 m (1.2 m/s, a scan every 4 s): a walk that
            # ends less than that short of the budget has room for no further sample.
            room = " (no room for another sample)" if model == "human" and budget - a["length"] < 4.8 else ""
            flags.append("uses less than 95% of the budget" + room)
        if a["wall"] > 2.35:
            flags.append("slow")
        flagged += bool(flags)
        # A person's walk: its reversals per 100 m (the robot may keep them where they pay).
        revs = f" reversals/100 m {100 * a['reversals'] / max(a['length'], 1e-9):.1f}" if model == "human" else ""
        print(head, f"auto {a['u']:.2f} coverage {c['u']:.2f} ratio {ratio:.3f} "
              f"length/budget {a['length'] / budget:.3f} wall {a['wall']:.2f} s{revs}", "; ".join(flags))
    # Utility never decreases when only the budget grows (same building, ends and model).
    by_case = {}
    for j, a, _ in results:
        if "u" in a:
            by_case.setdefault((j[0], j[5]), []).append((j[6], a["u"]))
    for (name, model), rows in sorted(by_case.items()):
        rows.sort()
        for (b0, u0), (b1, u1) in zip(rows, rows[1:]):
            if u1 < u0:
                flagged += 1
                print(f"{name} {model}: utility falls from {u0:.2f} at {b0:.0f} m to {u1:.2f} at {b1:.0f} m")
    print(f"buildings kept in {tmp} (b0.json ...), to plan a row again")
    print(f"{len(results)} rows, {flagged} flagged, {refused} refused")


if __name__ == "__main__":
    main()
