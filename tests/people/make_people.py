#!/usr/bin/python3
"""People scenes beside the two shared ones: the shared scenarios with other seeds (other paths,
distances, timing; the same sprites), made with the shared generator into OUT/<name>.

usage: make_people.py OUT [NAME ...]      (default: every scene below; one that exists is kept)

Each scene takes 1.5-3 minutes on 2 cores and 60-120 MB: write them under /tmp, never into git.
Judge a change on these as well as on the shared sequences (BENCHMARKS.md, "People scenes
generated beside the shared ones").
"""
import json, os, subprocess, sys, tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.normpath(os.path.join(HERE, '../../../shared'))
TOOLS = os.path.join(SHARED, 'tools', 'dyndata')
SOURCE = os.path.join(SHARED, 'data', 'tum', 'rgbd_dataset_freiburg3_teddy')
SPRITES = os.path.join(SHARED, 'data', 'dynamic', 'sprites_dev')
SCENES = {  # name: (shared scenario, seed)
    'gen_crowd_s7': ('dev_crowd', 7007),
    'gen_walking_s7': ('dev_walking', 7008),
    'gen_crowd_s9': ('dev_crowd', 7009),
    'gen_walking_s9': ('dev_walking', 7010),
    'gen_crowd_s11': ('dev_crowd', 7011),
    'gen_crowd_s13': ('dev_crowd', 7013),
}


def make(name, out):
    scenario, seed = SCENES[name]
    with open(os.path.join(TOOLS, 'scenarios', scenario + '.json')) as f:
        spec = json.load(f)
    spec['seed'], spec['name'] = seed, name
    with tempfile.NamedTemporaryFile('w', suffix='.json', delete=False) as f:
        json.dump(spec, f, indent=1)
    try:
        subprocess.run([sys.executable, os.path.join(TOOLS, 'make_dynamic_sequence.py'), SOURCE,
                        SPRITES, f.name, out], check=True, stdout=subprocess.DEVNULL)
    finally:
        os.unlink(f.name)


def main(argv):
    if len(argv) < 2 or argv[1] in ('-h', '--help'):
        print(__doc__)
        return 0 if len(argv) >= 2 else 2
    names = argv[2:] or list(SCENES)
    unknown = [n for n in names if n not in SCENES]
    if unknown:
        print('make_people.py: unknown scene %s (known: %s)' % (', '.join(unknown), ', '.join(SCENES)),
              file=sys.stderr)
        return 2
    for name in names:
        out = os.path.join(argv[1], name)
        if os.path.isfile(os.path.join(out, 'rgb.txt')):
            print('%s: exists, kept' % out)
            continue
        make(name, out)
        print('%s: made' % out)
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
