#!/usr/bin/env python3
"""Writes demo-building.json: a small office floor for the demo app and the Kotlin tests.

A 30 m corridor (vertices every 1.5 m), a 10.5 m side corridor off its middle, and a
6 m x 4.5 m meeting room off the east end, joined by doors. Pilot fingerprints at 10
places come from a log-distance model of 5 access points (seeded, rounded to 1 dB), and
the kernel is given so that nothing needs fitting. Deterministic: run it again to get
the same file.
"""
import json
import math
import random

rng = random.Random(7)
vertices, edges = [], []


def v(vid, x, y, label=None):
    d = {"id": vid, "x": round(x, 3), "y": round(y, 3)}
    if label:
        d["label"] = label
    vertices.append(d)
    return vid


corr = [v(f"c{i:02d}", 1.5 * i, 0.0, "Lobby" if i == 0 else None) for i in range(21)]
edges += [{"a": a, "b": b} for a, b in zip(corr, corr[1:])]
side = [v(f"s{i:02d}", 15.0, 1.5 * i) for i in range(1, 8)]
edges += [{"a": "c10", "b": side[0]}] + [{"a": a, "b": b} for a, b in zip(side, side[1:])]
vertices[-1]["label"] = "Kitchen"
room = []
for j in range(4):
    for i in range(5):
        room.append(v(f"r{j}{i}", 24.0 + 1.5 * i, -1.5 - 1.5 * j))
for j in range(4):
    for i in range(5):
        if i < 4:
            edges.append({"a": f"r{j}{i}", "b": f"r{j}{i+1}"})
        if j < 3:
            edges.append({"a": f"r{j}{i}", "b": f"r{j+1}{i}"})
edges.append({"a": "c16", "b": "r00", "length": 2.5})  # a door
edges.append({"a": "c20", "b": "r04"})
vertices[[x["id"] for x in vertices].index("r33")]["label"] = "Meeting room"

aps = {"ap-lobby": (1.0, 2.0), "ap-mid": (14.0, -2.0), "ap-side": (16.0, 9.0),
       "ap-room": (28.0, -4.0), "ap-east": (31.0, 1.0)}


def rss(x, y):
    out = {}
    for name, (ax, ay) in aps.items():
        d = max(1.0, math.hypot(x - ax, y - ay))
        r = -40.0 - 25.0 * math.log10(d) + rng.gauss(0, 2.0)
        if r > -92:
            out[name] = float(round(r))
    return out


pilot_places = [(0, 0), (6, 0), (12, 0), (18, 0), (24, 0), (30, 0),
                (15, 6), (15, 10.5), (25.5, -3), (28.5, -6)]
pilot = [{"x": float(x), "y": float(y), "rss": rss(x, y)} for x, y in pilot_places]

doc = {
    "format": "survey-building/1",
    "name": "Demo office",
    "floors": [{"id": 0, "name": "Ground"}],
    "vertices": vertices,
    "edges": edges,
    "pilot": pilot,
    "kernel": {"sf2": 40.0, "ell": 6.0, "sn2": 4.0},
}
with open("demo-building.json", "w") as f:
    json.dump(doc, f, indent=1)
    f.write("\n")
print(f"{len(vertices)} vertices, {len(edges)} edges, {len(pilot)} pilot points")
