#!/usr/bin/python3
"""Save and reload on real data (issue 47): run 1 maps a sequence and saves the map; run 2 plays
the sequence backward in that map. Fails unless run 2 relocalizes within its first 10 frames,
its trajectory, moved into the ground truth's frame by run 1's ATE alignment (no alignment of
its own), has an ATE of at most 2 cm, and it adds at most 10 % new keyframes.

  reload_check.py CASE --dynamap BIN [--work DIR]      CASE: teddy, bonn_crowd_slice
"""
import argparse, json, os, shutil, subprocess, sys

from bands import SHARED, SOURCE

# name: sequence under ../shared/data, its last frame (run 2 plays it from there to 0), config
CASES = {
    "teddy": ("tum/rgbd_dataset_freiburg3_teddy", 199, None),
    "bonn_crowd_slice": ("bonn/rgbd_bonn_crowd_400_499", 99, "config/bonn.yaml"),
}
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


def first_posed_frame(out):
    with open(os.path.join(out, "frames.txt")) as f:
        states = [line.split()[1] for line in f if line.strip() and line[0] != "#"]
    return next((i for i, s in enumerate(states) if s in ("tracked", "relocalized")), None)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", choices=sorted(CASES))
    ap.add_argument("--dynamap", required=True)
    ap.add_argument("--work", default="/tmp/dynamap_reload_check")
    a = ap.parse_args()
    source, last, config = CASES[a.case]
    extra = ["--config", os.path.join(SOURCE, config)] if config else []
    seq = os.path.join(SHARED, "data", source)
    if not os.path.isdir(seq):
        sys.exit("reload_check: %s not found (../shared must lie beside the checkout)" % seq)
    work = os.path.join(a.work, a.case)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    back, saved, align = (os.path.join(work, n) for n in ("backward", "map", "alignment.txt"))
    run1, run2 = os.path.join(work, "run1"), os.path.join(work, "run2")
    run([a.dynamap, "run", "--sequence", seq, "--out", run1, "--quiet", "--save-map", saved]
        + extra)
    run([a.dynamap, "evaluate", "--gt", os.path.join(seq, "groundtruth.txt"), "--est",
         os.path.join(run1, "trajectory.txt"), "--save-alignment", align])
    run(["/usr/bin/python3", os.path.join(SHARED, "tools", "make_long.py"), seq, back,
         "%d,0" % last])
    run([a.dynamap, "run", "--sequence", back, "--out", run2, "--quiet", "--load-map", saved]
        + extra)
    ate = json.loads(run([a.dynamap, "evaluate", "--gt", os.path.join(back, "groundtruth.txt"),
                          "--est", os.path.join(run2, "trajectory.txt"), "--alignment", align,
                          "--json"]))["ate"]["rmse_m"] * 100.0
    loaded, new = counts(run1)["keyframes"], counts(run2)["keyframes"]
    first = first_posed_frame(run2)
    print("%s: run 2 first posed at frame %s (<= %d), ATE %.2f cm with run 1's alignment "
          "(<= %.1f), %d new keyframes of %d (<= %.0f %%)"
          % (a.case, first, MAX_RELOCALIZED_FRAME, ate, MAX_ATE_CM, new, loaded,
             100 * MAX_NEW_KEYFRAME_SHARE))
    ok = (first is not None and first <= MAX_RELOCALIZED_FRAME and ate <= MAX_ATE_CM
          and new <= MAX_NEW_KEYFRAME_SHARE * loaded)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
