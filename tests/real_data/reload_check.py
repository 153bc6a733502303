#!/usr/bin/python3
"""Save and reload on real data (issue 47): run 1 maps a sequence and saves the map; run 2 plays
the sequence backward in that map. Fails unless run 2 relocalizes within its first 10 frames,
its trajectory, moved into the ground truth's frame by run 1's ATE alignment (no alignment of
its own), has an ATE of at most 2 cm, and it adds at most 10 % new keyframes.

  reload_check.py CASE --dynamap BIN [--work DIR] [--frames FIRST,LAST ...] [--run2 CASE2|DIR]
                  [--set KEY=VALUE ...]

--frames: run 1 plays frames FIRST..LAST of the case, run 2 LAST..FIRST (both made by
../shared/tools/make_long.py); repeat it to check several spans, one line each. Default: the
whole sequence. --run2: run 2 plays CASE2, another day in the same place: the same camera
frames with other people (teddy, teddy_dyn_dev and teddy_dyn_crowd_dev share theirs), or the
sequence in DIR (e.g. one that ../shared/tools/dyndata made from teddy with other people). --set:
passed to both runs (`dynamap run --set`). Exit status 1 if any span fails.
"""
import argparse, json, os, shutil, subprocess, sys

import bands
from bands import SHARED, SOURCE

# name (a case of bands.py, as it is): its last frame (run 2 plays the sequence from there)
CASES = {"teddy": 199, "bonn_crowd_slice": 99, "teddy_dyn_dev": 199, "teddy_dyn_crowd_dev": 199}
MAX_RELOCALIZED_FRAME = 10
MAX_ATE_CM = 2.0
MAX_NEW_KEYFRAME_SHARE = 0.10


def run(cmd):
    done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if done.returncode != 0:
        sys.exit("reload_check: %s failed (%d):\n%s" % (" ".join(cmd), done.returncode, done.stdout))
    return done.stdout


def counts(out):
    with open(os.path.join(out, "run.json")) as f:
        return json.load(f)["counts"]


def first_posed_frame(out, seq):
    """The index in seq of run 2's first posed frame: frames before the first relocalization
    have no pose and are left out of frames.txt."""
    with open(os.path.join(out, "frames.txt")) as f:
        posed = [line.split()[0] for line in f if line.strip() and line[0] != "#"
                 and line.split()[1] in ("tracked", "relocalized")]
    return frame_stamps(seq).index(posed[0]) if posed else None


def played(seq, first, last, out):
    """The frames first..last of seq, played by make_long.py into out."""
    run(["/usr/bin/python3", os.path.join(SHARED, "tools", "make_long.py"), seq, out,
         "%d,%d" % (first, last)])
    return out


def sequence_of(case):
    """The sequence of a case of bands.py, or the folder `case` names."""
    seq = case if case not in bands.CASES else os.path.join(SHARED, "data", bands.CASES[case][0])
    if not os.path.isdir(seq):
        sys.exit("reload_check: %s not found (../shared must lie beside the checkout)" % seq)
    return seq


def frame_stamps(seq):
    with open(os.path.join(seq, "rgb.txt")) as f:
        return [line.split()[0] for line in f if line.strip() and line[0] != "#"]


def check_span(dynamap, case, first, last, work, sets, run2_case):
    """Runs 1 and 2 over one span; returns (passed, the line to print)."""
    config = bands.CASES[case][2]
    case_last = CASES[case]
    extra = ["--config", os.path.join(SOURCE, config)] if config else []
    for kv in sets:
        extra += ["--set", kv]
    seq = sequence_of(case)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    saved, align = os.path.join(work, "map"), os.path.join(work, "alignment.txt")
    run1, run2 = os.path.join(work, "run1"), os.path.join(work, "run2")
    forward = seq if (first, last) == (0, case_last) else played(
        seq, first, last, os.path.join(work, "forward"))
    back = played(sequence_of(run2_case), last, first, os.path.join(work, "backward"))
    run([dynamap, "run", "--sequence", forward, "--out", run1, "--quiet", "--save-map", saved]
        + extra)
    run([dynamap, "evaluate", "--gt", os.path.join(forward, "groundtruth.txt"), "--est",
         os.path.join(run1, "trajectory.txt"), "--save-alignment", align])
    run([dynamap, "run", "--sequence", back, "--out", run2, "--quiet", "--load-map", saved]
        + extra)
    ate = json.loads(run([dynamap, "evaluate", "--gt", os.path.join(back, "groundtruth.txt"),
                          "--est", os.path.join(run2, "trajectory.txt"), "--alignment", align,
                          "--json"]))["ate"]["rmse_m"] * 100.0
    loaded, new = counts(run1)["keyframes"], counts(run2)["keyframes"]
    posed = first_posed_frame(run2, back)
    ok = (posed is not None and posed <= MAX_RELOCALIZED_FRAME and ate <= MAX_ATE_CM
          and new <= MAX_NEW_KEYFRAME_SHARE * loaded)
    name = case if run2_case == case else "%s then %s" % (case, os.path.basename(run2_case))
    line = ("%s %d-%d: run 2 first posed at frame %s (<= %d), ATE %.2f cm with run 1's "
            "alignment (<= %.1f), %d new keyframes of %d (<= %.0f %%)%s"
            % (name, first, last, posed, MAX_RELOCALIZED_FRAME, ate, MAX_ATE_CM, new, loaded,
               100 * MAX_NEW_KEYFRAME_SHARE, "" if ok else "  FAILED"))
    return ok, line


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", choices=sorted(CASES))
    ap.add_argument("--dynamap", required=True)
    ap.add_argument("--work", default="/tmp/dynamap_reload_check")
    ap.add_argument("--frames", action="append", default=[], metavar="FIRST,LAST")
    ap.add_argument("--run2", metavar="CASE2|DIR")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    a = ap.parse_args()
    run2_case = a.run2 or a.case
    if run2_case not in CASES and not os.path.isfile(os.path.join(run2_case, "rgb.txt")):
        ap.error("--run2 %s: neither a case (%s) nor a sequence folder" % (run2_case,
                                                                        ", ".join(sorted(CASES))))
    same_config = run2_case not in CASES or bands.CASES[run2_case][2] == bands.CASES[a.case][2]
    if not same_config or frame_stamps(sequence_of(run2_case)) != frame_stamps(sequence_of(a.case)):
        ap.error("--run2 %s: not the same camera frames and config as %s" % (run2_case, a.case))
    last = CASES[a.case]
    try:
        spans = [tuple(int(v) for v in f.split(",")) for f in a.frames] or [(0, last)]
    except ValueError:
        ap.error("--frames takes FIRST,LAST (frame numbers): %s" % a.frames)
    for span in spans:
        if len(span) != 2 or not 0 <= span[0] < span[1] <= last:
            ap.error("--frames %s: need FIRST,LAST with 0 <= FIRST < LAST <= %d" % (span, last))
    failed = 0
    for first, last in spans:
        work = os.path.join(a.work, "%s_%s_%d_%d" % (a.case, os.path.basename(run2_case.rstrip("/")),
                                                     first, last))
        ok, line = check_span(a.dynamap, a.case, first, last, work, a.set, run2_case)
        print(line, flush=True)
        failed += not ok
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
