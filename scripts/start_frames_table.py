#!/usr/bin/env python3
"""Runs of several clips from several start frames, per clip: the table of docs/results.md.

    python3 scripts/start_frames_table.py MODE:FILE [MODE:FILE ...] \\
        [--clips DIR] [--write docs/results.md --marker k00-turns]

FILE has one line per run, "CLIP START ATE WITH_POSE FRAMES MS": the clip's folder name, the
run's --first_frame, its ATE RMSE in metres ("nan": no evaluation), the frames with a pose, the
frames run and the median time per frame in ms. Per clip and mode: the runs, the median and
worst ATE (with --clips, the folder holding the clips: also the worst ATE as % of the run's path,
from the clip's poses.txt over the frames it ran), the runs that gave every frame a pose, the
median time per frame. With --write, the table replaces the text
between `<!-- MARKER:begin -->` and `<!-- MARKER:end -->` of that file. Standard library only.
"""
import argparse
import math
import statistics

from markdown_block import print_or_write


def load(path):
    runs = {}
    with open(path) as f:
        for line in f:
            fields = line.split()
            if not fields:
                continue
            clip, start = fields[0], int(fields[1])
            ate = float(fields[2])
            with_pose, frames, ms = (int(fields[3]), int(fields[4]), float(fields[5])) \
                if len(fields) >= 6 else (0, 1, float("nan"))
            runs.setdefault(clip, []).append((start, ate, with_pose, frames, ms))
    return runs


def path_lengths(poses_txt):
    """Cumulative path length at each pose of a KITTI poses.txt (metres)."""
    cumulative, last = [0.0], None
    with open(poses_txt) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            if len(v) != 12:
                continue
            p = (v[3], v[7], v[11])
            if last is not None:
                cumulative.append(cumulative[-1] + math.dist(p, last))
            last = p
    return cumulative


def row(mode, clip, runs, cumulative):
    ates = [r[1] for r in runs if not math.isnan(r[1])]
    worst = max(ates) if ates else float("nan")
    percent = ""
    if cumulative and ates:
        # Start frame s, n frames: the path from pose s to pose s + n - 1.
        worst_percent = max(100 * r[1] / (cumulative[min(r[0] + r[3], len(cumulative)) - 1] -
                                          cumulative[r[0]]) for r in runs if not math.isnan(r[1]))
        percent = " (%.3f %%)" % worst_percent
    return "| %s | %s | %d | %.4f | %.4f%s | %d | %.0f |" % (
        mode, clip, len(runs), statistics.median(ates) if ates else float("nan"), worst, percent,
        sum(r[2] == r[3] and not math.isnan(r[1]) for r in runs),
        statistics.median(r[4] for r in runs))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("specs", nargs="+", help="MODE:FILE")
    parser.add_argument("--clips", help="folder of the clips (CLIP/poses.txt)")
    parser.add_argument("--write", help="markdown file whose block MARKER is replaced")
    parser.add_argument("--marker", default="start-frames")
    args = parser.parse_args()
    lines = ["| mode | clip | runs | median ATE (m) | worst ATE (m, % of path) | runs with every frame "
             "posed | median ms per frame |", "|---|---|---:|---:|---:|---:|---:|"]
    for spec in args.specs:
        mode, path = spec.split(":", 1)
        runs = load(path)
        for clip in sorted(runs, key=lambda c: (len(c), c)):
            cumulative = path_lengths("%s/%s/poses.txt" % (args.clips, clip)) if args.clips else []
            lines.append(row(mode, clip, sorted(runs[clip]), cumulative))
    print_or_write("\n".join(lines) + "\n", args.write, args.marker)


if __name__ == "__main__":
    main()
