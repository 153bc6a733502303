#!/usr/bin/python3
"""One run of each people scene, and the table of BENCHMARKS.md ("People scenes generated beside
the shared ones"): the two shared sequences and the scenes make_people.py made.

usage: people_table.py --dynamap BIN --scenes DIR [--out DIR] [--jobs N] [--set KEY=VALUE ...]

BIN runs with its own libraries (BIN/../lib, as a frozen copy of a build does). Runs go to
--out (default /tmp/people_runs/default); a run folder that holds metrics.json is read, not run
again. Prints one Markdown row per scene.
"""
import argparse, json, os, sys
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, '..', 'real_data'))
from make_people import SCENES, SHARED  # noqa: E402
from bands import run_dynamap  # noqa: E402

SHARED_SCENES = ('teddy_dyn_dev', 'teddy_dyn_crowd_dev')


def sequence(name, scenes_dir):
    if name in SHARED_SCENES:
        return os.path.join(SHARED, 'data', 'dynamic', name)
    return os.path.join(scenes_dir, name)


def run(binary, seq, out, overrides):
    if not os.path.isfile(os.path.join(out, 'metrics.json')):
        run_dynamap(binary, seq, out, overrides, extra=['--save-masks'])


def share(x):
    """A share as BENCHMARKS.md writes it: .759 (1.000 stays)."""
    text = '%.3f' % x
    return text[1:] if text.startswith('0.') else text


def row(name, metrics):
    m, k, p = metrics, metrics['masks'], metrics['map']
    tracker = m.get('tracker_masks', {}).get('mean_iou')
    label = name + (' (shared)' if name in SHARED_SCENES else '')
    return '| %s | %.2f | %s (%s) | %s | %s | %s | %s | %.2f |' % (
        label, 100 * m['ate']['rmse_m'], share(k['mean_iou']), share(tracker) if tracker else '-',
        share(k['pixel_recall']), share(k['standing_masked_share']), share(p['precision']),
        share(p['completeness']), 100 * p['ghost_ratio'])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--dynamap', required=True)
    ap.add_argument('--scenes', required=True, help='the folder make_people.py wrote to')
    ap.add_argument('--out', default='/tmp/people_runs/default')
    ap.add_argument('--jobs', type=int, default=2)
    ap.add_argument('--set', action='append', default=[])
    a = ap.parse_args()
    names = list(SHARED_SCENES) + list(SCENES)
    missing = [n for n in names if not os.path.isfile(os.path.join(sequence(n, a.scenes), 'rgb.txt'))]
    if missing:
        print('people_table.py: no sequence for %s (make them: tests/people/make_people.py %s)'
              % (', '.join(missing), a.scenes), file=sys.stderr)
        return 2
    outs = {n: os.path.join(a.out, n) for n in names}
    with ThreadPoolExecutor(a.jobs) as ex:
        list(ex.map(lambda n: run(a.dynamap, sequence(n, a.scenes), outs[n], a.set), names))
    print('| scene | ATE cm | kf mask IoU (tracker\'s) | pixel recall | standing masked | map precision | completeness | ghost % |')
    print('|---|---|---|---|---|---|---|---|')
    for n in names:
        with open(os.path.join(outs[n], 'metrics.json')) as f:
            print(row(n, json.load(f)))
    return 0


if __name__ == '__main__':
    sys.exit(main())
