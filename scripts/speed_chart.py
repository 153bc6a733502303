#!/usr/bin/env python3
"""Where the wall time of runs goes: the frames, then finish(), as stacked bars, one per run.

usage: speed_chart.py OUT.png LABEL=RUN_DIR [LABEL=RUN_DIR ...] [--frames-per-s 30]

Reads RUN_DIR/timings.json (wall_time_s, finish_s, frames) of `dynamap run` folders and marks the
wall time at which the run would have kept the given frame rate end to end. Needs only OpenCV
and NumPy (Debian's python3-opencv).
"""
import json
import sys

import cv2
import numpy as np


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    rate = 30.0
    if "--frames-per-s" in argv:
        i = argv.index("--frames-per-s")
        rate = float(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    out, specs = argv[1], argv[2:]
    rows = []
    for spec in specs:
        label, _, run = spec.partition("=")
        try:
            t = json.load(open(run + "/timings.json"))
        except (OSError, ValueError) as e:
            sys.exit("speed_chart.py: %s/timings.json: %s" % (run, e))
        rows.append((label, t["wall_time_s"] - t["finish_s"], t["finish_s"], t["frames"]))
    w, left, right, bar, gap, top = 1000, 260, 40, 34, 18, 50
    h = top + len(rows) * (bar + gap) + 60
    img = np.full((h, w, 3), 255, np.uint8)
    t_max = max(r[1] + r[2] for r in rows) * 1.3
    x = lambda s: int(left + (w - left - right) * s / t_max)
    font = cv2.FONT_HERSHEY_SIMPLEX
    for k, (label, loop_s, finish_s, frames) in enumerate(rows):
        y = top + k * (bar + gap)
        cv2.rectangle(img, (x(0), y), (x(loop_s), y + bar), (200, 140, 60), -1)
        cv2.rectangle(img, (x(loop_s), y), (x(loop_s + finish_s), y + bar), (60, 120, 230), -1)
        cv2.putText(img, label, (10, y + 23), font, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
        text = "%.2f s = %.1f frames/s" % (loop_s + finish_s, frames / (loop_s + finish_s))
        cv2.putText(img, text, (x(loop_s + finish_s) + 6, y + 23), font, 0.42, (0, 0, 0), 1,
                    cv2.LINE_AA)
    frames = rows[0][3]
    limit = frames / rate
    cv2.line(img, (x(limit), top - 10), (x(limit), h - 45), (0, 0, 200), 1)
    cv2.putText(img, "%g frames/s for %d frames" % (rate, frames), (x(limit) - 90, top - 16),
                font, 0.42, (0, 0, 200), 1, cv2.LINE_AA)
    for s in range(0, int(t_max) + 1):
        cv2.line(img, (x(s), h - 45), (x(s), h - 40), (0, 0, 0), 1)
        cv2.putText(img, "%d s" % s, (x(s) - 8, h - 25), font, 0.4, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.rectangle(img, (left, h - 18), (left + 14, h - 6), (200, 140, 60), -1)
    cv2.putText(img, "frames", (left + 20, h - 7), font, 0.4, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.rectangle(img, (left + 90, h - 18), (left + 104, h - 6), (60, 120, 230), -1)
    cv2.putText(img, "finish (visibility pass, rebuild, map files)", (left + 110, h - 7), font,
                0.4, (0, 0, 0), 1, cv2.LINE_AA)
    if not cv2.imwrite(out, img):
        sys.exit("speed_chart.py: %s: cannot write" % out)


if __name__ == "__main__":
    main(sys.argv)
