#!/usr/bin/env python3
"""How well a rectified stereo pair's rows agree: the vertical offset v_right - v_left of the
same point in the two images, over a KITTI-layout folder.

    python3 scripts/stereo_rows.py FOLDER [--every N] [--max_points M]

FOLDER holds image_0/ (left), image_1/ (right) and calib.txt (P0: fx, cx, cy). On every N-th
frame (default 5): OpenCV's corners (goodFeaturesToTrack) in the left image, tracked into the
right image by pyramidal Lucas-Kanade in 2D and back; a point is kept when the round trip returns
within 0.1 px. Printed: the points kept, the median offset, the medians over the left / middle /
right thirds of the columns and the top / middle / bottom thirds of the rows, and the
least-squares fit dv = a + b x + c y with x = (u - cx) / fx, y = (v - cy) / fx (a: the rows'
shift, b: a roll of the right camera about its optical axis, c: a vertical scale difference).

A perfect rectification gives 0 everywhere. dala's stereo matcher searches the right point on
the left point's row (stereo.max_dv_px, 1.5 px, bounds how far the rows may disagree) and
refines the disparity along that row (frontend/stereo.h). Needs numpy and OpenCV's Python
module (Debian: python3-numpy python3-opencv).
"""
import argparse
import os
import sys

import cv2
import numpy as np


def read_p0(path):
    if not os.path.isfile(path):
        sys.exit("stereo_rows: %s is missing (a KITTI calib.txt with a P0 line)" % path)
    with open(path) as f:
        for line in f:
            key, _, values = line.partition(":")
            if key.strip() == "P0":
                p = [float(x) for x in values.split()]
                if len(p) == 12:
                    return p[0], p[2], p[6]  # fx, cx, cy
    sys.exit("stereo_rows: %s has no P0 line with 12 numbers" % path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder")
    parser.add_argument("--every", type=int, default=5, help="use every N-th frame (default 5)")
    parser.add_argument("--max_points", type=int, default=2000, help="corners per frame")
    args = parser.parse_args()
    if args.every < 1:
        sys.exit("stereo_rows: --every must be >= 1")
    left_dir, right_dir = os.path.join(args.folder, "image_0"), os.path.join(args.folder, "image_1")
    for d in (left_dir, right_dir):
        if not os.path.isdir(d):
            sys.exit("stereo_rows: %s is not a folder (a KITTI-layout stereo folder has image_0/ "
                     "and image_1/)" % d)
    fx, cx, cy = read_p0(os.path.join(args.folder, "calib.txt"))
    names = sorted(n for n in os.listdir(left_dir)
                   if os.path.splitext(n)[1].lower() in (".png", ".jpg", ".jpeg"))[:: args.every]
    if not names:
        sys.exit("stereo_rows: no .png or .jpg images in %s" % left_dir)
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-4)
    lk = dict(winSize=(15, 15), maxLevel=3, criteria=criteria)
    u, v, dv = [], [], []
    for name in names:
        left = cv2.imread(os.path.join(left_dir, name), cv2.IMREAD_GRAYSCALE)
        right = cv2.imread(os.path.join(right_dir, name), cv2.IMREAD_GRAYSCALE)
        if left is None or right is None:
            sys.exit("stereo_rows: cannot read %s in both image folders" % name)
        if left.shape != right.shape:
            sys.exit("stereo_rows: %s: left %dx%d, right %dx%d; a rectified pair has one size"
                     % (name, left.shape[1], left.shape[0], right.shape[1], right.shape[0]))
        height, width = left.shape
        p = cv2.goodFeaturesToTrack(left, args.max_points, 0.01, 7)
        if p is None:
            continue
        q, ok_lr, _ = cv2.calcOpticalFlowPyrLK(left, right, p, None, **lk)
        back, ok_rl, _ = cv2.calcOpticalFlowPyrLK(right, left, q, None, **lk)
        ok = (ok_lr[:, 0] == 1) & (ok_rl[:, 0] == 1)
        ok &= np.linalg.norm((back - p)[:, 0], axis=1) < 0.1
        u += list(p[ok, 0, 0])
        v += list(p[ok, 0, 1])
        dv += list((q - p)[ok, 0, 1])
    if len(dv) < 10:
        sys.exit("stereo_rows: fewer than 10 points tracked between the cameras in %d frames"
                 % len(names))
    u, v, dv = np.array(u), np.array(v), np.array(dv)
    print("%d points over %d frames: v_right - v_left median %+.3f px" % (len(dv), len(names),
                                                                         np.median(dv)))
    for label, coord, size in (("columns", u, width), ("rows", v, height)):
        parts = []
        for k, part in enumerate(("left", "middle", "right") if label == "columns"
                                 else ("top", "middle", "bottom")):
            m = (coord >= k * size / 3) & (coord < (k + 1) * size / 3)
            parts.append("%s %+.3f (%d)" % (part, np.median(dv[m]), m.sum()) if m.any()
                         else "%s -" % part)
        print("  by %s: %s" % (label, ", ".join(parts)))
    x, y = (u - cx) / fx, (v - cy) / fx
    design = np.c_[np.ones_like(x), x, y]
    (a, b, c), *_ = np.linalg.lstsq(design, dv, rcond=None)
    residual = dv - design @ np.array([a, b, c])
    print("  fit dv = %+.3f %+.3f x %+.3f y px (x, y normalised; residual MAD %.3f px)"
          % (a, b, c, np.median(np.abs(residual - np.median(residual)))))


if __name__ == "__main__":
    main()
