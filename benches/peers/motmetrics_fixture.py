#!/usr/bin/env python3
"""CLEAR MOT cross-check fixture for haunts-tracking's `metrics::clear_mot`.

Generates a seeded synthetic multi-object scenario (people walking in and out of a 12 m x
12 m room; hypotheses with noise, misses, false positives, identity swaps and fragmented
tracks), scores it with

- the `motmetrics` package (`MOTAccumulator`, LAP solver forced to scipy), on plain
  Euclidean distances in metres with pairs beyond 0.75 m set to NaN (`max_d = 0.75`), so
  its MOTP is a mean distance in metres (not the mean squared distance that
  `norm2squared_matrix` would give);
- a port of the per-frame logic of `clear_mot.py` (angusleigh/leg_tracker_benchmarks,
  `ClearMot.calc_clear_mot`), with the `munkres` package as there,

and writes the frames and both results to tracking/tests/fixtures/clear_mot_motmetrics.json.

    python3 benches/peers/motmetrics_fixture.py [--seed 2008] [--out PATH]
"""

import argparse
import json
import math
from pathlib import Path

import motmetrics as mm
import munkres
import numpy as np

THRESHOLD = 0.75
ROOM = 12.0


def scenario(seed, people=10, frames=200, dt=0.1):
    """Truth and hypothesis frames: lists of [(id, x, y)] per frame."""
    rng = np.random.default_rng(seed)
    # Each person: entry frame, exit frame, start position, velocity (changing slowly).
    persons = []
    for pid in range(1, people + 1):
        start = int(rng.integers(0, frames // 2))
        end = int(min(frames, start + rng.integers(frames // 4, frames)))
        pos = rng.uniform(1.0, ROOM - 1.0, 2)
        heading = rng.uniform(-math.pi, math.pi)
        speed = rng.uniform(0.0, 1.4)  # some stand still
        persons.append(dict(id=pid, start=start, end=end, pos=pos, heading=heading, speed=speed))

    # Hypothesis id of each person's track; changed to fragment tracks and swap identities.
    track_of = {p["id"]: 100 + p["id"] for p in persons}
    next_track = 200
    truth, hyps = [], []
    for k in range(frames):
        t_frame, h_frame = [], []
        present = []
        for p in persons:
            if not p["start"] <= k < p["end"]:
                continue
            p["heading"] += rng.normal(0.0, 0.15)
            step = p["speed"] * dt * np.array([math.cos(p["heading"]), math.sin(p["heading"])])
            p["pos"] = np.clip(p["pos"] + step, 0.0, ROOM)
            present.append(p)
            t_frame.append((p["id"], *p["pos"]))

        # Identity swap between the two closest present people, now and then.
        if len(present) >= 2 and rng.random() < 0.05:
            a, b = rng.choice(len(present), 2, replace=False)
            ia, ib = present[a]["id"], present[b]["id"]
            track_of[ia], track_of[ib] = track_of[ib], track_of[ia]
        for p in present:
            if rng.random() < 0.02:  # track lost and restarted with a new id
                track_of[p["id"]] = next_track
                next_track += 1
            if rng.random() < 0.1:  # miss
                continue
            # Mostly small noise; sometimes a large error near or beyond the threshold.
            sigma = 0.12 if rng.random() < 0.9 else 0.5
            x, y = p["pos"] + rng.normal(0.0, sigma, 2)
            h_frame.append((track_of[p["id"]], x, y))
        # False positives: anywhere, or close to a person (a second track on them).
        for _ in range(int(rng.poisson(0.6))):
            if present and rng.random() < 0.4:
                p = present[int(rng.integers(len(present)))]
                x, y = p["pos"] + rng.normal(0.0, 0.4, 2)
            else:
                x, y = rng.uniform(0.0, ROOM, 2)
            h_frame.append((next_track, x, y))
            next_track += 1
        rnd = lambda objs: [(int(i), round(float(x), 6), round(float(y), 6)) for i, x, y in objs]
        truth.append(rnd(t_frame))
        hyps.append(rnd(h_frame))
    return truth, hyps


def distances(truth, hyp):
    """Plain Euclidean distances, NaN beyond the threshold (motmetrics: do not pair)."""
    if not truth or not hyp:
        return np.empty((len(truth), len(hyp)))
    o = np.array([[x, y] for _, x, y in truth])
    h = np.array([[x, y] for _, x, y in hyp])
    d = np.sqrt(mm.distances.norm2squared_matrix(o, h))
    d[d > THRESHOLD] = np.nan
    return d


def score_motmetrics(truth, hyps):
    acc = mm.MOTAccumulator(auto_id=True)
    with mm.lap.set_default_solver("scipy"):
        for t, h in zip(truth, hyps):
            acc.update([i for i, _, _ in t], [i for i, _, _ in h], distances(t, h))
    names = ["num_frames", "num_objects", "num_predictions", "num_matches", "num_switches",
             "num_false_positives", "num_misses", "num_detections", "mota", "motp"]
    summary = mm.metrics.create().compute(acc, metrics=names, name="fixture")
    out = {n: summary[n].iloc[0].item() for n in names}
    for n in names[:-2]:
        out[n] = int(out[n])
    return out


def score_clear_mot_py(truth, hyps):
    """The per-frame logic of leg_tracker_benchmarks' clear_mot.py (est = hypothesis,
    gt = truth), without the ROS plumbing."""
    correct = switches = misses = fps = total = 0
    dist_sum, dist_count = 0.0, 0
    prev = {}  # est id -> gt id, latest pairs
    dist = lambda a, b: math.hypot(a[1] - b[1], a[2] - b[2])
    for gts, ests in zip(truth, hyps):
        total += len(gts)
        matches = {}  # est index -> gt index
        for e_id, g_id in prev.items():
            e = next((i for i, o in enumerate(ests) if o[0] == e_id), None)
            g = next((i for i, o in enumerate(gts) if o[0] == g_id), None)
            if e is not None and g is not None and dist(ests[e], gts[g]) < THRESHOLD:
                matches[e] = g
        matrix = [[dist(e, g) if ei not in matches and gi not in matches.values() else 99999.0
                   for gi, g in enumerate(gts)] for ei, e in enumerate(ests)]
        if matrix and matrix[0]:
            for ei, gi in munkres.Munkres().compute(matrix):
                if matrix[ei][gi] < THRESHOLD:
                    matches[ei] = gi
        fps += sum(1 for ei in range(len(ests)) if ei not in matches)
        misses += sum(1 for gi in range(len(gts)) if gi not in matches.values())
        for ei, gi in matches.items():
            e_id, g_id = ests[ei][0], gts[gi][0]
            if e_id in prev:
                if prev[e_id] == g_id:
                    correct += 1
                else:
                    switches += 1
            elif g_id in prev.values():
                switches += 1
            else:
                correct += 1
            dist_sum += dist(ests[ei], gts[gi])
            dist_count += 1
        matched_e = {ests[ei][0] for ei in matches}
        matched_g = {gts[gi][0] for gi in matches.values()}
        prev = {e: g for e, g in prev.items() if e not in matched_e and g not in matched_g}
        for ei, gi in matches.items():
            prev[ests[ei][0]] = gts[gi][0]
    assert total == correct + switches + misses
    return {
        "num_frames": len(truth),
        "num_objects": total,
        "num_predictions": sum(len(h) for h in hyps),
        "num_detections": dist_count,
        "num_matches": correct,
        "num_switches": switches,
        "num_false_positives": fps,
        "num_misses": misses,
        "mota": 1.0 - (switches + fps + misses) / total,
        "motp": dist_sum / dist_count,
    }


def main():
    root = Path(__file__).resolve().parents[2]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=2008)
    parser.add_argument("--out", type=Path,
                        default=root / "tracking/tests/fixtures/clear_mot_motmetrics.json")
    args = parser.parse_args()

    truth, hyps = scenario(args.seed)
    result = {
        "generator": "benches/peers/motmetrics_fixture.py",
        "motmetrics_version": mm.__version__,
        "munkres_version": getattr(munkres, "__version__", "unknown"),
        "seed": args.seed,
        "match_threshold": THRESHOLD,
        "distance": "euclidean metres; motmetrics pairs with d > match_threshold set to NaN",
        "motmetrics": score_motmetrics(truth, hyps),
        "clear_mot_py": score_clear_mot_py(truth, hyps),
        "frames": [
            {"time": round(k * 0.1, 6), "truth": [list(o) for o in t], "hypotheses": [list(o) for o in h]}
            for k, (t, h) in enumerate(zip(truth, hyps))
        ],
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(result, f, separators=(",", ":"))
        f.write("\n")
    print(json.dumps({k: result[k] for k in ("motmetrics", "clear_mot_py")}, indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
