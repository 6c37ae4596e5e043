#!/usr/bin/env python3
"""How much could any rule that confirms tentative tracks sooner gain on a recorded sequence?

Reads the CSV that `cargo run --release --example eval_tracking -- <dir> --tracker kf
--tentative FILE` writes: one row per tentative (not yet confirmed) track at each scored scan,
with `person` = 1 when an annotated person stood within the match threshold. Reporting a
tentative track with `person` = 1 removes a miss; reporting one with `person` = 0 adds a false
positive. So a confirmation rule gains `reported people - reported clutter` errors.

An *oracle* is trained to tell the two apart from what the tracker knows of each track (hits,
age, distance travelled, speed, position uncertainty, hits per second) and where it is (range
and bearing in the laser frame), with the sequence's own labels: random forests and gradient
boosting, cross-validated over blocks of `--block` consecutive scans (neighbouring scans
share tracks, so a random split would leak). For each model it prints the ROC AUC and the
best net gain over all thresholds. No rule over these features can do better than a model
trained on the answers, up to the cross-validation's noise, so the best net gain bounds what
tuning the confirmation can bring.

    python3 benches/peers/confirmation_oracle.py FILE [--block 40] [--folds 5] [--seeds 3]

Prints one JSON line. Needs scikit-learn (benches/peers/requirements-gp.txt).
"""

import argparse
import csv
import json
import math

import numpy as np
from sklearn.ensemble import HistGradientBoostingClassifier, RandomForestClassifier
from sklearn.metrics import roc_auc_score
from sklearn.model_selection import GroupKFold, cross_val_predict


def load(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"{path}: no tentative samples")
    scan = np.array([int(r["scan"]) for r in rows])
    person = np.array([int(r["person"]) for r in rows])
    features = []
    for r in rows:
        x, y = float(r["x"]), float(r["y"])
        hits, age = float(r["hits"]), float(r["age"])
        features.append(
            [
                hits,
                age,
                float(r["travel"]),
                float(r["speed"]),
                float(r["position_std"]),
                hits / max(age, 0.1),
                math.hypot(x, y),
                math.atan2(y, x),
            ]
        )
    return np.array(features), person, scan


def best_net_gain(person, score):
    """max over thresholds t of #(person, score >= t) - #(clutter, score >= t), and 0 for
    reporting nothing."""
    order = np.argsort(-score, kind="stable")
    s, p = score[order], person[order]
    gain = np.cumsum(np.where(p == 1, 1, -1))
    # Only cut between distinct scores: equal scores are reported together.
    last_of_value = np.r_[s[1:] != s[:-1], True]
    return int(max(0, gain[last_of_value].max()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv")
    ap.add_argument("--block", type=int, default=40, help="scans per cross-validation group")
    ap.add_argument("--folds", type=int, default=5)
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()

    X, y, scan = load(args.csv)
    if y.min() == y.max():
        raise SystemExit("need both people and clutter among the samples")
    groups = scan // args.block
    models = {
        "random_forest": lambda seed: RandomForestClassifier(
            n_estimators=300, min_samples_leaf=3, random_state=seed
        ),
        "gradient_boosting": lambda seed: HistGradientBoostingClassifier(
            max_depth=3, random_state=seed
        ),
    }
    out = {"samples": int(len(y)), "people": int(y.sum()), "block": args.block, "models": {}}
    for name, make in models.items():
        aucs, gains = [], []
        for seed in range(args.seeds):
            p = cross_val_predict(
                make(seed), X, y, groups=groups, cv=GroupKFold(args.folds), method="predict_proba"
            )[:, 1]
            aucs.append(roc_auc_score(y, p))
            gains.append(best_net_gain(y, p))
        out["models"][name] = {
            "auc": round(float(np.median(aucs)), 3),
            "best_net_gain": int(np.median(gains)),
            "best_net_gain_max": int(max(gains)),
        }
    # What no model is needed for: report every tentative track.
    out["report_all_net_gain"] = int(2 * y.sum() - len(y))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
