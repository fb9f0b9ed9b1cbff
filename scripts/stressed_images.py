#!/usr/bin/env python3
"""A KITTI folder whose images are changed the ways a real drive changes them, with the same
ground truth: exposure, tone curve, sensor noise, motion blur, dropped frames and a stop
(docs/results.md, "stop 59").

    python3 scripts/stressed_images.py SRC DST --kind KIND [--seed S]

KIND (every image of SRC, left and right alike unless said):
  gain          each frame's exposure changed by a factor exp(N(0, 0.3^2)), one per frame (both
                cameras alike: a rig with one exposure control)
  gain_per_camera   the same, a factor per camera and frame (cameras that expose on their own)
  gamma         the tone curve of a camera that encodes for display: 255 (I / 255)^2.2
  dim           an underexposed drive: I * 0.35 (fewer grey levels, the same contrast ratios)
  dark          both: 0.5 * 255 (I / 255)^2.2
  noise         sensor noise, N(0, 6^2) grey levels added per pixel
  blur          horizontal motion blur of 1-9 px, drawn per frame
  drop          4 frames of the middle left out (a recorder that dropped them: the times keep
                their gap)
  stop          the car stands still for 15 frames at frame 25 (that frame repeated; every image
                of the folder gets fresh N(0, 2^2) sensor noise, so the copies differ; the
                times renumbered at 10 Hz)
Pixels are clipped to [0, 255]. DST holds image_0/ (and image_1/ when SRC has it), calib.txt,
poses.txt and times.txt; it is written as DST.partial and renamed when complete. Deterministic
for a seed. Needs numpy and OpenCV's Python module (Debian: python3-numpy python3-opencv).
tests/e2e_real/kitti_exposure_e2e_test.cc makes a gain_per_camera + stop folder in C++.
"""
import argparse
import os
import shutil
import sys

try:
    import cv2
    import numpy as np
except ImportError as e:
    sys.exit(f"stressed_images.py needs numpy and OpenCV's Python module ({e}); "
             "on Debian: apt-get install python3-numpy python3-opencv")

KINDS = ("gain", "gain_per_camera", "gamma", "dim", "dark", "noise", "blur", "drop", "stop")
STOP_AT, STOP_FRAMES = 25, 15


def frame_order(kind, n, rng):
    """Which source frame each output frame shows."""
    if kind == "drop":
        gone = set(rng.choice(np.arange(3, n - 3), size=4, replace=False).tolist())
        return [i for i in range(n) if i not in gone]
    if kind == "stop":
        if n <= STOP_AT:
            sys.exit(f"--kind stop needs more than {STOP_AT} frames, not {n}")
        return list(range(STOP_AT)) + [STOP_AT] * STOP_FRAMES + list(range(STOP_AT, n))
    return list(range(n))


def write(a, tmp, cams, names, poses, times, order, rng):
    """Writes the stressed folder into tmp."""
    for cam in cams:
        os.makedirs(os.path.join(tmp, cam))
    shutil.copy(os.path.join(a.src, "calib.txt"), os.path.join(tmp, "calib.txt"))
    for j, i in enumerate(order):
        gain = float(np.exp(rng.normal(0.0, 0.3)))
        blur = int(rng.integers(1, 10))
        for cam in cams:
            path = os.path.join(a.src, cam, names[i])
            image = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
            if image is None:
                raise SystemExit(f"cannot read {path}")
            im = image.astype(np.float32)
            if a.kind == "gain":
                im *= gain
            elif a.kind == "gain_per_camera":
                im *= gain if cam == "image_0" else float(np.exp(rng.normal(0.0, 0.3)))
            elif a.kind == "gamma":
                im = 255.0 * (im / 255.0) ** 2.2
            elif a.kind == "dim":
                im *= 0.35
            elif a.kind == "dark":
                im = 0.5 * 255.0 * (im / 255.0) ** 2.2
            elif a.kind == "noise":
                im += rng.normal(0.0, 6.0, im.shape)
            elif a.kind == "blur" and blur > 1:
                kernel = np.zeros((blur, blur), np.float32)
                kernel[blur // 2, :] = 1.0 / blur
                im = cv2.filter2D(im, -1, kernel)
            elif a.kind == "stop":
                im += rng.normal(0.0, 2.0, im.shape)
            out = np.clip(im + 0.5, 0, 255).astype(np.uint8)
            if not cv2.imwrite(os.path.join(tmp, cam, f"{j:06d}.png"), out):
                raise SystemExit(f"cannot write {tmp}/{cam}/{j:06d}.png")
    with open(os.path.join(tmp, "poses.txt"), "w") as f:
        f.write("".join(poses[i] + "\n" for i in order))
    with open(os.path.join(tmp, "times.txt"), "w") as f:
        if a.kind == "stop":
            f.write("".join(f"{0.1 * j:e}\n" for j in range(len(order))))
        else:
            f.write("".join(times[i] + "\n" for i in order))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("src", help="a KITTI sequence folder (image_0/, [image_1/,] calib.txt, "
                    "poses.txt, times.txt)")
    ap.add_argument("dst", help="the folder to write (must not exist)")
    ap.add_argument("--kind", required=True, choices=KINDS)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    a.dst = os.path.normpath(a.dst)  # "DST/" would put DST.partial inside DST.
    if os.path.exists(a.dst):
        sys.exit(f"{a.dst} exists: give a new folder")
    cams = [c for c in ("image_0", "image_1") if os.path.isdir(os.path.join(a.src, c))]
    if "image_0" not in cams:
        sys.exit(f"{a.src} has no image_0/: give a KITTI sequence folder")
    for name in ("calib.txt", "poses.txt", "times.txt"):
        if not os.path.isfile(os.path.join(a.src, name)):
            sys.exit(f"{a.src} has no {name}: give a KITTI sequence folder with ground truth")
    names = sorted(n for n in os.listdir(os.path.join(a.src, "image_0")) if n.endswith(".png"))
    with open(os.path.join(a.src, "poses.txt")) as f:
        poses = [line.strip() for line in f if line.strip()]
    with open(os.path.join(a.src, "times.txt")) as f:
        times = [line.strip() for line in f if line.strip()]
    if not (len(names) == len(poses) == len(times)):
        sys.exit(f"{a.src}: {len(names)} images, {len(poses)} poses, {len(times)} times")
    if a.kind == "drop" and len(names) < 10:
        sys.exit(f"--kind drop needs 10 frames or more, not {len(names)}")
    rng = np.random.default_rng(a.seed)
    order = frame_order(a.kind, len(names), rng)

    tmp = a.dst + ".partial"
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        write(a, tmp, cams, names, poses, times, order, rng)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)  # No half-written folder is left behind.
        raise
    os.rename(tmp, a.dst)
    print(f"{a.dst}: {len(order)} frames of {a.src}, {a.kind} (seed {a.seed})")


if __name__ == "__main__":
    main()
