#!/usr/bin/env python3
"""A KITTI folder's left images turned about the camera centre by an added yaw, with exact
ground truth: real images through fast rotations (docs/results.md, "stop 58").

    python3 scripts/turned_images.py SRC DST --amplitude_deg A --period_frames P \\
        [--width 720 --height 300]

The yaw of frame i is theta_i = A sin(2 pi i / P). A rotation about the camera centre is a
homography: a pixel of the virtual image (focal length of SRC, principal point at the centre of a
WIDTH x HEIGHT image centred in SRC's view) comes from SRC's pixel K R_y(theta_i) K_v^-1 (u, v, 1)
(R_y about the camera's y axis, down); the camera-to-world rotation of frame i is
R_w_c R_y(theta_i), its position unchanged. DST holds image_0/, calib.txt, poses.txt, times.txt
(one camera: `dala run DST --mode mono`). The script refuses a yaw that would look past SRC's
image. Needs numpy and OpenCV's Python module (Debian: python3-numpy python3-opencv).
tests/e2e_real/kitti_yaw_e2e_test.cc makes the same folder in C++.
"""
import argparse
import os
import shutil
import sys

try:
    import cv2
    import numpy as np
except ImportError as e:
    sys.exit(f"turned_images.py needs numpy and OpenCV's Python module ({e}); "
             "on Debian: apt-get install python3-numpy python3-opencv")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("src", help="a KITTI sequence folder (image_0/, calib.txt, poses.txt, times.txt)")
    ap.add_argument("dst", help="the folder to write (must not exist)")
    ap.add_argument("--amplitude_deg", type=float, required=True)
    ap.add_argument("--period_frames", type=float, required=True)
    ap.add_argument("--width", type=int, default=720)
    ap.add_argument("--height", type=int, default=300)
    a = ap.parse_args()
    if os.path.exists(a.dst):
        sys.exit(f"{a.dst} exists: give a new folder")
    with open(os.path.join(a.src, "calib.txt")) as f:
        P0 = np.array([float(v) for v in f.readline().split()[1:13]]).reshape(3, 4)
    K = P0[:, :3]
    names = sorted(n for n in os.listdir(os.path.join(a.src, "image_0")) if n.endswith(".png"))
    G = np.loadtxt(os.path.join(a.src, "poses.txt")).reshape(-1, 3, 4)
    if len(G) != len(names):
        sys.exit(f"{len(names)} images but {len(G)} poses in {a.src}")
    first = cv2.imread(os.path.join(a.src, "image_0", names[0]), cv2.IMREAD_GRAYSCALE)
    if first is None:
        sys.exit(f"cannot read {names[0]} in {a.src}/image_0")
    h_src, w_src = first.shape
    K_v = np.array([[K[0, 0], 0, (a.width - 1) / 2.0],
                    [0, K[1, 1], K[1, 2] - (h_src - a.height) / 2.0], [0, 0, 1]])
    corners = np.array([[0, a.width - 1, 0, a.width - 1], [0, 0, a.height - 1, a.height - 1],
                        [1, 1, 1, 1.0]])
    tmp = a.dst + ".partial"
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(os.path.join(tmp, "image_0"))
    poses = []
    for i, name in enumerate(names):
        th = np.radians(a.amplitude_deg) * np.sin(2 * np.pi * i / a.period_frames)
        c, s = np.cos(th), np.sin(th)
        R_y = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        M = K @ R_y @ np.linalg.inv(K_v)  # virtual pixel -> recorded pixel
        uv = M @ corners
        uv = uv[:2] / uv[2]
        if uv.min() < 0 or uv[0].max() > w_src - 1 or uv[1].max() > h_src - 1:
            shutil.rmtree(tmp)
            sys.exit(f"frame {i}: a yaw of {np.degrees(th):.2f} deg looks past the recorded image; "
                     "give a smaller --amplitude_deg, --width or --height")
        img = cv2.imread(os.path.join(a.src, "image_0", name), cv2.IMREAD_GRAYSCALE)
        if img is None:
            shutil.rmtree(tmp)
            sys.exit(f"cannot read {name} in {a.src}/image_0")
        turned = cv2.warpPerspective(img, M, (a.width, a.height),
                                     flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)
        cv2.imwrite(os.path.join(tmp, "image_0", name), turned)
        T = G[i].copy()
        T[:, :3] = T[:, :3] @ R_y
        poses.append(T.reshape(-1))
    np.savetxt(os.path.join(tmp, "poses.txt"), np.array(poses), fmt="%.12e")
    shutil.copy(os.path.join(a.src, "times.txt"), os.path.join(tmp, "times.txt"))
    with open(os.path.join(tmp, "calib.txt"), "w") as f:
        for k in range(4):
            P = np.hstack([K_v, np.zeros((3, 1))])
            f.write(f"P{k}: " + " ".join(f"{v:.12e}" for v in P.reshape(-1)) + "\n")
    os.rename(tmp, a.dst)
    print(f"{a.dst}: {len(names)} frames, yaw {a.amplitude_deg} deg sin(2 pi i / {a.period_frames})")


if __name__ == "__main__":
    main()
