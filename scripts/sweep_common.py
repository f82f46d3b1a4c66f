"""What the sweep scripts share: a building's total edge length, and running jobs two at a
time, each pinned to its own core (0 and 1)."""
import math, queue, threading


def total_length(b):
    """Sum of a `survey-building/1` file's edge lengths (an edge without `length` is as long
    as the straight line between its ends)."""
    pos = {v["id"]: (v["x"], v["y"]) for v in b["vertices"]}
    return sum(e.get("length", math.dist(pos[e["a"]], pos[e["b"]])) for e in b["edges"])


def on_two_cores(jobs, run):
    """`run(job, core)` for every job, two at a time on cores 0 and 1; the list of
    `(job, result)` in the order they finished."""
    todo = queue.Queue()
    for j in jobs:
        todo.put(j)
    results = []

    def worker(core):
        while True:
            try:
                j = todo.get_nowait()
            except queue.Empty:
                return
            results.append((j, run(j, core)))

    threads = [threading.Thread(target=worker, args=(c,)) for c in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return results
