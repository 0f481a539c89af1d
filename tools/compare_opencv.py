#!/usr/bin/env python3
"""Compares `weldseam calibrate` with OpenCV's calibrateHandEye (all its
methods) on the same simulated board sets, and prints a Markdown table of
each one's error against the simulator's truth (translation mm / rotation
degrees).

Not part of the default test run. A developer runs it by hand:

    pip install "opencv-python-headless<5" numpy   (5.0 dropped calibrateHandEye from its Python module)
    cargo build --release
    python3 tools/compare_opencv.py [--weldseam target/release/weldseam]

Each set is written by `weldseam simulate --calibration board` (15
captures, robot noise 0.05 mm and 0.01 degrees RMS, board noise 0.05 mm and
0.02 degrees RMS) into a temporary directory; weldseam reads the capture
file, OpenCV the same numbers. OpenCV solves a camera fixed in the cell
when given the inverse robot poses, as its documentation says.
"""

import argparse
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

METHODS = [
    ("Tsai", cv2.CALIB_HAND_EYE_TSAI),
    ("Park", cv2.CALIB_HAND_EYE_PARK),
    ("Horaud", cv2.CALIB_HAND_EYE_HORAUD),
    ("Andreff", cv2.CALIB_HAND_EYE_ANDREFF),
    ("Daniilidis", cv2.CALIB_HAND_EYE_DANIILIDIS),
]

# (label, seed, extra simulate flags); seeds 201 and up were not used while
# weldseam's solver was written.
SETS = [
    ("clean", 201, []),
    ("clean", 202, []),
    ("clean", 203, []),
    ("eye-to-hand", 204, ["--eye-to-hand"]),
    ("eye-to-hand", 205, ["--eye-to-hand"]),
    ("wrong pairing (capture 7)", 206, ["--wrong-pairing", "7"]),
    ("wrong pairing (capture 2)", 207, ["--wrong-pairing", "2"]),
    ("small rotations", 208, ["--small-rotations"]),
    ("small rotations", 209, ["--small-rotations"]),
    ("near-parallel axes", 210, ["--parallel-axes"]),
]


def rotation_zyx(rx, ry, rz):
    """R = Rz(rz) Ry(ry) Rx(rx), angles in degrees (the `zyx` convention)."""
    a, b, c = (math.radians(v) for v in (rx, ry, rz))
    x = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    y = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    z = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    return z @ y @ x


def matrix(rows):
    return np.array(rows, dtype=float).reshape(4, 4)


def error(found, truth):
    t = np.linalg.norm(found[:3, 3] - truth[:3, 3])
    r = found[:3, :3] @ truth[:3, :3].T
    angle = math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(r) - 1) / 2))))
    return t, angle


def opencv(captures, eye_to_hand, method):
    r_hand, t_hand, r_target, t_target = [], [], [], []
    for c in captures:
        x, y, z, rx, ry, rz = c["robot_pose"]
        hand = np.eye(4)
        hand[:3, :3] = rotation_zyx(rx, ry, rz)
        hand[:3, 3] = [x, y, z]
        if eye_to_hand:
            hand = np.linalg.inv(hand)
        target = matrix(c["camera_T_target"])
        r_hand.append(hand[:3, :3])
        t_hand.append(hand[:3, 3].reshape(3, 1))
        r_target.append(target[:3, :3])
        t_target.append(target[:3, 3].reshape(3, 1))
    r, t = cv2.calibrateHandEye(r_hand, t_hand, r_target, t_target, method=method)
    out = np.eye(4)
    out[:3, :3] = r
    out[:3, 3] = t.ravel()
    return out


def errors_on(weldseam, tmp, seed, flags):
    """weldseam's and each OpenCV method's (translation, rotation) error on
    one simulated set, and weldseam's report."""
    captures_path = Path(tmp) / f"set-{seed}.json"
    truth_path = Path(tmp) / f"truth-{seed}.json"
    subprocess.run(
        [weldseam, "simulate", "--calibration", "board", "--seed", str(seed),
         "--out", str(captures_path), "--truth", str(truth_path)] + flags,
        check=True, stdout=subprocess.DEVNULL)
    eye_to_hand = "--eye-to-hand" in flags
    report = json.loads(subprocess.run(
        [weldseam, "calibrate", "--captures", str(captures_path), "--json"]
        + (["--eye-to-hand"] if eye_to_hand else []),
        check=True, capture_output=True, text=True).stdout)
    truth = matrix(json.loads(truth_path.read_text())["hand_eye"])
    captures = json.loads(captures_path.read_text())["captures"]
    found = [matrix(report["hand_eye"])] + [opencv(captures, eye_to_hand, m) for _, m in METHODS]
    return [error(f, truth) for f in found], report


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--weldseam", default="target/release/weldseam")
    parser.add_argument("--seeds", type=int, default=20, help="clean sets in the summary")
    args = parser.parse_args()
    header = ["set", "seed", "weldseam"] + [name for name, _ in METHODS] + ["flagged", "warned"]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    with tempfile.TemporaryDirectory() as tmp:
        for label, seed, flags in SETS:
            errors, report = errors_on(args.weldseam, tmp, seed, flags)
            cells = [f"{t:.3f} / {r:.4f}" for t, r in errors]
            flagged = ", ".join(str(i) for i in report["outliers"]) or "-"
            warned = "yes" if any("ill-posed" in w or "too little" in w for w in report["warnings"]) else "-"
            print(f"| {label} | {seed} | " + " | ".join(cells) + f" | {flagged} | {warned} |")
        # Over many clean sets: the mean and worst error of each, and how
        # often weldseam is at least as close as OpenCV's best method.
        runs = [errors_on(args.weldseam, tmp, 300 + k, [])[0] for k in range(args.seeds)]
        print()
        print(f"Clean sets, seeds 300 to {299 + args.seeds}: mean and worst error (mm / degrees)")
        print()
        print("| | weldseam | " + " | ".join(name for name, _ in METHODS) + " |")
        print("|---|" + "---|" * (len(METHODS) + 1))
        for what, pick in [("mean", lambda v: sum(v) / len(v)), ("worst", max)]:
            cells = []
            for k in range(len(METHODS) + 1):
                cells.append(f"{pick([r[k][0] for r in runs]):.3f} / {pick([r[k][1] for r in runs]):.4f}")
            print(f"| {what} | " + " | ".join(cells) + " |")
        closer = sum(1 for r in runs if r[0][0] <= min(e[0] for e in r[1:]))
        print()
        print(f"weldseam's translation at least as close as OpenCV's best method on {closer} of {len(runs)} sets")
    return 0


if __name__ == "__main__":
    sys.exit(main())
