#!/usr/bin/env python3
"""Single runs side by side, from their report.json: the table of docs/results.md.

    python3 scripts/runs_table.py LABEL=DIR [LABEL=DIR ...] [--write docs/results.md --marker M]

DIR is a `dala run --out` folder. Per run: the frames with a pose of those run, the keyframes in
the map, the loops closed and detected, the places stored for place recognition (-1: a report
without them), the ATE RMSE (after the global BA where one ran), the online ATE (before it), the
scale along the path, the global BA's time, the peak memory and the median time per frame. With
--write, the table replaces the text between `<!-- MARKER:begin -->` and `<!-- MARKER:end -->` of
that file.
Standard library only.
"""
import argparse
import json
import os
import sys

from markdown_block import print_or_write


def row(label, folder):
    with open(os.path.join(folder, "report.json")) as f:
        s = json.load(f)["summary"]
    if "ate" not in s:
        sys.exit("runs_table: %s/report.json has no ATE (a run without ground truth)" % folder)
    refinement = s.get("refinement", {})
    global_ba = refinement.get("done", False)
    online = s.get("online", {}).get("ate", {}).get("rmse") if global_ba else s["ate"]["rmse"]
    scale = s.get("scale_along_path", {})
    return "| %s | %d / %d | %d | %d / %d | %d | %s | %s | %s | %s | %.0f MiB | %.1f ms |" % (
        label, s["frames_with_pose"], s["frames"], s["keyframes_in_map"], s["loops_closed"],
        s["loops_detected"], s.get("places", -1),
        "%.4f m" % s["ate"]["rmse"] if global_ba else "-",
        "%.4f m" % online if online is not None else "-",
        "%.3f-%.3f" % (scale["min"], scale["max"]) if scale.get("segments") else "-",
        "%.0f s" % refinement["time_s"] if global_ba else "off", s["peak_rss_mb"], s["ms_median"])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", metavar="LABEL=DIR",
                        help="LABEL may hold '=' (the last one splits); DIR may not")
    parser.add_argument("--write", metavar="FILE", help="rewrite the marked block of FILE")
    parser.add_argument("--marker", default="runs", help="the block's name in FILE")
    args = parser.parse_args()
    lines = ["| run | frames with a pose | keyframes in the map | loops closed / detected | "
             "places stored | "
             "ATE after the global BA | ATE online | scale along the path | global BA | "
             "peak memory | per frame |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for spec in args.runs:
        label, _, folder = spec.rpartition("=")  # Labels may hold "key=value".
        if not label or not folder:
            parser.error("expected LABEL=DIR, got %r" % spec)
        lines.append(row(label, folder))
    print_or_write("\n".join(lines) + "\n", args.write, args.marker)


if __name__ == "__main__":
    main()
