#!/usr/bin/env python3
"""Independent reference values for dala's RPE and KITTI segment errors.

What it computes
----------------
On evo's test data in ../shared/data/eval-reference (see ../shared/data/README.md), with numpy
only and written from the published definitions, not from dala's C++:

* RPE as evo_rpe with its defaults (evo/core/metrics.py RPE, evo/core/filters.py): consecutive
  pairs (all_pairs = False), chosen on the (aligned) estimate:
    - delta in frames: ids 0, d, 2d, ...; pairs (0, d), (d, 2d), ...
    - delta in metres (filter_pairs_by_path): walking along the estimate from pose 0, a pose
      becomes an id when the path travelled since the previous id (or since pose 0) is >= delta;
      pairs are consecutive ids.
  For a pair (i, j), with ground truth P and estimate Q (4x4, world <- camera):
      E = (P_i^-1 P_j)^-1 (Q_i^-1 Q_j)
  translation error |t(E)| in metres, rotation error angle(R(E)) in degrees, and numpy's rmse,
  mean, median, std (ddof 0), min, max over the pairs. The angle is taken as
  atan2(|vee(R - R^T)| / 2, (tr R - 1) / 2), which is accurate for small angles (unlike acos).
  The estimate is the *aligned* one (dala's documented choice, evo_rpe -a / -as): an SE(3)
  alignment cannot change E (checked below: the unaligned estimate gives the same numbers to
  ~1e-12), a Sim(3) scale does (Umeyama 1991, implemented here with numpy's SVD).

* KITTI odometry devkit segment errors (evaluate_odometry.cpp, calcSequenceErrors), on the
  associated pairs and the raw, unaligned estimate (as the devkit):
    - dist[k]: ground truth path length from pose 0 to pose k;
    - first frames 0, 10, 20, ... (step_size 10), lengths 100, 200, ..., 800 m;
    - lastFrameFromSegmentLength: the first i >= first with dist[i] > dist[first] + len, else
      no segment;
    - E = (Q_f^-1 Q_l)^-1 (P_f^-1 P_l), t_err = |t(E)| / len,
      r_err = acos(clamp(0.5 (tr R(E) - 1), -1, 1)) / len (the devkit's rotationError);
    - scores: plain averages over all segments (all lengths together), reported as
      t_err in % (x 100) and r_err in deg per 100 m (x 100 x 180 / pi).
  The devkit keeps distances and errors in float; like dala (docs/evaluation.md: "distances are
  accumulated in double") this uses double throughout. The script also prints, as diagnostics,
  the scores with float32 distances and with the devkit's float arithmetic emulated, to show how
  far the compiled devkit is from the double definition on these files.

Input conventions (the choices that matter at 1e-6):
* KITTI rows are 3x4 [R|t]; the files keep ~7 significant digits, so R^T R - I is ~1e-7 (gt)
  to ~8e-7 (ORB). Each R is replaced by the nearest rotation (polar factor through the SVD), as
  dala's reader documents (core/io/trajectory_io.h). This is the choice that agrees with the raw
  matrices: RPE on the raw products (angle by atan2 as below) differs from it by ~1e-8 relative
  on the rotation median, while a quaternion round trip of each R (dala's reader before this
  check) differs by 1.4e-5. Only the devkit's acos on raw, non-orthonormal products is sensitive
  (r_err ~3e-5 relative); the script prints those raw-matrix scores for comparison.
* TUM rows are "t x y z qx qy qz qw"; the quaternion is normalized (as evo and dala do).
* TUM association: as the TUM RGB-D tools' associate.py (dala's documented rule): all pairs with
  |t_gt - t_est| <= max_diff are candidates, accepted greedily by increasing |dt|, each pose used
  once; stamps are compared as integer nanoseconds parsed from the decimal text. Pairs are then
  ordered by estimate time.

How to rerun
------------
    /usr/bin/python3 tests/core/eval/reference_values.py [DATA_DIR]

DATA_DIR defaults to ../shared/data/eval-reference relative to the project root. It prints every
value that tests/core/eval/reference_test.cc pins (EvalReference.*Rpe*, *KittiSegments*), with 12
significant digits.
"""

import math
import os
import sys

import numpy as np


# ----------------------------------------------------------------------------------------------
# Reading


def nearest_rotation(m):
    """The rotation closest to m in the Frobenius norm (polar decomposition)."""
    u, _, vt = np.linalg.svd(m)
    d = np.sign(np.linalg.det(u @ vt))
    return u @ np.diag([1.0, 1.0, d]) @ vt


def read_kitti(path, orthonormalize=True):
    poses = []
    with open(path) as f:
        for line in f:
            v = line.split()
            if not v:
                continue
            assert len(v) == 12, path
            m = np.eye(4)
            m[:3, :4] = np.array([float(x) for x in v]).reshape(3, 4)
            if orthonormalize:
                m[:3, :3] = nearest_rotation(m[:3, :3])
            poses.append(m)
    return poses


def stamp_ns(text):
    """Integer nanoseconds from a decimal seconds string, without going through a double."""
    sign = -1 if text.startswith("-") else 1
    text = text.lstrip("+-")
    whole, _, frac = text.partition(".")
    frac = (frac + "000000000")[:9]
    return sign * (int(whole or "0") * 1000000000 + int(frac))


def quat_to_rot(qx, qy, qz, qw):
    q = np.array([qw, qx, qy, qz], dtype=float)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def read_tum(path):
    stamps, poses = [], []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            v = line.split()
            assert len(v) == 8, path
            t = [float(x) for x in v[1:]]
            m = np.eye(4)
            m[:3, :3] = quat_to_rot(t[3], t[4], t[5], t[6])
            m[:3, 3] = t[0:3]
            stamps.append(stamp_ns(v[0]))
            poses.append(m)
    return stamps, poses


def associate(stamps_gt, stamps_est, max_diff_ns):
    """associate.py: greedy by increasing |dt|; returns (gt index, est index) by est time."""
    candidates = []
    for j, te in enumerate(stamps_est):
        for i, tg in enumerate(stamps_gt):
            dt = abs(tg - te)
            if dt <= max_diff_ns:
                candidates.append((dt, j, i))
    candidates.sort()
    used_gt, used_est, matches = set(), set(), []
    for _, j, i in candidates:
        if i in used_gt or j in used_est:
            continue
        used_gt.add(i)
        used_est.add(j)
        matches.append((i, j))
    matches.sort(key=lambda m: stamps_est[m[1]])
    return matches


# ----------------------------------------------------------------------------------------------
# Metrics


def rotation_angle(r):
    """Rotation angle in radians, stable near 0: atan2(sin, cos) from the skew part and trace."""
    s = 0.5 * np.linalg.norm([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    c = 0.5 * (np.trace(r) - 1.0)
    return math.atan2(s, c)


def stats(e):
    e = np.asarray(e, dtype=float)
    return {
        "rmse": float(np.sqrt(np.mean(e ** 2))),
        "mean": float(np.mean(e)),
        "median": float(np.median(e)),
        "std": float(np.std(e)),
        "min": float(np.min(e)),
        "max": float(np.max(e)),
    }


def umeyama(x, y, with_scale):
    """(s, R, t) minimising sum |y_i - (s R x_i + t)|^2 (Umeyama 1991); x, y are n x 3."""
    mx, my = x.mean(axis=0), y.mean(axis=0)
    xc, yc = x - mx, y - my
    n = x.shape[0]
    cov = yc.T @ xc / n
    u, d, vt = np.linalg.svd(cov)
    s_mat = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        s_mat[2, 2] = -1.0
    r = u @ s_mat @ vt
    scale = np.trace(np.diag(d) @ s_mat) / (np.sum(xc ** 2) / n) if with_scale else 1.0
    t = my - scale * r @ mx
    return scale, r, t


def align(gt, est, with_scale):
    x = np.array([q[:3, 3] for q in est])
    y = np.array([p[:3, 3] for p in gt])
    s, r, t = umeyama(x, y, with_scale)
    out = []
    for q in est:
        m = np.eye(4)
        m[:3, :3] = r @ q[:3, :3]
        m[:3, 3] = s * r @ q[:3, 3] + t
        out.append(m)
    ate = np.linalg.norm(np.array([p[:3, 3] - q[:3, 3] for p, q in zip(gt, out)]), axis=1)
    return out, s, stats(ate)


def rpe_pairs(est, delta, unit):
    if unit == "frames":
        ids = list(range(0, len(est), int(delta)))
    else:  # evo filter_pairs_by_path, all_pairs = False
        ids, travelled = [], 0.0
        for i in range(len(est)):
            if i > 0:
                travelled += float(np.linalg.norm(est[i][:3, 3] - est[i - 1][:3, 3]))
            if travelled >= delta:
                ids.append(i)
                travelled = 0.0
    return list(zip(ids[:-1], ids[1:]))


def rpe(gt, est, delta, unit):
    inv = np.linalg.inv
    t_err, r_err = [], []
    pairs = rpe_pairs(est, delta, unit)
    for i, j in pairs:
        e = inv(inv(gt[i]) @ gt[j]) @ (inv(est[i]) @ est[j])
        t_err.append(float(np.linalg.norm(e[:3, 3])))
        r_err.append(math.degrees(rotation_angle(e[:3, :3])))
    return len(pairs), stats(t_err), stats(r_err)


KITTI_LENGTHS = [100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0]


def trajectory_distances(gt, dtype=np.float64):
    dist = [dtype(0.0)]
    for k in range(1, len(gt)):
        d = gt[k - 1][:3, 3].astype(dtype) - gt[k][:3, 3].astype(dtype)
        dist.append(dtype(dist[-1] + dtype(np.sqrt(np.sum(d * d)))))
    return np.array(dist, dtype=dtype)


def last_frame_from_segment_length(dist, first, length):
    for i in range(first, len(dist)):
        if dist[i] > dist[first] + length:
            return i
    return -1


def kitti_segments(gt, est, dist_dtype=np.float64):
    inv = np.linalg.inv
    dist = trajectory_distances(gt, dist_dtype)
    segments = []  # (first, last, length, t_err, r_err)
    for first in range(0, len(gt), 10):
        for length in KITTI_LENGTHS:
            last = last_frame_from_segment_length(dist, first, dist_dtype(length))
            if last == -1:
                continue
            delta_gt = inv(gt[first]) @ gt[last]
            delta_est = inv(est[first]) @ est[last]
            e = inv(delta_est) @ delta_gt
            r = math.acos(max(min(0.5 * (np.trace(e[:3, :3]) - 1.0), 1.0), -1.0))
            segments.append((first, last, length, np.linalg.norm(e[:3, 3]) / length, r / length))
    return segments


def kitti_devkit_float(gt, est):
    """The devkit as compiled: raw matrices (double, libviso2's FLOAT), float distances, float d
    in rotationError, float errors and sums. Diagnostic only."""
    f32 = np.float32
    inv = np.linalg.inv
    dist = trajectory_distances(gt, f32)
    t_sum, r_sum, count = f32(0.0), f32(0.0), 0
    for first in range(0, len(gt), 10):
        for length in KITTI_LENGTHS:
            last = last_frame_from_segment_length(dist, first, f32(length))
            if last == -1:
                continue
            e = inv(inv(est[first]) @ est[last]) @ (inv(gt[first]) @ gt[last])
            d = f32(0.5) * (f32(e[0, 0]) + f32(e[1, 1]) + f32(e[2, 2]) - f32(1.0))
            r = f32(math.acos(max(min(float(d), 1.0), -1.0)))
            t = np.sqrt(np.sum(e[:3, 3].astype(f32) ** 2, dtype=f32), dtype=f32)
            t_sum = f32(t_sum + f32(t / f32(length)))
            r_sum = f32(r_sum + f32(r / f32(length)))
            count += 1
    return count, 100.0 * float(t_sum / f32(count)), \
        100.0 * 180.0 / math.pi * float(r_sum / f32(count))


def kitti_scores(segments):
    to_deg_100m = 100.0 * 180.0 / math.pi
    t = 100.0 * float(np.mean([s[3] for s in segments]))
    r = to_deg_100m * float(np.mean([s[4] for s in segments]))
    per_length = []
    for length in KITTI_LENGTHS:
        sel = [s for s in segments if s[2] == length]
        if sel:
            per_length.append((length, len(sel), 100.0 * float(np.mean([s[3] for s in sel])),
                               to_deg_100m * float(np.mean([s[4] for s in sel]))))
    return len(segments), t, r, per_length


# ----------------------------------------------------------------------------------------------
# Output


def fmt(x):
    return "%.12g" % x


def print_rpe(title, result):
    n, t, r = result
    print("  %s: %d pairs" % (title, n))
    print("    trans rmse %s mean %s median %s std %s max %s" %
          (fmt(t["rmse"]), fmt(t["mean"]), fmt(t["median"]), fmt(t["std"]), fmt(t["max"])))
    print("    rot_deg rmse %s mean %s median %s std %s max %s" %
          (fmt(r["rmse"]), fmt(r["mean"]), fmt(r["median"]), fmt(r["std"]), fmt(r["max"])))


def max_rel_diff(a, b):
    (_, ta, ra), (_, tb, rb) = a, b
    return max(abs(x[k] - y[k]) / abs(y[k]) for x, y in ((ta, tb), (ra, rb)) for k in x if y[k])


def kitti_sequence(data, name):
    gt = read_kitti(os.path.join(data, "KITTI_00_gt.txt"))
    est = read_kitti(os.path.join(data, name))
    assert len(gt) == len(est) == 4541
    print("KITTI_00_gt vs %s (%d poses, by index)" % (name, len(gt)))
    for mode in ("se3", "sim3"):
        aligned, s, ate = align(gt, est, mode == "sim3")
        print("  %s alignment: scale %s, ATE rmse %s mean %s" %
              (mode, fmt(s), fmt(ate["rmse"]), fmt(ate["mean"])))
        frames = rpe(gt, aligned, 1, "frames")
        print_rpe("RPE %s, delta 1 frame" % mode, frames)
        metres = rpe(gt, aligned, 100.0, "metres")
        print_rpe("RPE %s, delta 100 m" % mode, metres)
        if mode == "se3":
            print("    (unaligned estimate, max relative difference: 1 frame %.1e, 100 m %.1e)" %
                  (max_rel_diff(rpe(gt, est, 1, "frames"), frames),
                   max_rel_diff(rpe(gt, est, 100.0, "metres"), metres)))
    segments = kitti_segments(gt, est)
    n, t, r, per_length = kitti_scores(segments)
    print("  KITTI segments (raw estimate): %d segments, t_err %s %%, r_err %s deg/100m" %
          (n, fmt(t), fmt(r)))
    for length, count, tl, rl in per_length:
        print("    %4d m: %4d segments, t_err %s %%, r_err %s deg/100m" %
              (length, count, fmt(tl), fmt(rl)))
    # Diagnostics: the devkit's float distances, and the raw (not orthonormalized) matrices.
    seg32 = kitti_segments(gt, est, np.float32)
    moved = sum(a[:3] != b[:3] for a, b in zip(seg32, segments)) + abs(len(seg32) - len(segments))
    n32, t32, r32, _ = kitti_scores(seg32)
    print("    float32 distances (the devkit's): %d segments, %d of them end elsewhere; "
          "t_err %s %%, r_err %s deg/100m" % (n32, moved, fmt(t32), fmt(r32)))
    gt_raw = read_kitti(os.path.join(data, "KITTI_00_gt.txt"), False)
    est_raw = read_kitti(os.path.join(data, name), False)
    nf, tf, rf = kitti_devkit_float(gt_raw, est_raw)
    print("    devkit float arithmetic emulated: %d segments, t_err %s %%, r_err %s deg/100m "
          "(relative to double: %.1e, %.1e)" % (nf, fmt(tf), fmt(rf), tf / t - 1, rf / r - 1))
    raw = kitti_scores(kitti_segments(gt_raw, est_raw))
    print("    raw (non-orthonormalized) matrices: t_err %s %%, r_err %s deg/100m" %
          (fmt(raw[1]), fmt(raw[2])))


def tum_sequence(data):
    stamps_gt, gt_all = read_tum(os.path.join(data, "freiburg1_xyz-groundtruth.txt"))
    stamps_est, est_all = read_tum(os.path.join(data, "freiburg1_xyz-rgbdslam.txt"))
    matches = associate(stamps_gt, stamps_est, 20000000)  # max_diff 0.02 s
    gt = [gt_all[i] for i, _ in matches]
    est = [est_all[j] for _, j in matches]
    print("freiburg1_xyz groundtruth vs rgbdslam (TUM, max_diff 0.02 s): %d pairs" % len(gt))
    aligned, s, ate = align(gt, est, False)
    print("  se3 alignment: ATE rmse %s" % fmt(ate["rmse"]))
    frames = rpe(gt, aligned, 1, "frames")
    print_rpe("RPE se3, delta 1 frame", frames)
    print("    (unaligned estimate, max relative difference %.1e)" %
          max_rel_diff(rpe(gt, est, 1, "frames"), frames))
    dist = trajectory_distances(gt)
    print("  gt path length %s m (no 100 m KITTI segment)" % fmt(dist[-1]))


def main():
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__)))))
    data = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        root, "..", "shared", "data", "eval-reference")
    kitti_sequence(data, "KITTI_00_ORB.txt")
    kitti_sequence(data, "KITTI_00_SPTAM.txt")
    tum_sequence(data)


if __name__ == "__main__":
    main()
