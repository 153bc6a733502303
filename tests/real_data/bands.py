#!/usr/bin/python3
"""Regression bands: every metric of a real-data run inside a band measured from its spread.

  bands.py check CASE --dynamap BIN [--work DIR] [--set KEY=VALUE ...]
                                                      run one case, compare with bands.json
  bands.py measure --dynamap BIN [BIN ...] [--cases A,B] [--metrics M,N] [--work DIR]
                                                      run every case's variants, write bands.json
                                                      (--metrics: only those metrics' bands)
  bands.py sweep --dynamap BIN [--cases A,B] [--starts A-B] [--set KEY=VALUE ...]
                                                      run each case from every start frame of
                                                      `measure`, print each run and the means
                                                      (judge a change on more than one run)
  bands.py limits                                     recompute every limit from the samples
                                                      in bands.json (after a change of the rule)
  bands.py table                                      bands.json as a Markdown table
  bands.py list                                       the cases, one a line

A case is a sequence from ../shared/data (as it is, or a variant generated from it: played
backward by ../shared/tools/make_long.py, every 2nd frame) run by `dynamap run` with the
default backend. `check` runs the case as it is (start frame 0) and fails when a metric lies
outside its band. `measure` runs each case from several start frames (0, 2, ..., the frames
before the start dropped) with each given build (e.g. with and without the fast paths) and
writes the samples and the limits to bands.json: a metric's limit on its worse side is
mean + 3 standard deviations of the samples (mean - 3 sd where higher is better), never
tighter than the worst sample. Offline runs repeat exactly on one machine, so the spread is
what small changes of the input (and of the arithmetic) do to a metric, the noise a change of
the code must stay within. Better than the band always passes.
Data missing is a failure, never a skip.
"""
import argparse, datetime, json, math, os, platform, shutil, statistics, subprocess, sys

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.normpath(os.path.join(HERE, "..", ".."))
SHARED = os.path.normpath(os.path.join(SOURCE, "..", "shared"))
BANDS_FILE = os.path.join(HERE, "bands.json")
STARTS = [0, 2, 4, 6, 8, 10]
SIGMAS = 3.0

# name: source under ../shared/data, variant, config.
CASES = {
    "teddy": ("tum/rgbd_dataset_freiburg3_teddy", None, None),
    "teddy_dyn_dev": ("dynamic/teddy_dyn_dev", None, None),
    "teddy_dyn_crowd_dev": ("dynamic/teddy_dyn_crowd_dev", None, None),
    "bonn_crowd_slice": ("bonn/rgbd_bonn_crowd_400_499", None, "config/bonn.yaml"),
    "bonn_crowd_slice_backward": ("bonn/rgbd_bonn_crowd_400_499", "backward", "config/bonn.yaml"),
    "teddy_dyn_crowd_dev_stride2": ("dynamic/teddy_dyn_crowd_dev", "stride2", None),
}

# metric: (where in the run's outputs, True if higher is better)
METRICS = {
    "ate_cm": (("metrics", "ate", "rmse_m"), False),
    "jitter_mm": (("metrics", "rpe_one_frame", "trans_rmse_m"), False),
    "lost_frames": (("frames", "lost"), False),
    "relocalized_frames": (("frames", "relocalized"), False),
    # Frames whose features gave no pose, posed by the depth fallback alone (status "depth").
    "posed_by_depth_frames": (("frames", "depth"), False),
    "mask_iou": (("metrics", "masks", "mean_iou"), True),
    "mask_recall": (("metrics", "masks", "pixel_recall"), True),
    "mask_precision": (("metrics", "masks", "pixel_precision"), True),
    "standing_masked_share": (("metrics", "masks", "standing_masked_share"), False),
    "map_precision": (("metrics", "map", "precision"), True),
    "map_completeness": (("metrics", "map", "completeness"), True),
    "map_ghost_ratio": (("metrics", "map", "ghost_ratio"), False),
}
# Metrics in other units than the outputs' metres.
UNITS = {"ate_cm": 100.0, "jitter_mm": 1000.0}


class DataMissing(Exception):
    pass


def source_dir(case):
    path = os.path.join(SHARED, "data", CASES[case][0])
    if not os.path.isfile(os.path.join(path, "rgb.txt")):
        raise DataMissing("real_data: %s not found (the shared data must lie beside the checkout "
                          "as ../shared)" % path)
    return path


def link_sequence(src, dst, start, stride):
    """dst: src's files linked, rgb.txt cut to every stride-th frame from `start` on (every
    depth frame stays listed, so each colour frame keeps the depth it is associated with)."""
    shutil.rmtree(dst, ignore_errors=True)
    os.makedirs(dst)
    for name in sorted(os.listdir(src)):
        if name != "rgb.txt":
            os.symlink(os.path.realpath(os.path.join(src, name)), os.path.join(dst, name))
    n, lines = 0, []
    for line in open(os.path.join(src, "rgb.txt")):
        if line.startswith("#") or not line.strip():
            lines.append(line)
            continue
        if n >= start and (n - start) % stride == 0:
            lines.append(line)
        n += 1
    with open(os.path.join(dst, "rgb.txt"), "w") as f:
        f.writelines(lines)


def prepare(case, start, work):
    """The case's sequence from frame `start` on, as a folder of links under `work`."""
    src = source_dir(case)
    variant = CASES[case][1]
    stride = 2 if variant == "stride2" else 1
    if variant == "backward":
        frames = sum(1 for l in open(os.path.join(src, "rgb.txt")) if l.strip() and l[0] != "#")
        played = os.path.join(work, "%s_played" % case)
        if not os.path.isfile(os.path.join(played, "rgb.txt")):
            make_long = os.path.join(SHARED, "tools", "make_long.py")
            if not os.path.isfile(make_long):
                raise DataMissing("real_data: %s not found" % make_long)
            shutil.rmtree(played, ignore_errors=True)
            subprocess.run(["/usr/bin/python3", make_long, src, played, "%d,0" % (frames - 1)],
                           check=True, stdout=subprocess.DEVNULL)
        src = played
    seq = os.path.join(work, "%s_from%d" % (case, start))
    link_sequence(src, seq, start, stride)
    return seq


def run(dynamap, case, seq, out, overrides=()):
    shutil.rmtree(out, ignore_errors=True)
    config = os.path.join(SOURCE, CASES[case][2]) if CASES[case][2] else None
    run_dynamap(dynamap, seq, out, overrides, config)
    return read_metrics(out)


def run_dynamap(dynamap, seq, out, overrides=(), config=None, extra=()):
    """`dynamap run` of `seq` into `out` (`--set` each override, `--config` if given, then
    `extra` arguments); raises RuntimeError with its output if it fails."""
    cmd = [dynamap, "run", "--sequence", seq, "--out", out, "--quiet"]
    for override in overrides:
        cmd += ["--set", override]
    if config:
        cmd += ["--config", config]
    cmd += list(extra)
    # A build's (or a frozen copy's) own libraries and plugins: <dir>/bin/dynamap, <dir>/lib.
    env = dict(os.environ)
    lib = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(dynamap))), "lib")
    env["LD_LIBRARY_PATH"] = lib + (":" + env["LD_LIBRARY_PATH"] if env.get("LD_LIBRARY_PATH") else "")
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    if proc.returncode != 0:
        raise RuntimeError("real_data: %s failed (exit %d):\n%s" % (" ".join(cmd),
                                                                    proc.returncode, proc.stdout))


def read_metrics(out):
    """Every metric of METRICS that the run's outputs hold (ATE in cm)."""
    with open(os.path.join(out, "metrics.json")) as f:
        found = {"metrics": json.load(f), "frames": {"lost": 0, "relocalized": 0, "depth": 0}}
    for line in open(os.path.join(out, "frames.txt")):
        words = line.split()
        if len(words) >= 2 and words[-1] in found["frames"]:
            found["frames"][words[-1]] += 1
    values = {}
    for metric, (path, _) in METRICS.items():
        node = found
        for key in path:
            node = node.get(key) if isinstance(node, dict) else None
        if isinstance(node, (int, float)):
            values[metric] = float(node) * UNITS.get(metric, 1.0)
    return values


# Shares and ratios: a limit beyond [0, 1] is no limit; it is kept there.
SHARES = {"mask_iou", "mask_recall", "mask_precision", "standing_masked_share", "map_precision",
          "map_completeness", "map_ghost_ratio"}


def band_of(samples, higher_is_better, share=False):
    mean = statistics.fmean(samples)
    sd = statistics.stdev(samples) if len(samples) > 1 else 0.0
    if higher_is_better:
        limit = min(mean - SIGMAS * sd, min(samples))
        return {"min": max(limit, 0.0) if share else limit}
    limit = max(mean + SIGMAS * sd, max(samples))
    return {"max": min(limit, 1.0) if share else limit}


def entry_of(metric, samples):
    return {"samples": [round(v, 6) for v in samples], "mean": statistics.fmean(samples),
            "sd": statistics.stdev(samples) if len(samples) > 1 else 0.0,
            "band": band_of(samples, METRICS[metric][1], metric in SHARES)}


def violations(values, bands):
    """(metric, value, band) for each banded metric outside its band or missing from the run."""
    bad = []
    for metric, band in bands.items():
        value = values.get(metric)
        if value is None or ("max" in band and value > band["max"]) or \
                ("min" in band and value < band["min"]):
            bad.append((metric, value, band))
    return bad


def load_bands():
    with open(BANDS_FILE) as f:
        return json.load(f)


def check(args):
    bands = load_bands()["cases"].get(args.case)
    if bands is None:
        raise SystemExit("real_data: no bands for case '%s' in %s" % (args.case, BANDS_FILE))
    os.makedirs(args.work, exist_ok=True)
    values = run(args.dynamap[0], args.case, prepare(args.case, 0, args.work),
                 os.path.join(args.work, args.case + "_run"), args.set)
    bad = violations(values, {m: b["band"] for m, b in bands.items()})
    for metric, entry in sorted(bands.items()):
        band = entry["band"]
        limit = "<= %.4g" % band["max"] if "max" in band else ">= %.4g" % band["min"]
        value = values.get(metric)
        state = "FAIL" if any(b[0] == metric for b in bad) else "ok"
        print("%-24s %10s  band %-12s (samples %.4g +- %.2g)  %s" % (
            metric, "missing" if value is None else "%.4g" % value, limit, entry["mean"],
            entry["sd"], state))
    print("%s: %d of %d metrics outside their bands" % (args.case, len(bad), len(bands)))
    return 1 if bad else 0


def measure(args):
    cases = args.cases.split(",") if args.cases else list(CASES)
    only = set(args.metrics.split(",")) if args.metrics else None  # None: every metric
    result = load_bands() if os.path.isfile(BANDS_FILE) else {"cases": {}}
    for case in cases:
        samples = {}
        for b, dynamap in enumerate(args.dynamap):
            for start in STARTS:
                seq = prepare(case, start, args.work)
                values = run(dynamap, case, seq, os.path.join(args.work, "%s_b%d_run" % (case, b)))
                print("%s build %d start %d: %s" % (case, b, start, json.dumps(values)), flush=True)
                for metric, value in values.items():
                    samples.setdefault(metric, []).append(value)
        entries = {metric: entry_of(metric, s) for metric, s in samples.items()
                   if only is None or metric in only}
        if only is None:
            result["cases"][case] = entries
        else:  # only these metrics' bands change
            result["cases"].setdefault(case, {}).update(entries)
    commit = subprocess.run(["git", "-C", SOURCE, "describe", "--always", "--dirty"],
                            stdout=subprocess.PIPE, text=True).stdout.strip()
    result["how_measured"] = {
        "method": "each case run from start frames %s (the frames before dropped) with each of "
                  "%d builds; a metric's limit on its worse side is mean -/+ %g standard "
                  "deviations of the samples, never tighter than the worst sample; better than "
                  "the band always passes" % (STARTS, len(args.dynamap), SIGMAS),
        "builds": args.builds or ["build %d" % i for i in range(len(args.dynamap))],
        "command": "tests/real_data/bands.py measure --dynamap " + " ".join(args.dynamap) +
                   ("" if args.cases is None else " --cases " + args.cases) +
                   ("" if args.metrics is None else " --metrics " + args.metrics),
        "commit": commit,
        "date": datetime.datetime.now(datetime.timezone.utc).date().isoformat(),
        "machine": "%s, %d cores" % (cpu_model(), os.cpu_count()),
    }
    for case in cases:  # the cases not measured now keep theirs
        when = {k: result["how_measured"][k] for k in ("commit", "date", "machine", "builds")}
        if only is None:
            result.setdefault("measured_at", {})[case] = when
        else:  # the case's other metrics keep theirs
            result.setdefault("measured_at", {}).setdefault(case, {})[
                "metrics " + args.metrics] = when
    write_bands(result)
    return 0


def parse_starts(text):
    """'0-11' (a range, both ends in) or '0,3,7': the start frames of a sweep."""
    try:
        if "-" in text:
            first, last = (int(v) for v in text.split("-"))
            return list(range(first, last + 1))
        return [int(v) for v in text.split(",")]
    except ValueError:
        raise SystemExit("real_data: --starts '%s': expected A-B or A,B,C (frame numbers)" % text)


def sweep(args):
    """Each case from every start frame, one build, overrides: each run and the means."""
    cases = args.cases.split(",") if args.cases else list(CASES)
    starts = parse_starts(args.starts) if args.starts else STARTS
    for case in cases:
        runs = []
        for start in starts:
            seq = prepare(case, start, args.work)
            values = run(args.dynamap[0], case, seq, os.path.join(args.work, case + "_sweep"),
                         args.set)
            runs.append(values)
            print("%s start %d: %s" % (case, start, json.dumps(values)), flush=True)
        means = {m: statistics.fmean(r[m] for r in runs) for m in runs[0]}
        print("%s mean of %d: %s" % (case, len(runs), " ".join(
            "%s %.4g" % (m, v) for m, v in means.items())), flush=True)
    return 0


def recompute_limits():
    result = load_bands()
    for case, metrics in result["cases"].items():
        for metric, entry in metrics.items():
            metrics[metric] = entry_of(metric, entry["samples"])
    write_bands(result)
    return 0


def print_table():
    """One row a case, one column a metric: the samples' mean and the band's limit."""
    result = load_bands()
    how = result["how_measured"]
    print("Last measured %s at %s on %s: `%s` (each case's commit and date: `measured_at` in "
          "bands.json). A cell: the mean of the samples, then the limit (≤ at most, ≥ at least)."
          "\n" % (how["date"], how["commit"], how["machine"], how["command"]))
    print("| case | " + " | ".join(METRICS) + " |")
    print("|---" * (len(METRICS) + 1) + "|")
    for case, metrics in sorted(result["cases"].items()):
        cells = []
        for metric in METRICS:
            entry = metrics.get(metric)
            if entry is None:
                cells.append("")
                continue
            band = entry["band"]
            limit = "≤ %.3g" % band["max"] if "max" in band else "≥ %.3g" % band["min"]
            cells.append("%.3g %s" % (entry["mean"], limit))
        print("| %s | %s |" % (case, " | ".join(cells)))
    return 0


def write_bands(result):
    with open(BANDS_FILE, "w") as f:
        json.dump(result, f, indent=1, sort_keys=True)
        f.write("\n")
    print("wrote", BANDS_FILE)


def cpu_model():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.machine()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("command", choices=["check", "measure", "sweep", "limits", "table", "list"])
    parser.add_argument("case", nargs="?")
    parser.add_argument("--dynamap", nargs="+", default=[os.path.join(SOURCE, "build/bin/dynamap")])
    parser.add_argument("--builds", nargs="*", help="names of the --dynamap builds (measure)")
    parser.add_argument("--cases", help="comma list (measure, sweep; default all)")
    parser.add_argument("--starts", help="sweep only: start frames, A-B or A,B,C (default those "
                        "of measure: 0, 2, ..., 10)")
    parser.add_argument("--metrics", help="comma list: measure only these metrics' bands "
                        "(the others keep theirs; default all)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a configuration override for the runs (check, sweep)")
    parser.add_argument("--work", default="/tmp/dynamap_real_data")
    args = parser.parse_args()
    try:
        if args.command == "list":
            print("\n".join(CASES))
            return 0
        if args.command == "limits":
            return recompute_limits()
        if args.command == "table":
            return print_table()
        if args.command == "check":
            if args.case not in CASES:
                raise SystemExit("real_data: unknown case '%s' (known: %s)" % (args.case,
                                                                              ", ".join(CASES)))
            return check(args)
        if args.command == "sweep":
            return sweep(args)
        return measure(args)
    except DataMissing as e:
        print(e, file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
