#!/usr/bin/env python3
"""Does leg_tracker's own cluster feature set transfer across recordings better than ours?
(issue 17). Decided inside leg_tracker's training set only, by leave-one-recording-out
cross-validation; the evaluation bag is touched once, afterwards, by `moving1`.

Feature sets, on the very same clusters (leg_tracker's clustering, 0.13 m / >= 3 points;
the rows of `Samples` with `SampleParams::default()`, dumped with their beams by
`examples/dump_cluster_features.rs`):

- `ours`: our 16 features (tracking/src/detect/features.rs), taken from the dump (the Rust
  values themselves, so no port can drift from them);
- `leg_tracker`: the 17 features of leg_tracker's `calc_cluster_features.cpp`
  (angusleigh/leg_tracker_benchmarks), recomputed here from its formulas, in float64 from
  the float32 ranges and angles a ROS scan carries (the C++ works in float32; the one place
  where that matters, Heron's area of a nearly flat triangle, whose float32 radicand can
  drop below 0 and give NaN, is clamped at 0 here);
- `union`: both, 33 columns.

Forest: scikit-learn RandomForestClassifier like ours (20 trees, no depth limit,
min_samples_leaf 5, max_features 4, bootstrap), n_jobs 1, seeds 0..4; figures are medians
over seeds.

Scheme (leave one recording out, `loro`): 6 folds. Fold k holds out the labelled legs of
positive recording k (positive_1, 2, 3, 4, 6, 7: each another place or day) and run k of
6 runs of consecutive scans of every negative topic (negative_2's left, rear and right
lasers): the negatives were recorded by a robot driven through rooms without people, so
a run of its scans is another stretch of the route, i.e. other rooms, and the three
lasers' scans of the same instants stay together (they see the same rooms at the same
time). Each fold thus holds out about 1/6 of the negatives with 1/6 of the recordings of
legs, and every training set keeps all three lasers. Positive recordings' unlabelled
clusters are not rows (as in Samples). Reported: the pooled out-of-fold AUC and, per held-
out recording, the AUC of its legs against the fold's negatives (scored by the same
forest). A second scheme, `loro_topic` (hold out positive k and one whole negative topic,
all 18 pairs), is reported as a check; it does not take part in the choice.

Choice, fixed before any look at general_tracking_moving_1: the set with the highest
median pooled `loro` AUC. Its lead over `ours` counts as a better transfer only when it
is at least 0.01 in pooled AUC and the set wins in at least 4 of the 6 held-out
recordings; otherwise the sets are called not distinguishable, and `ours` is kept (no
porting cost).

Commands (from the project root):
  cargo run --release --example dump_cluster_features -- training ../shared/data/leg_tracker/training/text OUT/train.csv
  python3 benches/peers/leg_features_transfer.py cv --rows OUT/train.csv --out OUT/cv.json
  cargo run --release --example dump_cluster_features -- eval ../shared/data/leg_tracker/general_tracking_moving_1 OUT/eval.csv
  python3 benches/peers/leg_features_transfer.py moving1 --rows OUT/train.csv --eval OUT/eval.csv --cv OUT/cv.json
"""

import argparse
import csv
import gzip
import json
import math
import os
import sys
import time

import numpy as np
from sklearn.ensemble import RandomForestClassifier
from sklearn.metrics import roc_auc_score

TRAINING = "../shared/data/leg_tracker/training/text"
MOVING_1 = "../shared/data/leg_tracker/general_tracking_moving_1"

OURS = [
    "points", "width", "length", "std", "median_deviation", "occluded", "linearity",
    "circularity", "radius", "boundary_length", "boundary_regularity", "mean_curvature",
    "mean_angle", "inscribed_angle_mean", "inscribed_angle_std", "distance",
]
LEG_TRACKER = [
    "num_points", "std", "avg_median_dev", "width1", "linearity", "circularity", "radius",
    "boundary_length", "boundary_regularity", "mean_curvature", "ang_diff", "iav", "std_iav",
    "distance", "distance_per_point", "occluded_right", "occluded_left",
]
SEEDS = range(5)
FOLDS = 6


# --------------------------------------------------------------------------- data

def read_scans(path):
    """Scans of a text copy: list of (angle_min, increment, range_min, range_max, ranges)
    at float32, as a ROS LaserScan carries them."""
    opener = gzip.open if path.endswith(".gz") else open
    out = []
    with opener(path, "rt") as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            t = line.split()
            n = int(t[7])
            ranges = np.array([float(v) for v in t[8:8 + n]], dtype=np.float32)
            if len(ranges) != n:
                raise ValueError(f"{path}: short scan line")
            head = np.array([float(v) for v in t[3:7]], dtype=np.float32)
            out.append((head[0], head[1], head[2], head[3], ranges))
    return out


def read_rows(path):
    """The dump of examples/dump_cluster_features.rs."""
    rows = []
    with open(path) as f:
        r = csv.DictReader(f)
        for d in r:
            rows.append(d)
    return rows


# ------------------------------------------------------------ leg_tracker features

def is_hit(r, rmin, rmax):
    return bool(r > rmin and r < rmax)  # NaN fails both, as in Sample::Extract


def leg_tracker_features(scan, indices):
    """The 17 features of calc_cluster_features.cpp for the beams `indices` (increasing)."""
    amin, inc, rmin, rmax, ranges = scan
    idx = np.asarray(indices)
    r = ranges[idx].astype(np.float64)
    ang = (np.float32(amin) + idx.astype(np.float32) * np.float32(inc)).astype(np.float64)
    P = np.stack([np.cos(ang) * r, np.sin(ang) * r], axis=1)
    n = len(P)
    mean = P.mean(axis=0)
    med = np.median(P, axis=0)  # 0.5 (v[(n-1)/2] + v[n/2]) per coordinate
    distance = math.hypot(med[0], med[1])
    d = P - mean
    std = math.sqrt((d ** 2).sum() / (n - 1.0))
    avg_median_dev = np.linalg.norm(P - med, axis=1).sum() / n

    # Occlusion: 1 unless the neighbouring beam is a hit farther than the end point (or
    # closer than 1 cm); a missing or out-of-range neighbour leaves it at 1.
    occluded_left = 1.0
    occluded_right = 1.0
    prev, nxt = idx[0] - 1, idx[-1] + 1
    if prev >= 0 and is_hit(ranges[prev], rmin, rmax):
        if ranges[idx[0]] < ranges[prev] or ranges[prev] < 0.01:
            occluded_left = 0.0
    if nxt < len(ranges) and is_hit(ranges[nxt], rmin, rmax):
        if ranges[idx[-1]] < ranges[nxt] or ranges[nxt] < 0.01:
            occluded_right = 0.0

    width1 = float(np.linalg.norm(P[-1] - P[0]))
    # Linearity: sum of squares of the centred points along the second singular vector.
    s = np.linalg.svd(d, compute_uv=False)
    linearity = float(s[1] ** 2) if len(s) > 1 else 0.0
    # Circle: least squares (SVD) of -2x xc - 2y yc + c = -(x^2 + y^2), laser frame.
    A = np.column_stack([-2.0 * P[:, 0], -2.0 * P[:, 1], np.ones(n)])
    B = -(P ** 2).sum(axis=1)
    sol = np.linalg.lstsq(A, B, rcond=None)[0]
    xc, yc = sol[0], sol[1]
    rc = math.sqrt(max(xc * xc + yc * yc - sol[2], 0.0))
    circularity = float(((rc - np.hypot(xc - P[:, 0], yc - P[:, 1])) ** 2).sum())
    radius = rc

    # Triples (right, mid, left) = (p[i-1], p[i], p[i+1]).
    right, mid, left = P[:-2], P[1:-1], P[2:]
    ml = left - mid
    mr = right - mid
    L_ml = np.linalg.norm(ml, axis=1)
    L_mr = np.linalg.norm(mr, axis=1)
    L_lr = np.linalg.norm(left - right, axis=1)
    Aa = (ml[:, 0] * mr[:, 0] + ml[:, 1] * mr[:, 1]) / L_mr ** 2
    Bb = (ml[:, 0] * mr[:, 1] - ml[:, 1] * mr[:, 0]) / L_mr ** 2
    th = np.arctan2(Bb, Aa)
    th = np.where(th < 0, th + 2 * math.pi, th)
    ang_diff = float(th.sum() / n)
    sp = 0.5 * (L_ml + L_mr + L_lr)
    area = np.sqrt(np.maximum(sp * (sp - L_ml) * (sp - L_mr) * (sp - L_lr), 0.0))
    k = 4 * area / (L_ml * L_mr * L_lr * n)
    mean_curvature = float(np.where(th > 0, k, -k).sum())
    segs = np.linalg.norm(np.diff(P, axis=0), axis=1)
    boundary_length = float(segs.sum())
    sumsq = float((segs ** 2).sum())
    boundary_regularity = math.sqrt(max(sumsq - boundary_length ** 2 / n, 0.0) / (n - 1))

    # Inscribed angles at p[1..n-2] between p[0] and p[n-1].
    ml = P[0] - mid
    mr = P[-1] - mid
    L_mr = np.linalg.norm(mr, axis=1)
    Aa = (ml[:, 0] * mr[:, 0] + ml[:, 1] * mr[:, 1]) / L_mr ** 2
    Bb = (ml[:, 0] * mr[:, 1] - ml[:, 1] * mr[:, 0]) / L_mr ** 2
    th = np.arctan2(Bb, Aa)
    th = np.where(th < 0, th + 2 * math.pi, th)
    s1, s2 = float(th.sum()), float((th ** 2).sum())
    iav = s1 / n
    std_iav = math.sqrt(max(s2 - s1 * s1 / n, 0.0) / (n - 1))

    f = [n, std, avg_median_dev, width1, linearity, circularity, radius, boundary_length,
         boundary_regularity, mean_curvature, ang_diff, iav, std_iav, distance,
         distance / n, occluded_right, occluded_left]
    return np.array(f, dtype=np.float64), P.mean(axis=0)


def self_test():
    """Known values of the port on synthetic clusters."""
    inc = np.float32(math.radians(0.25))
    # A circular arc of radius 0.06 m at 2 m facing the laser, 9 beams: its points are
    # where the beams hit the circle.
    rr, dd = 0.06, 2.0
    beams = np.arange(-4, 5)
    a = (beams.astype(np.float32) * inc).astype(np.float64)
    # Ray-circle intersection (near side).
    bq = -2 * dd * np.cos(a)
    rng = (-bq - np.sqrt(bq ** 2 - 4 * (dd ** 2 - rr ** 2))) / 2
    ranges = np.full(20, np.inf, dtype=np.float32)
    ranges[6:15] = rng.astype(np.float32)
    scan = (np.float32(-10 * inc), inc, np.float32(0.03), np.float32(11.0), ranges)
    f, _ = leg_tracker_features(scan, list(range(6, 15)))
    g = dict(zip(LEG_TRACKER, f))
    assert abs(g["radius"] - rr) < 1e-5, g["radius"]
    assert g["circularity"] < 1e-10
    assert abs(g["mean_curvature"] - 7 / 9 / rr) < 1e-2, g["mean_curvature"]
    assert g["occluded_left"] == 1 and g["occluded_right"] == 1  # neighbours are inf
    assert abs(g["num_points"] - 9) == 0
    # The arc bulges towards the laser: going from p[i+1] to p[i-1] counterclockwise the
    # angle at p[i] is > pi in the scan's (counterclockwise) turning sense, or < pi.
    assert abs(g["ang_diff"] * 9 / 7 - math.pi) < 1.0
    # A wall: linearity 0, a neighbour farther on the right unoccludes that side.
    ranges = np.full(20, 3.0, dtype=np.float32)
    ranges[6:12] = (2.0 / np.cos((np.arange(6, 12) - 10) * inc)).astype(np.float32)
    scan = (np.float32(-10 * inc), inc, np.float32(0.03), np.float32(11.0), ranges)
    f, _ = leg_tracker_features(scan, list(range(6, 12)))
    g = dict(zip(LEG_TRACKER, f))
    assert g["linearity"] < 1e-10, g["linearity"]
    assert g["occluded_left"] == 0 and g["occluded_right"] == 0
    assert abs(g["ang_diff"] * 6 / 4 - math.pi) < 1e-4
    assert abs(g["iav"] * 6 / 4 - math.pi) < 1e-4
    assert abs(g["distance"] - 2.0) < 1e-3


def feature_table(rows, scans_of):
    """Our features (from the dump), leg_tracker's (recomputed), labels, recordings,
    scans."""
    ours = np.array([[float(d[k]) for k in OURS] for d in rows])
    lt = np.empty((len(rows), len(LEG_TRACKER)))
    worst = 0.0
    for i, d in enumerate(rows):
        scan = scans_of(d["recording"])[int(d["scan"])]
        idx = [int(v) for v in d["indices"].split()]
        lt[i], c = leg_tracker_features(scan, idx)
        worst = max(worst, abs(c[0] - float(d["cx"])), abs(c[1] - float(d["cy"])))
    if worst > 1e-4:
        raise SystemExit(f"centroids differ from the dump's by {worst} m: scans misaligned")
    legs = np.array([d["leg"] == "1" for d in rows])
    rec = np.array([d["recording"] for d in rows])
    scan = np.array([int(d["scan"]) for d in rows])
    return {"ours": ours, "leg_tracker": lt, "union": np.hstack([ours, lt])}, legs, rec, scan, worst


def load_training(rows_path, data_dir):
    rows = read_rows(rows_path)
    cache = {}

    def scans_of(name):
        if name not in cache:
            cache[name] = read_scans(os.path.join(data_dir, f"{name}.scans.txt.gz"))
        return cache[name]

    sets, legs, rec, scan, worst = feature_table(rows, scans_of)
    n_scans = {name: len(v) for name, v in cache.items()}
    return sets, legs, rec, scan, n_scans, worst


# ------------------------------------------------------------------------- forests

def forest(seed):
    return RandomForestClassifier(
        n_estimators=20, max_depth=None, min_samples_leaf=5, max_features=4,
        bootstrap=True, n_jobs=1, random_state=seed)


def loro_folds(legs, rec, scan, n_scans):
    """Fold of each row under `loro` (see the module doc)."""
    positives = sorted(r for r in n_scans if r.startswith("positive"))
    fold = np.full(len(legs), -1)
    for i, (r, s) in enumerate(zip(rec, scan)):
        if r.startswith("positive"):
            fold[i] = positives.index(r)
        else:
            fold[i] = min(s * FOLDS // n_scans[r], FOLDS - 1)
    assert (fold >= 0).all()
    return fold, positives


def run_folds(X, y, fold, seed):
    """Out-of-fold probabilities and per-fold AUCs (each fold scored by its own forest)."""
    oof = np.zeros(len(y))
    per = []
    for k in sorted(set(fold)):
        test = fold == k
        m = forest(seed).fit(X[~test], y[~test])
        oof[test] = m.predict_proba(X[test])[:, 1]
        per.append(roc_auc_score(y[test], oof[test]))
    return roc_auc_score(y, oof), per


def cv(args):
    self_test()
    t0 = time.time()
    sets, legs, rec, scan, n_scans, worst = load_training(args.rows, args.data)
    nan = {k: int(np.isnan(v).sum()) for k, v in sets.items()}
    print(f"{len(legs)} rows, {legs.sum()} legs; centroids agree within {worst:.1e} m; "
          f"NaN cells {nan}; features {time.time() - t0:.0f} s", flush=True)
    fold, positives = loro_folds(legs, rec, scan, n_scans)
    out = {"rows": int(len(legs)), "legs": int(legs.sum()), "seeds": list(SEEDS),
           "held_out": positives, "schemes": {}}

    # Primary: loro.
    res = {}
    for name, X in sets.items():
        pooled, per = [], []
        for seed in SEEDS:
            p, f = run_folds(X, legs, fold, seed)
            pooled.append(p)
            per.append(f)
            print(f"  loro {name} seed {seed}: pooled {p:.4f} per fold "
                  f"{' '.join(f'{v:.3f}' for v in f)}", flush=True)
        res[name] = {"pooled": pooled, "per_fold": per,
                     "pooled_median": float(np.median(pooled)),
                     "per_fold_median": [float(v) for v in np.median(per, axis=0)]}
    out["schemes"]["loro"] = res

    # The choice (rule in the module doc), before anything else is run.
    best = max(res, key=lambda k: res[k]["pooled_median"])
    lead = res[best]["pooled_median"] - res["ours"]["pooled_median"]
    wins = sum(a > b for a, b in zip(res[best]["per_fold_median"],
                                    res["ours"]["per_fold_median"]))
    better = best != "ours" and lead >= 0.01 and wins >= 4
    out["choice"] = {
        "best_pooled": best, "lead_over_ours": lead, "folds_won_over_ours": wins,
        "transfers_better_than_ours": bool(better),
        "chosen": best if better else "ours",
        "lt_vs_ours": {
            "lead": res["leg_tracker"]["pooled_median"] - res["ours"]["pooled_median"],
            "folds_won": sum(a > b for a, b in zip(res["leg_tracker"]["per_fold_median"],
                                                   res["ours"]["per_fold_median"]))},
        "made_at_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }
    print("choice:", json.dumps(out["choice"]), flush=True)
    with open(args.out, "w") as f:
        json.dump(out, f, indent=1)

    if not args.skip_checks:
        # Check 1: the consecutive-run folds of train.rs (5 runs of every recording).
        res = {}
        for name, X in sets.items():
            f5 = np.zeros(len(legs), dtype=int)
            for i, (r, s) in enumerate(zip(rec, scan)):
                f5[i] = min(s * 5 // n_scans[r], 4)
            pooled = [run_folds(X, legs, f5, seed)[0] for seed in SEEDS[:3]]
            res[name] = {"pooled": pooled, "pooled_median": float(np.median(pooled))}
            print(f"  runs {name}: {res[name]['pooled_median']:.4f}", flush=True)
        out["schemes"]["consecutive_runs"] = res
        with open(args.out, "w") as f:
            json.dump(out, f, indent=1)
        # Check 2: loro_topic, 18 pairs (positive k, negative topic t).
        topics = sorted(r for r in n_scans if r.startswith("negative"))
        res = {}
        for name, X in sets.items():
            per = []
            for seed in SEEDS[:3]:
                aucs = []
                for pk in positives:
                    for t in topics:
                        test = (rec == pk) | (rec == t)
                        train = ~test & ((rec != pk) & (rec != t))
                        m = forest(seed).fit(X[train], legs[train])
                        aucs.append(roc_auc_score(legs[test],
                                                  m.predict_proba(X[test])[:, 1]))
                per.append(aucs)
            med = np.median(per, axis=0)  # per pair, over seeds
            res[name] = {"pairs": [f"{p}/{t}" for p in positives for t in topics],
                         "per_pair_median": [float(v) for v in med],
                         "mean_of_pairs": float(med.mean())}
            print(f"  loro_topic {name}: mean of 18 pairs {med.mean():.4f}", flush=True)
        out["schemes"]["loro_topic"] = res
        with open(args.out, "w") as f:
            json.dump(out, f, indent=1)
    print(f"done in {time.time() - t0:.0f} s")


def moving1(args):
    """Once, after the choice: each set's forest trained on every training row, scored on
    the clusters of cluster_quality.rs' protocol."""
    with open(args.cv) as f:
        cvres = json.load(f)
    if "choice" not in cvres:
        raise SystemExit("no choice recorded: run `cv` first")
    print("choice made before:", json.dumps(cvres["choice"]))
    sets, legs, _, _, _, _ = load_training(args.rows, args.data)
    erows = read_rows(args.eval)
    ev_scans = read_scans(os.path.join(args.sequence, "scans.txt"))
    esets, elegs, _, _, worst = feature_table(erows, lambda _: ev_scans)
    width = -np.array([float(d["width"]) for d in erows])
    shipped = np.array([float(d["probability"]) for d in erows])
    out = {"clusters": int(len(elegs)), "legs": int(elegs.sum()),
           "centroid_agreement_m": worst,
           "shipped_forest_auc": roc_auc_score(elegs, shipped),
           "width_auc": roc_auc_score(elegs, width), "sets": {}}
    for name, X in sets.items():
        aucs = [roc_auc_score(elegs, forest(seed).fit(X, legs).predict_proba(esets[name])[:, 1])
                for seed in SEEDS]
        out["sets"][name] = {"aucs": aucs, "median": float(np.median(aucs))}
        print(f"  moving_1 {name}: median {np.median(aucs):.4f} "
              f"({' '.join(f'{a:.3f}' for a in aucs)})", flush=True)
    out["choice"] = cvres["choice"]
    print(json.dumps(out))
    with open(args.out, "w") as f:
        json.dump(out, f, indent=1)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("cv")
    a.add_argument("--rows", required=True)
    a.add_argument("--data", default=TRAINING)
    a.add_argument("--out", required=True)
    a.add_argument("--skip-checks", action="store_true")
    b = sub.add_parser("moving1")
    b.add_argument("--rows", required=True)
    b.add_argument("--eval", required=True)
    b.add_argument("--cv", required=True)
    b.add_argument("--data", default=TRAINING)
    b.add_argument("--sequence", default=MOVING_1)
    b.add_argument("--out", required=True)
    sub.add_parser("self-test")
    args = p.parse_args()
    if args.cmd == "cv":
        cv(args)
    elif args.cmd == "moving1":
        moving1(args)
    else:
        self_test()
        print("ok")


if __name__ == "__main__":
    sys.exit(main())
